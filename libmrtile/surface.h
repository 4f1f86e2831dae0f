#pragma once
//! \file surface.h
//! \brief Reconstruction (paper §4.3, Algorithm 2), extended to always give a valid 2-manifold.
//! \details T1: every tile with a fan is triangulated from its centre (a new vertex at the node mean) to
//! its pseudo-tile boundary. T2: tile boundary edges longer than ε are split, the boundary points are
//! Delaunay-triangulated (locally in each tile's plane with its surface neighbours when the tiles know
//! them, 2D on the projection plane for height fields, else 3D), and triangles with all vertices in one
//! tile, with an edge crossing a tile (a chord), between tiles that do not meet on the surface, or not
//! fitting in a sphere of the local alpha radius b are removed. Beyond the paper, the remaining
//! triangles are only *candidates*: an advancing front seeded by the consistently oriented T1 fans
//! accepts them one at a time (best-shaped first) only if the surface stays an oriented 2-manifold,
//! gaps left between tiles are filled, and the sample's own borders stay open. See surface.cpp.
//! The result is always a valid oriented 2-manifold; its *topology* is right when neighbouring tiles do
//! not overlap (make_tiles' default Voronoi partition) and the sampling is dense next to the tiles.
//! Properties on the mesh (names in mesh.h): "f:tile", "f:gap", "v:cluster"; vertex normals.

#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"
#include "libmrtile/single_view.h"
#include "libmrtile/tiles.h"

#include <cstddef>
#include <optional>
#include <vector>

