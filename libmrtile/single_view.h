#pragma once
//! \file single_view.h
//! \brief Whether a cloud is one view from its viewpoint: no point lies hidden behind others along its
//! ray from there (beyond the paper).
//! \details A single range scan or depth image is a disc with holes: whatever the scene, the surface
//! the scanner saw has no handle, and build_surface refuses faces that would add one. But a viewpoint
//! does not prove a single view: PCL keeps the first cloud's sensor origin when clouds are merged or
//! registered, and a user may name a viewpoint for several scans together (QA round 35: a torus
//! sampled all round, saved with a stale VIEWPOINT, lost its handle). What tells them apart is
//! occlusion. The points' directions from the viewpoint are binned on a cube map, the cells sized for
//! about `points_per_cell` points each; in a cell, a point lies behind another layer when the depths
//! sorted jump by `min_gap_cells` cell widths (and `layer_ratio`) on the way to it (a surface seen at a
//! grazing angle spreads its depths within a cell, but without such a gap), and it hides behind a
//! surface when that nearer layer lies all round its direction (at a silhouette it lies on one side,
//! and the point beside it was seen past the edge). In one view next to nothing hides; a closed object
//! seen all round hides half its points, a merge of scans every object's shadow. Deterministic;
//! linear in the points sampled.

#include "libmrtile/vec3.h"

#include <cstddef>
#include <vector>

namespace mrt {

struct SingleViewOptions
{
    //! Points per occupied direction cell, on average: sets the cells' angular size.
    double points_per_cell = 8.0;
    //! Behind another layer: farther from the viewpoint than the cell's nearer layer by this factor
    //! (1: any factor; a larger one misses every object far from the viewpoint, whose depth is a small
    //! fraction of its distance: QA round 39's torus merged from views 27 m away hid nothing at 1.1)...
    double layer_ratio = 1.0;
    //! ...and by this many cell widths at that depth (noise and mixed pixels stay within a few).
    double min_gap_cells = 8.0;
    //! One view when at most this share of the points sampled hide behind a surface. Single views hide
    //! 0-0.5% (noisy ones with mixed pixels at every silhouette up to 1.04%), merges 2% (a sparse scan
    //! of a torus's back) to 51% (QA round 39's cases): a cloud judged one view loses its handles, one
    //! judged merged meshes as without a viewpoint.
    double max_hidden_share = 0.015;
    //! Points looked at, at most (every k-th point of the cloud, in order: deterministic).
    std::size_t max_samples = 262144;
};

struct SingleViewStats
{
    std::size_t sampled = 0; //!< points looked at
    std::size_t hidden = 0;  //!< of them, behind another layer of their cell
    double hidden_share = 0.0;
    bool single_view = false; //!< hidden_share ≤ max_hidden_share (and some points sampled)
};

//! \brief Measures how many points hide behind others as seen from `viewpoint` (both in one frame).
//! Points at the viewpoint itself are left out. An empty cloud is no single view.
//! \throw InvalidInput if an option is out of range (points_per_cell < 1, layer_ratio < 1, a negative
//! gap or share, max_samples 0) or a position or the viewpoint is not finite.
SingleViewStats single_view_stats(const std::vector<Vec3>& points, const Vec3& viewpoint, const SingleViewOptions& options = {});

} // namespace mrt
