#pragma once
//! \file sample_dimension.h
//! \brief Whether a cloud samples a surface at all: its local dimension, from how fast the distance to
//! the k-th nearest point grows with k (beyond the paper).
//! \details Around a point of a surface the points within r grow as r², in a volume as r³, along a
//! curve as r: with d(k) the distance to the k-th nearest point, the dimension is
//! log(far / near) / log(d(far) / d(near)), about 2 on a surface and 3 in a volume. The method meshes
//! surfaces; points that fill a volume (random points in a box, a cloud of vegetation, noise many point
//! spacings deep) have none, and meshing them spends minutes on a mesh of no use (a million random
//! points: 236 s, 26,192 crossing pairs). It is measured at a scale large against the point spacing, so
//! that noise of a few spacings on a surface stays a surface: on every k-th point of the cloud (at most
//! `max_points` of them), with `near` and `far` neighbours among those, far being about 1/64 of them.
//! Measured (near 128, far 2048): clean and noisy scans 2.0-2.2 (the bunny 2.06, Igea 2.02, the
//! rocker arm 2.20; a sphere with noise of 4 point spacings 2.38, a slab 15 spacings thick 2.40),
//! random points in a cube 2.84. Deterministic; the cost is `samples` neighbour searches.
//!
//! \code
//!   const mrt::SampleDimension d = mrt::sample_dimension(cloud.positions);
//!   if (d.fills_volume) { /* no surface to mesh */ }
//! \endcode

#include "libmrtile/vec3.h"

#include <cstddef>
#include <vector>

namespace mrt {

struct DimensionOptions
{
    //! Neighbours counted for the inner distance d(near).
    std::size_t near = 32;
    //! Neighbours counted for the outer distance d(far); a cloud (after thinning) needs 8 × far points
    //! for a measure (fewer points mesh in seconds whatever they are).
    std::size_t far = 512;
    //! The cloud is thinned to every k-th point, at most this many (the scale of the measure is then a
    //! share of the cloud, whatever its size).
    std::size_t max_points = 32768;
    //! Points whose dimension is measured (evenly through the thinned cloud).
    std::size_t samples = 512;
    //! A mean dimension at or above this fills a volume (surfaces measure up to about 2.4, volumes
    //! about 2.8).
    double volume_dimension = 2.6;
};

struct SampleDimension
{
    std::size_t sampled = 0;     //!< points whose dimension was measured (0: too few points to tell)
    double mean_dimension = 0.0; //!< their mean local dimension (0 when none)
    bool fills_volume = false;   //!< mean_dimension ≥ volume_dimension
};

//! \brief The mean local dimension of the points (see the file comment) and whether they fill a volume.
//! \throw InvalidInput if an option is out of range (near < 2, far ≤ near, samples or max_points 0,
//! volume_dimension not finite) or a position is not finite.
SampleDimension sample_dimension(const std::vector<Vec3>& positions, const DimensionOptions& options = {});

} // namespace mrt