namespace mrt {

enum class HeightField
{
    Auto, //!< use 2D Delaunay when the tiles form a graph over a plane (see SurfaceOptions::max_tilt_degrees)
    On,   //!< always project onto the plane across the dominant tile normal direction
    Off,  //!< always 3D Delaunay
};

//! Largest SurfaceOptions::close_holes accepted.
inline constexpr std::size_t kMaxCloseHoles = 2000;

struct SurfaceOptions
{
    //! Functional-data mode (paper §4.3, 2D Delaunay on a projection). Auto switches it on when every
    //! tile normal is within max_tilt_degrees of the dominant normal axis and no tile's projected centre
    //! lies inside another tile's projected outline (the tiles do not overlap along the axis).
    HeightField height_field = HeightField::Auto;
    //! Largest angle between a tile normal and the axis for Auto to choose height-field mode.
    double max_tilt_degrees = 65.0;
    //! Height-field mode: true = triangulate continuously across jumps (paper Fig. 9c); false = keep
    //! discontinuities open (Fig. 9b) by rejecting gap triangles with an edge rising more than step_height.
    bool bridge_steps = true;
    //! Largest rise along the axis of a gap edge when bridge_steps is false; 0 = the local alpha radius b.
    double step_height = 0.0;
    //! Global alpha (model units). 0 = automatic: alpha_factor × the mean tile boundary edge length.
    //! The local radius b of a gap triangle is alpha × (largest mean boundary edge length of its tiles /
    //! the global mean), so it follows the local tile size.
    double alpha = 0.0;
    //! Factor of the automatic alpha.
    double alpha_factor = 2.5;
    //! ε: boundary edges longer than this are split (model units). 0 = automatic: split_factor × the
    //! tile's point spacing sqrt(area / points). Negative: never split.
    double split_length = 0.0;
    //! Factor of the automatic ε.
    double split_factor = 2.0;
    //! Largest turn between a new gap triangle and an existing neighbour across an edge (folds beyond it
    //! are rejected).
    double max_turn_degrees = 120.0;
    //! Fill holes left between tiles (the small ones also before the front may close handles, so that
    //! a handle face cannot join two neighbouring gaps).
    bool fill_holes = true;
    //! A hole is filled when its perimeter is at most hole_factor × the largest perimeter of the tiles
    //! on its loop (and it touches at least two tiles and has at most max_hole_edges edges); larger loops
    //! are the sample's borders and stay open.
    double hole_factor = 1.0;
    //! Largest number of edges of a hole that is filled (its minimum-area triangulation is cubic in
    //! them). 300 left a rocker arm at 0.02 capped over its through-hole (genus 0) and at 0.015 with
    //! a 397-edge crack, and a cone's 63° rim with a 190-edge slit at 0.005 (whose widened loop grew past 300).
    std::size_t max_hole_edges = 500;
    //! Beyond the gaps between tiles: after everything else, fill every hole left with at most this many
    //! edges, the sample's own holes too (a scan's unseen base; the outline of an open scan as well, if
    //! it has no more edges), for watertight output (3D printing, volumes, simulation). 0 = off (the
    //! default: such holes are where the sample ends, and a fill there is made up). Filled by the same
    //! triangulation as the gaps, where a manifold patch fits and does not cut through the surface
    //! (SurfaceStats::closings_refused: a single view's outline, whose surface bulges inside it); at most
    //! kMaxCloseHoles (the minimum-area fill is cubic in a hole's edges: 2,000 edges take about a second).
    std::size_t close_holes = 0;
    //! A tile is interior (not on the sample's border) when, seen from its centre in its own plane or
    //! in a neighbour's, its surface neighbours (Tile::neighbours) and theirs leave no empty angular
    //! sector wider than this, or its neighbours form a closed ring around it. A hole whose loop touches only interior tiles is
    //! filled whatever its size (up to max_hole_edges).
    double interior_gap_degrees = 170.0;
    //! A hole whose mean width (2 area / perimeter of its fill) exceeds this many point spacings of its
    //! tiles (Tile::spacing) is a hole in the sample, not a gap between tiles, and stays open (every
    //! point lies in some tile, so gaps are about one spacing wide). 0 = no limit.
    double max_gap_width = 4.0;
    //! After assembly, collapse the ε-split points that carry no shape into their loop neighbours (the
    //! fans stay exactly as they were; gap faces re-attach; topology unchanged). Fewer faces, same error.
    //! On the mesh's border every collapse (of these and of the two passes below) keeps the border
    //! within a point spacing of its tile of where it was: of the points it removes and of every border
    //! point removed before on the edges it changes, and the new border near the old.
    bool collapse_split_points = true;
    //! With collapse_split_points, loop points that are input points are collapsed too when the surface
    //! moves by at most this × their tile's RMS plane distance, in three passes that halve it (so at most
    //! 1.75 × this in all; 0 = split points only). A gap face may turn freely but not fold.
    double collapse_tolerance = 0.5;
    //! With collapse_split_points, then merge the rim points across the strips of gap faces between
    //! tiles (an edge with a gap face on both sides joining two rim points collapses, shortest first)
    //! when the surface moves by at most this × the tile's RMS plane distance, in three halving passes
    //! (0 = off). A strip is about one point spacing wide and costs two faces per rim point for almost no
    //! shape: merging it spends those faces where the vertex fit (fit_vertices.h) can use them.
    double strip_tolerance = 2.0;
    //! Threads for the tiles' local Delaunay triangulations (0 = one per hardware thread). The result
    //! does not depend on it.
    std::size_t threads = 0;
};

struct SurfaceStats
{
    std::size_t tiles = 0;           //!< tiles given
    std::size_t fan_tiles = 0;       //!< tiles with a fan (>= 3 hull points)
    std::size_t boundary_points = 0; //!< points in the gap triangulation, split points included
    std::size_t split_points = 0;    //!< points inserted on long boundary edges
    std::size_t candidates = 0;      //!< Delaunay triangles left after pruning
    std::size_t fan_faces = 0;       //!< T1 faces in the mesh
    std::size_t gap_faces = 0;       //!< T2 faces in the mesh (hole fills included)
    std::size_t refused_faces = 0;   //!< faces OpenMesh's add_face refused (should be 0)
    std::size_t holes_filled = 0;
    std::size_t hole_faces = 0;      //!< faces added by hole filling (part of gap_faces)
    //! With close_holes: holes left open because their cap would cut through the surface (the border
    //! of a single view is no hole: the surface bulges inside it).
    std::size_t closings_refused = 0;
    std::size_t boundary_loops = 0;  //!< boundary loops left open
    std::size_t split_vertices = 0;  //!< pinched vertices duplicated to keep the mesh manifold
    std::size_t collapsed_split_points = 0; //!< loop points (ε-split, then rim) removed after assembly
    std::size_t components = 0;
    //! Tiles whose fan ended up alone while their neighbours' surface closed over them (left out).
    std::size_t dropped_fans = 0;
    //! Islands put back because the rest of the surface did not cover their place (a separate piece of
    //! the sample beside a larger one); their fans are also counted in dropped_fans.
    std::size_t restored_islands = 0;
    bool height_field_used = false;
    Vec3 height_field_axis{0, 0, 1}; //!< the "up" the height field is a graph over (when used)
    //! Meshed in 3D by HeightField::Auto for want of a CRS, although the tiles would pass as an
    //! airborne scan's (ground and roofs facing up z, walls left out): HeightField::On may fit better.
    bool looks_airborne = false;
    double alpha = 0.0;              //!< global alpha used (model units)
    //! With a viewpoint: how many points hide behind others from it (single_view.h); where none to
    //! speak of, the cloud is one view (view->single_view) and no face added a handle.
    std::optional<SingleViewStats> view;
    double seconds = 0.0;
};

//! The height-field decision build_surface makes for these tiles (SurfaceOptions::height_field): whether
//! the surface is meshed as a graph over the plane normal to `axis`, and which tiles are steeper than
//! max_tilt_degrees there (walls: they get no fan, and the gap triangulation bridges across them).
//! Auto requires that no tile's centre lies inside another's outline seen along the axis (no
//! overhangs) and no tile is steep, but in a georeferenced cloud facing up (an airborne scan), where
//! steep tiles holding at most a tenth of the points are walls and centres within two spacings of an
//! outline's edge pass. mesh_cut asks it first, and builds a height field with walls in its plane
//! (TileOptions::plane_axis, make_tiles with the walls fanless).
struct HeightFieldChoice
{
    bool used = false;
    Vec3 axis{0, 0, 1};
    std::vector<bool> steep; //!< per tile, when used
};

HeightFieldChoice choose_height_field(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options);

//! Per tile, whether its surface neighbours (Tile::neighbours) surround it, leaving no empty angular
//! sector wider than options.interior_gap_degrees: not on the sample's border. Hole filling fills the
//! holes among such tiles (they are gaps between tiles, not the sample's own holes).
std::vector<bool> surrounded_tiles(const std::vector<Tile>& tiles, const SurfaceOptions& options = {});

//! \brief Checks the options build_surface takes (mesh_cut too, before any work).
//! \throw InvalidInput naming the option and its allowed range: a negative or NaN length or factor,
//! height_field none of the enum's values, max_tilt_degrees outside (0, 90] (a tile normal's angle to
//! the axis), max_turn_degrees outside (0, 180] (a turn across an edge), interior_gap_degrees outside
//! (0, 360] (a sector seen from a tile's centre), close_holes above kMaxCloseHoles.
void check_surface_options(const SurfaceOptions& options);

//! \brief Meshes the tiles of a cut (from make_tiles) into an oriented 2-manifold.
//! \details Deterministic. Closed components are oriented outward (positive signed volume); open ones
//! face h.cloud.viewpoint when it is set (the scanner's position: a scan's mesh faces its scanner,
//! summed over the component's area), otherwise along the axis in height-field mode, otherwise to
//! positive signed volume.
//! \throw InvalidInput if there are no tiles, a tile does not belong to `h`, or an option is out of range.
Mesh build_surface(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options = {},
                   SurfaceStats* stats = nullptr);

//! \brief The same, built into `mesh`, which must be empty: for a caller that keeps the mesh in a
//! struct (an OpenMesh mesh has no move constructor, so assigning a returned one copies it).
void build_surface(const Hierarchy& h, const std::vector<Tile>& tiles, Mesh& mesh, const SurfaceOptions& options = {},
                   SurfaceStats* stats = nullptr);

} // namespace mrt
