#pragma once
//! \file tiles.h
//! \brief Tile generation (paper §4.2): the convex hull of each cut cluster in its best-fit plane.
//! \details For a cut node the plane through its centre spanned by its two largest PCA directions is
//! the tile plane; the tile's points are projected into it and the convex hull H of the projections is
//! computed. The *pseudo tile* is the polygon through the hull points at their original 3D positions.
//! The tile's points are those of the node's Voronoi cell among the cut's centres (TileOptions::
//! voronoi_trim, default) or the node's own. A cut of N points costs O(N log N) in all.

#include "libmrtile/hierarchy.h"
#include "libmrtile/vec3.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace mrt {

//! TileOptions::meet_factor for thin walls (`mrtile --thin-walls`): cells whose points come within 4 point
//! spacings of each other meet; the sides of walls about 3 spacings thick and more are told apart.
inline constexpr double kThinWallMeetFactor = 4.0;

//! TileOptions::max_points' default, and the size above which a node's hull is stored (set_node_hulls):
//! the nodes whose tiles are built from a sample of their points, and need their hull for their outline.
inline constexpr std::size_t kHullStoredAbove = 256;

struct TileOptions
{
    //! A hull point is dropped as collinear when the turn at it is at most this fraction of the squared
    //! extent of the projected cluster (scale-free; 0 keeps every point that turns at all).
    double collinear_tolerance = 1e-12;
    //! Build the tiles from the Voronoi partition of the points by the cut's centres: every point goes
    //! to the tile of its nearest centre (found exactly by a greedy walk on the centres' Delaunay graph
    //! from its own node's centre). A coarse node is a union of leaves and need not be convex, so the
    //! convex hulls of the nodes themselves can overlap; Voronoi cells are disjoint and convex, so the
    //! fans never overlap, and since every point is in some cell the gaps between tiles stay about one
    //! point spacing wide. Also finds which tiles meet on the surface (Tile::neighbours).
    //! false: each tile is the hull of exactly its node's points (the paper's literal tiles).
    bool voronoi_trim = true;
    //! Two tiles are neighbours on the surface when some point of one lies within adjacency_factor ×
    //! the larger of their point spacings of the bisector plane of the two centres (the sampled surface
    //! comes that close to their Voronoi face).
    double adjacency_factor = 1.5;
    //! Thin walls (opt-in; `mrtile --thin-walls` sets kThinWallMeetFactor): two tiles facing the same
    //! way within 30 degrees (either way round) are neighbours only if, moreover, a point of one cell
    //! within that reach of the bisector comes within meet_factor × the larger spacing of some point of
    //! the other cell: the surface runs from one cell into the other. Where the two sides of a thin wall
    //! face each other, the bisector of an outer and an inner centre set apart along the wall crosses
    //! both sides, so both cells have points at it, each on its own side, a wall's thickness apart, and
    //! the bisector test alone makes them neighbours across the wall. Off by default: where a plate's
    //! rim is not sampled (a CAD part's vertices), coarse tiles of its two sides meet only across the rim,
    //! and the test leaves the rim open (README: Choices, thin walls). 0 = off.
    double meet_factor = 0.0;
    //! Place the fan apex at the height (along the normal) that fits the fan to the tile's points in
    //! least squares; false: the mean height of the points near the centre (on the surface).
    bool fit_apex = true;
    //! Build each tile from at most about this many of its node's points (every k-th point of the node's
    //! range, which the tree keeps spatially coherent) plus the node's own hull points (found in one
    //! cheap pass: only points outside the octagon of the extremes are sorted), so that the costly part
    //! of a cut (the Voronoi walk of every point) scales with its tiles, not with the points under them,
    //! while tiles at open borders still reach the sample's border. 0 = every point (the paper's tiles).
    //! Fewer interior points leave gaps between tiles as wide as the sample's spacing; the gap
    //! triangulation fills them, and coarse cuts spend fewer faces for the same error (after the vertex
    //! fit). Far smaller samples (~64) leave gaps wide enough to close real holes or add handles.
    std::size_t max_points = kHullStoredAbove;
    //! Measure Tile::coverage_gap of every tile; with voronoi_trim, a tile whose cell's hull covers a
    //! hole is built from its own node's points of the cell only (see Tile::coverage_gap).
    bool measure_gaps = true;
    //! Nonzero: every tile's plane is normal to this axis instead of its PCA plane, so that its hull
    //! is taken in the plane the surface is a graph over (height-field mode, set by mesh_cut). A tile
    //! of a roof edge with some wall points has a PCA plane tilted toward the wall; its hull in that
    //! plane, mapped back to the points' heights, folds over itself seen from above.
    Vec3 plane_axis{0, 0, 0};
};

