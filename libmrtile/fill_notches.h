#pragma once
//! \file fill_notches.h
//! \brief Notches in a mesh's open border that the sample covers are filled (beyond the paper).
//! \details Where two tiles meet at the sample's outline, the gap triangulation's face across their
//! hulls' ends is long and flat, and alpha pruning drops it: the border runs inward to a hull point and
//! out again, a notch as deep as a fraction of the tiles' width. At coarse cuts of a terrain the notches
//! were 10 m deep on a 2 km survey whose tiles claimed 0.86 m (QA round 38), and tilesets cut side by
//! side showed gaps along their shared borders. A notch is two consecutive edges a -> c -> b of a
//! piece's outline (its longest border loop; the others are holes, which hole filling judges whole)
//! whose triangle (a, c, b) lies outside the surface, turned like the faces beside it; it is filled
//! when it is deep (c lies more than `min_depth_spacings` point spacings from the line a-b), opens wide
//! (`min_angle_degrees` at c), crosses no face, and the input points cover it in one layer (every spot
//! of the triangle has a point within `cover_spacings` spacings, near its plane, and few points lie
//! over it a little off the plane). The face is a gap face (f:tile -1, f:gap true). Deterministic.

#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>

namespace mrt {

struct NotchOptions
{
    //! Only notches deeper than this many point spacings are filled (shallower ones lie within the
    //! tiles' own error, and filling them would only add faces).
    double min_depth_spacings = 3.0;
    //! The input points must cover the notch: every spot of its triangle has a point within this many
    //! spacings, at most that far from the triangle's plane.
    double cover_spacings = 1.5;
    //! The notch opens at least this wide at its inner vertex (degrees): a narrower inlet's triangle is
    //! a sliver reaching into the surface, which a later local refinement (refine_mesh) folded near.
    double min_angle_degrees = 60.0;
    //! The new face turns at most this much from each face it joins (degrees): a notch lies in the
    //! surface's continuation, a convex corner's triangle folds back over the surface.
    double max_turn_degrees = 30.0;
    //! Passes over the borders: a filled notch can leave a new one beside it.
    int rounds = 4;
};

//! \brief Fills the notches of `mesh`'s borders that the points of `h` cover; returns the faces added.
//! `spacing_of` gives the point spacing of the tile each vertex names (v:cluster → spacing; vertices
//! whose cluster is missing or spaced 0 start no notch); the depth is judged by the smaller of it and
//! the spacing of the node's own points (from their spread in its plane), since a tile's hull area over
//! its node's points overstates it where the tile's cell spans larger neighbours' points.
//! \throw InvalidInput for options out of range (negative or NaN spacings, a turn outside (0, 90], an
//! angle outside [0, 180), rounds outside [0, 64]) or a mesh without the v:cluster / f:tile / f:gap properties.
std::size_t fill_notches(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
                         const NotchOptions& options = {});

} // namespace mrt
