#pragma once
//! \file tiles.h
//! \brief Tile generation (paper §4.2): the convex hull of each cut cluster in its best-fit plane.
//! \details For a cut node the plane through its centre spanned by its two largest PCA directions is
//! the tile plane; the node's points are projected into it and the convex hull H of the projections is
//! computed. The *pseudo tile* is the polygon through the hull points at their original 3D positions.
//! Only the node's point range, moments and PCA frame are used, so a tile costs O(k log k) for a node of
//! k points and any cut of the hierarchy can be tiled.

#include "libmrtile/hierarchy.h"
#include "libmrtile/vec3.h"

#include <cstdint>
#include <vector>

namespace mrt {

struct TileOptions
{
    //! A hull point is dropped as collinear when the turn at it is at most this fraction of the squared
    //! extent of the projected cluster (scale-free; 0 keeps every point that turns at all).
    double collinear_tolerance = 1e-12;
    //! Build each tile only from the node's points that lie in the Voronoi cell of its centre among
    //! the cut's centres (exact: tested against the centre's Delaunay neighbours). A coarse node is a
    //! union of leaves and need not be convex, so the convex hull of all its points can overlap its
    //! neighbours; trimmed tiles lie in disjoint convex cells, so their fans never overlap. The
    //! trimmed-off points are still the node's (the cut stays a partition); the gap triangulation
    //! covers them.
    bool voronoi_trim = true;
};

struct Tile
{
    std::int32_t node = -1; //!< hierarchy node id
    Vec3 centre;            //!< node mean (the fan centre, paper §4.3 T1)
    Vec3 normal;            //!< unit PCA normal (frame.vectors[0]); its sign is the frame's, not outward
    Vec3 axis_u;            //!< unit in-plane axis (largest PCA direction)
    Vec3 axis_v;            //!< unit in-plane axis, cross(axis_u, axis_v) == normal
    //! Point indices (tree order) of the convex hull of the projected points, counter-clockwise seen
    //! from `normal`, collinear hull points dropped. Fewer than 3 entries when the cluster has fewer than
    //! 3 points or is collinear (the entries are then the distinct extreme points): such a tile has no fan.
    std::vector<std::uint32_t> boundary;
    double area = 0.0;        //!< area of the projected hull (tile plane units²)
    std::uint32_t points = 0; //!< number of points in the node

    bool has_fan() const { return boundary.size() >= 3; }
};

//! \brief Builds the tile of every node of `cut`, in cut order.
//! \throw InvalidInput if a cut entry is not a node id of `h` or names an empty node.
std::vector<Tile> make_tiles(const Hierarchy& h, const std::vector<std::int32_t>& cut, const TileOptions& options = {});

//! Builds one tile from the node's point range and frame (used by make_tiles; exposed for tests).
//! With `rivals`, only points nearer to the node's centre than to every rival centre are used
//! (falling back to all points if that leaves none).
Tile make_tile(const Hierarchy& h, std::int32_t node, const TileOptions& options = {},
               const std::vector<Vec3>& rivals = {});

} // namespace mrt