struct Tile
{
    std::int32_t node = -1; //!< hierarchy node id
    //! Node mean (paper §4.3 T1's fan centre; used for all tile geometry); where strays far off were
    //! left out of the tile (tiles.cpp: drop_strays), the mean of the rest, with the plane fitted to them.
    Vec3 centre;
    //! Where the fan's centre vertex is placed: `centre` moved along the normal to the height that fits
    //! the fan to the tile's points in least squares (TileOptions::fit_apex; otherwise the mean height
    //! of the points near the centre). The mean of a curved patch lies below it by about two thirds of
    //! its sag, and a fan whose apex is on the surface is a cone under a dome; the fitted apex sits
    //! above the surface and halves the mean distance or better on curved tiles. Equal to `centre` on
    //! flat tiles.
    Vec3 apex;
    Vec3 normal;            //!< unit PCA normal (frame.vectors[0]); its sign is the frame's, not outward
    Vec3 axis_u;            //!< unit in-plane axis (largest PCA direction)
    Vec3 axis_v;            //!< unit in-plane axis, cross(axis_u, axis_v) == normal
    //! Point indices (tree order) of the convex hull of the projected points, counter-clockwise seen
    //! from `normal`, collinear hull points dropped. Fewer than 3 entries when the cluster has fewer than
    //! 3 points or is collinear (the entries are then the distinct extreme points): such a tile has no fan.
    std::vector<std::uint32_t> boundary;
    double area = 0.0;        //!< area of the projected hull (tile plane units²)
    std::uint32_t points = 0; //!< number of points the tile was built from (its Voronoi cell's, or its node's)
    //! Of those, how many lie apart in the tile plane: points within a hundredth of the mean spacing of
    //! each other (clumps of near-equal points, such as repeated frames of one view) count once. 0
    //! without a fan.
    std::uint32_t distinct_points = 0;
    //! Indices (into the tile vector, ascending) of the tiles that meet this one on the sampled surface:
    //! the restricted Delaunay neighbours found from the points (voronoi_trim only; else empty).
    std::vector<std::uint32_t> neighbours;
    //! How far the tile's outline reaches over surface none of its points sample (coverage_gap.h, from
    //! the points it was built from; model units; 0 without TileOptions::measure_gaps). A Voronoi cell
    //! can take in points across a hole from a neighbouring node, and its hull then covers the hole:
    //! such a tile is built from its own node's points in the cell instead, and this is the gap left
    //! after that. It can still exceed the node's own Node::coverage_gap (the node's hull is judged
    //! with a sample of its points); mesh_cut refines such tiles (MeshOptions::gap_rounds).
    double coverage_gap = 0.0;

    //! Mean point spacing sqrt(area / distinct_points) (0 without a fan). Counting clumped points as
    //! one keeps the spacing of the surface's sampling, which gap widths and split lengths follow.
    double spacing() const
    {
        const std::uint32_t n = distinct_points > 0 ? distinct_points : points;
        return n > 0 && area > 0.0 ? std::sqrt(area / n) : 0.0;
    }
    //! No fan although the hull has three points or more: a steep tile in height-field mode (a wall of
    //! a few points between a roof and the ground), whose points join the gap triangulation instead.
    bool fanless = false;
    bool has_fan() const { return !fanless && boundary.size() >= 3; }
};

//! \throw InvalidInput unless collinear_tolerance is finite and >= 0, adjacency_factor and meet_factor >= 0
//! and plane_axis finite (make_tiles, make_tile and refine_mesh check it first).
void check_tile_options(const TileOptions& options);

//! \brief Builds the tile of every node of `cut`, in cut order.
//! \throw InvalidInput if a cut entry is not a node id of `h` or names an empty node.
std::vector<Tile> make_tiles(const Hierarchy& h, const std::vector<std::int32_t>& cut, const TileOptions& options = {});

//! \brief The same with the cut entries marked in `fanless` built as fanless tiles without points
//! (Tile::fanless, empty boundary), left out of the others' partition: the walls of a height field
//! (mesh_cut), whose few points would otherwise join the roof's and the ground's cells and pull
//! their fans up and down across the step, which the gap triangulation bridges instead.
//! \throw InvalidInput as make_tiles, or if `fanless` is not one flag per cut entry.
std::vector<Tile> make_tiles(const Hierarchy& h, const std::vector<std::int32_t>& cut, const TileOptions& options,
                             const std::vector<bool>& fanless);

//! \brief The convex hull of all of the node's points in its PCA plane: tree-order point indices,
//! ascending (collinear hull points dropped; 1 or 2 points for a degenerate node).
//! \details Read from Hierarchy::hull_points where set_node_hulls stored it, otherwise computed in one
//! pass of dot products over the node's points (only the points outside the octagon of the extremes
//! along 8 directions are sorted: Akl and Toussaint).
std::vector<std::uint32_t> node_hull(const Hierarchy& h, std::int32_t node);

//! \brief The hull (node_hull) of every node of more than kHullStoredAbove points, as
//! Hierarchy::hull_start and hull_points hold them (`threads` 0 = one per hardware thread; the result
//! does not depend on it). A pass over every point per level of the tree (0.25 s CPU per million
//! points): save_model does it, so that cuts of a loaded model read a large node's points only where
//! its tile needs them; a hierarchy just built and cut once does not need it (a cut's nodes are one
//! pass over the points).
void compute_node_hulls(const Hierarchy& h, std::vector<std::size_t>& start, std::vector<std::uint32_t>& points,
                        std::size_t threads = 0);

//! \brief compute_node_hulls into `h` itself: for a hierarchy kept in memory and cut many times
//! (refine_mesh), as loading a model gives.
void set_node_hulls(Hierarchy& h, std::size_t threads = 0);

//! Builds one tile from all of the node's points and its frame (no Voronoi partition; for tests).
//! \throw InvalidInput as check_tile_options, or if `node` is not a node of `h`.
Tile make_tile(const Hierarchy& h, std::int32_t node, const TileOptions& options = {});

} // namespace mrt
