#pragma once
//! \file sample_dimension.h
//! \brief Whether a cloud samples a surface at all, or fills a volume: its local dimension at a large
//! scale and the flatness of its leaves at the smallest (beyond the paper).
//! \details The method meshes surfaces; points that fill a volume (random points in a box, a cloud of
//! vegetation) have none, and meshing them spends minutes on a mesh of no use (a million random points:
//! 236 s, 1,640 pieces, 26,192 crossing pairs). Two measures, because each alone mistakes a surface:
//!  - The dimension: around a point of a surface the points within r grow as r², in a volume as r³,
//!    along a curve as r; with d(k) the distance to the k-th nearest point it is
//!    log(far / near) / log(d(far) / d(near)). Measured on every k-th point in the hierarchy's order
//!    (at most `max_points`; spatially even, where every k-th point of a grid read row by row can be one
//!    plane of it), so that `far` is about 1/64 of them: large against the point spacing, so that
//!    noise of a few spacings is still a surface (a sphere with noise of 4 spacings: 2.24-2.38), small
//!    against the object, so that curvature does not count (the shared scans 1.99-2.19). Random points
//!    measure 2.8-3.1, but so do surfaces stacked closer than that scale: nested spheres, a rolled or
//!    crumpled sheet, the pages of a book (QA round 76: 2.64-2.87).
//!  - The leaves' roughness: sqrt(λ0 / λ1) of the input points of each leaf of the hierarchy (16-32
//!    points), the median over the leaves. A surface, stacked or not, is flat at that scale (0.00-0.02);
//!    a volume is not (0.57-0.68), nor is a noisy surface (0.55-0.67), which the dimension tells apart.
//! A cloud fills a volume when both say so. Deterministic; the dimension costs about 0.03 s whatever the
//! size (`samples` neighbour searches); the roughness reads the leaves' frames (one eigen-decomposition
//! per leaf of the raw positions where denoising moved the points: about 0.05 s per million points).
//!
//! \code
//!   const mrt::Hierarchy h = mrt::build_hierarchy(std::move(cloud));
//!   if (mrt::sample_dimension(h).fills_volume) { /* no surface to mesh */ }
//! \endcode

#include "libmrtile/hierarchy.h"

#include <cstddef>

namespace mrt {

struct DimensionOptions
{
    //! Neighbours counted for the inner distance d(near).
    std::size_t near = 32;
    //! Neighbours counted for the outer distance d(far); the cloud (after thinning) needs 8 × far points
    //! for a measure (fewer points mesh in seconds whatever they are).
    std::size_t far = 512;
    //! The cloud is thinned to every k-th point, at most this many (the scale of the measure is then a
    //! share of the cloud, whatever its size).
    std::size_t max_points = 32768;
    //! Points whose dimension is measured (evenly through the thinned cloud).
    std::size_t samples = 512;
    //! A mean dimension at or above this is a volume's (surfaces measure up to about 2.4 unless stacked,
    //! volumes about 2.8).
    double volume_dimension = 2.6;
    //! A median leaf roughness at or above this is a volume's (or noise's); surfaces measure about 0.02.
    double volume_roughness = 0.4;
};

struct SampleDimension
{
    std::size_t sampled = 0;     //!< points whose dimension was measured (0: too few points to tell)
    double mean_dimension = 0.0; //!< their mean local dimension (0 when none)
    double leaf_roughness = 0.0; //!< median over the leaves of at least 8 points (0 when none)
    //! mean_dimension ≥ volume_dimension and leaf_roughness ≥ volume_roughness.
    bool fills_volume = false;
};

//! \brief Both measures (see the file comment) of the points of `h` as they were read (raw_positions
//! when denoised, else cloud.positions), and whether they fill a volume.
//! \throw InvalidInput if an option is out of range (near < 2, far ≤ near, samples or max_points 0, a
//! threshold not finite).
SampleDimension sample_dimension(const Hierarchy& h, const DimensionOptions& options = {});

} // namespace mrt
