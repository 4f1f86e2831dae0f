#pragma once
//! \file reconstruct.h
//! \brief The one-call pipeline from a cut to a measured mesh: tiles (§4.2), surface (§4.3), quality.
//! \details
//! \code
//!   Hierarchy h = build_hierarchy(read_points("scan.ply"));          // §4.1, once
//!   Cut cut = cut_by_tolerance(h, 0.002);                             // any cut (cut.h)
//!   MeshResult r = mesh_cut(h, cut);                                  // §4.2-4.3 → OpenMesh
//!   QualityReport q = measure_quality(h, r.cut, r.mesh);              // numbers users can trust
//! \endcode

#include "libmrtile/close_covered_holes.h"
#include "libmrtile/color_vertices.h"
#include "libmrtile/cut.h"
#include "libmrtile/fill_notches.h"
#include "libmrtile/fit_vertices.h"
#include "libmrtile/mesh.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/refine_fans.h"
#include "libmrtile/remove_bridges.h"
#include "libmrtile/remove_folds.h"
#include "libmrtile/remove_slivers.h"
#include "libmrtile/surface.h"
#include "libmrtile/tiles.h"
#include "libmrtile/untangle.h"

#include <functional>

namespace mrt {

//! The most rounds of each of MeshOptions' refinements (small objects, gaps, dropped tiles, pieces):
//! each round can cost a meshing, and every refinement converges in a few.
inline constexpr int kMaxRefineRounds = 64;

struct MeshOptions
{
    TileOptions tiles;       //!< tile generation (§4.2)
    SurfaceOptions surface;  //!< gap triangulation and manifold assembly (§4.3)
    FanRefineOptions refine; //!< interior vertices where a fan deviates from its tile (refine_fans.h)
    //! vertex positions fitted to the points, each round after a relaxation (fit_vertices.h); vertical
    //! in height-field mode
    FitOptions fit;
    //! caps flipped away before the fit (remove_slivers.h); vertical in height-field mode
    SliverOptions slivers;
    //! folded edges (spikes and flaps at sharp edges) flipped away after the fit, never adding a
    //! crossing (remove_folds.h); vertical in height-field mode; fold_angle_degrees 180 = off
    FoldOptions folds;
    //! self-intersections removed by local flips and moves, after the fit (untangle.h); max_rounds 0 = off
    UntangleOptions untangle;
    //! the points' colours onto the vertices, last, when the cloud has colours (color_vertices.h)
    ColorOptions colors;
    //! notches of open borders that the points cover filled, before the slivers (fill_notches.h);
    //! rounds 0 = off
    NotchOptions notches;
    //! small holes that the points cover closed by a fan around a vertex on the sample, after the
    //! notches (close_covered_holes.h); max_edges 0 = off; vertical in height-field mode
    CoveredHoleOptions covered_holes;
    //! tubes of long gap faces across empty space, joining two surfaces that face each other a few
    //! spacings apart, cut and their loops capped, first after the surface (remove_bridges.h; not
    //! on a height field, one layer over its plane); max_loop_edges 0 = off
    BridgeOptions bridges;
    //! A separate object that the cut gives one or two tiles cannot close (two hemisphere fans are a
    //! flat pillow) and the surface drops it. Tiles in a piece of the tile adjacency (Tile::neighbours)
    //! of at most three tiles, while other pieces exist, are refined (replaced by their children) up to
    //! this many times before meshing (0 = mesh the cut as given). 50 unit spheres 5 apart at
    //! tolerance 0.01 (two tiles each): 33 were dropped; now all are closed.
    int small_object_rounds = 3;
    //! A tile whose outline reaches over a hole of the sample farther than its node's geometric error
    //! (Tile::coverage_gap > node_error, cut.h) is refined too, up to this many times (0 = never): its
    //! Voronoi cell took in points across the hole, or the cut kept it although its gap is larger than
    //! its node's error. A flat plate with holes 12 and 20 spacings wide: both covered by one tile each;
    //! now open.
    int gap_rounds = 6;
    //! A face of the surface over a hole of the sample that no tile's own gap saw (a spot of it with no
    //! point within the larger of its tiles' node_error and 4 of their point spacings: a hole between
    //! tiles, their hulls and the gap triangles across it within the local alpha radius) has its
    //! corners' tiles refined and the cut meshed again, up to this many times (0 = never); a round is
    //! kept only when less of the surface lies over holes, with no more pieces and no more fans left
    //! out. A sphere with a hole 11 spacings wide at tolerance 0.01: covered, the mesh 0.13 from every
    //! point over it; now open. Costs a test of the faces longer than half their reach, and a meshing
    //! per round only where such faces exist.
    int hole_rounds = 3;
    //! A tile whose fan the surface left out while its points lie away from the mesh (their median
    //! distance over 3 of its spacings: surface the mesh does not have, not a fan its neighbours' gap
    //! faces cover) is refined and the cut meshed again, up to this many times (0 = never; leaves are
    //! never refined). The two bunny scans of bun.conf at tolerance 0.01: a 388-point strip at the base
    //! was left out, 10% of the diagonal from the mesh; now within 2.8%. Costs a meshing per round, only
    //! when such a tile exists. A round whose surface crosses itself more than the one before
    //! (self_intersecting_faces, before the fit) is undone and ends the rounds: refined tiles can fold
    //! into their neighbours where the untangling cannot undo it. Points of tiles still away are not
    //! fitted to.
    int dropped_rounds = 3;
    //! A mesh in several pieces with open borders (a closed thin part at a coarse cut, its tiles
    //! straddling it: the rocker arm at tolerance 0.02 was 11 pieces with 12 loops) has the tiles on
    //! its boundary loops refined and is meshed again, up to this many times (0 = never); a round is
    //! kept only when it leaves fewer pieces and no more loops. So does a height field in one piece
    //! whose loops inside its outline run along tiles their neighbours surround (slits), kept with fewer
    //! loops and no more pieces. Costs a meshing per round, only for meshes with such loops.
    int piece_rounds = 3;
    //! The same for a surface in 3D in one piece whose loops run along tiles their neighbours surround:
    //! cracks where coarse tiles straddle an acute edge of a closed solid (a tetrahedron at tolerance
    //! 0.01: 8-10 slits along its edges; 3 rounds: 8 -> 0). Loops the caps from the points close (on a
    //! copy of the surface) are left to them. A crack lies over sampled surface, so a
    //! loop whose faces at its corners span a hole of the sample (spots 6 spacings from every point)
    //! is a hole's rim and left; a round is kept only with fewer loops, no more pieces, no higher
    //! genus, no more fans left out, at most 5% more crossing pairs in the surface (their count moves
    //! by a few percent with any change of the cut), no more of the mesh over the loops' tiles
    //! farther than 3 spacings from the points (else it is tried once more without the loops that
    //! did so) nor among the faces it changed anywhere, and no point of a regular sample farther from
    //! the mesh by a spacing. 0 = never.
    int crack_rounds = 3;
    //! Beyond the paper: where the finished mesh (after the fit and the untangling) is one piece and
    //! still crosses itself, the tiles of the crossing faces that are not leaves are refined and the cut
    //! meshed and finished again, up to this many times (coarse tiles straddling an acute edge fan from
    //! inside the solid: a tetrahedron at tolerance 0.01 kept 379 crossing pairs, none with the rounds).
    //! A round is kept only when its mesh crosses itself less and is one piece with no more loops, no
    //! higher genus, no more fans left out (or no more points in tiles away from it), no more of it
    //! over the sample's holes and no point of a regular sample farther from it by a spacing. A round
    //! tried costs a meshing, kept or not; a mesh without crossings costs nothing. 0 = never.
    int crossing_rounds = 2;
    //! mesh_mended only: where its mesh is still in pieces that the sample joins after its finer cuts,
    //! the cut kept is meshed again with thin walls (TileOptions::meet_factor = kThinWallMeetFactor, when
    //! it is 0) and that mesh is kept on the finer cuts' terms: fewer pieces, no more boundary loops, no
    //! points left out that the first kept. The two sides of a wall a few spacings thick, joined and torn
    //! apart by the surface, are such pieces (a sphere shell 3 spacings thick: 109 pieces, 110 loops ->
    //! one piece, 14 loops). false = never.
    bool thin_walls_when_in_pieces = true;
};

struct MeshResult
{
    Mesh mesh;
    SurfaceStats surface;
    //! The cut meshed: the cut given (in point order, whatever order it was given in), with the tiles
    //! of small separate objects refined (MeshOptions::small_object_rounds). Pass it to measure_quality.
    Cut cut;
    std::size_t tiles = 0;
    std::size_t refined_points = 0; //!< points inserted into fans (refine_fans)
    std::size_t notches = 0;        //!< faces filling notches of open borders (fill_notches)
    CoveredHoleStats covered_holes; //!< small covered holes closed (close_covered_holes)
    BridgeStats bridges;            //!< tubes across empty space cut (remove_bridges)
    //! Tiles meshed in all: the cut's, and the refined cut's again in each round that remeshed it
    //! (MeshOptions::piece_rounds, dropped_rounds). The surface costs about the same per tile, so this
    //! is the meshing's work, counted the same on every machine.
    std::size_t meshed_tiles = 0;
    FitStats fit;                   //!< the vertex fit (fit_vertices)
    SliverStats slivers;            //!< caps and needles removed (remove_slivers)
    FoldStats folds;                //!< folded edges flipped away after the fit (remove_folds)
    UntangleStats untangle;         //!< self-intersections removed (untangle)
    double seconds = 0.0; //!< tiles + surface + slivers + fit (with its relaxation) + colours
};

//! \brief What mesh_cut checks of its options before any work: the rounds, and the options of the tiles,
//! the surface, the fit (its relaxation too), the slivers' removal and the untangling. \throw InvalidInput
//! naming the first option out of range.
void check_mesh_options(const MeshOptions& options);

//! Tiles the cut and meshes it. \throw InvalidInput if the cut is not a partition of the points, or as
//! check_mesh_options.
MeshResult mesh_cut(const Hierarchy& h, const Cut& cut, const MeshOptions& options = {});

struct TriangleCountResult
{
    Cut cut;            //!< a best-N cut (cut_by_budget)
    MeshResult result;  //!< its mesh
    std::size_t meshings = 0; //!< candidate cuts meshed to find it
    TopologyStats asked;         //!< the topology of the best fitting cut's mesh (when one fits)
    bool smaller_budget = false; //!< a smaller budget was kept: the best fitting cut was in pieces
    bool in_pieces = false;      //!< whether the mesh kept is in pieces that its sample joins
};

//! \brief The finest best-N cut (cut_by_budget) whose mesh has at most `triangles` faces, and its mesh.
//! \details A cut's face count is known only once it is meshed (tiles differ in size and rim), so this
//! meshes a few candidate cuts: a guess from the faces per tile seen so far, then bisection on N between
//! the largest N known to fit and the smallest known not to, up to `max_meshings` (default 10), and
//! stops once a fitting cut's mesh has 99% of `triangles` faces or more (finer cuts would add under 1%). The
//! face count grows with N almost always, not strictly; the result is the best fitting cut found. When
//! even one tile has more faces, that one-tile mesh is returned; when the leaves fit, the leaves'.
//! Where the best fitting cut's mesh is in pieces that its sample joins (see mesh_mended), the budgets
//! 0.95, 0.9, 0.85 and 0.8 × N are meshed too (one of them only, past one no better, for cuts over 1,000
//! tiles), and one is kept on mesh_mended's terms: fewer pieces, no more loops, no fewer points kept.
//! \throw InvalidInput if triangles == 0 or max_meshings == 0.
TriangleCountResult mesh_to_triangle_count(const Hierarchy& h, std::size_t triangles, const MeshOptions& options = {},
                                           std::size_t max_meshings = 10);

struct MendedMeshResult
{
    MeshResult result;   //!< the mesh kept
    int steps = 0;       //!< finer cuts kept (0: the cut asked was not in pieces, or no finer one was better)
    TopologyStats asked; //!< the topology of the mesh of the cut asked
    bool in_pieces = false; //!< whether the mesh kept is still in pieces that the sample joins
    //! whether the mesh kept was meshed with thin walls (MeshOptions::thin_walls_when_in_pieces)
    bool thin_walls = false;
};

//! \brief Meshes cut_at(0), and where its mesh is in pieces that its sample is not, the finer cuts
//! cut_at(1), cut_at(2), ... (beyond the paper).
//! \details A coarse cut can mesh in pieces at thin or sharply curved parts (the bunny at tolerance
//! 0.025: both ear tips loose; the rocker arm at 0.017: 4 pieces). mesh_cut mends what refining the
//! tiles on their loops mends (MeshOptions::piece_rounds); where pieces are left that hold tiles that
//! are neighbours on the surface (Tile::neighbours: the sample runs from one to the other), cut_at(k)
//! is meshed for k = 1 .. mend_steps while the best so far is in pieces (past one that is no better
//! only while the cuts have at most 1,000 tiles), and kept when it has fewer pieces and no more boundary
//! loops than that best, and leaves out no more points (those of tiles without a vertex in the mesh). Tiles are joined when their points come within 3 point spacings.
//! Where the best is still in pieces after that, its cut is meshed once more with thin walls
//! (MeshOptions::thin_walls_when_in_pieces) and kept on the same terms (MendedMeshResult::thin_walls).
//! cut_at(k) should be finer with k and meet whatever cut_at(0) was asked to meet (a tolerance / √2^k,
//! a camera's pixel error / √2^k). Separate objects and a scan's separate fragments are no such pieces
//! and cost nothing more. \throw InvalidInput as mesh_cut, or mend_steps outside [0, 8].
MendedMeshResult mesh_mended(const Hierarchy& h, const std::function<Cut(int)>& cut_at, const MeshOptions& options = {},
                             int mend_steps = 3);

//! mesh_mended over cut_by_tolerance(h, tolerance / √2^k): the tolerance cut kept has tolerance
//! tolerance / √2^steps, which meets the tolerance asked too. \throw InvalidInput as mesh_mended and
//! cut_by_tolerance.
MendedMeshResult mesh_at_tolerance(const Hierarchy& h, double tolerance, const MeshOptions& options = {},
                                   int mend_steps = 3);

struct QualityReport
{
    TopologyStats topology;
    //! Paper eq. 4-6: mean distance of each point to the plane of its tile, divided by the object
    //! diameter (the bounding box's largest side, as the paper's 0.1557 for the bunny is).
    double e_rms = 0.0;
    //! Distances from every input point to the mesh, as fractions of the bounding-box diagonal (the
    //! points read: Hierarchy::raw_positions after a denoised build; a loaded denoised model has only
    //! its moved points, and the distances are to them).
    //! Its `far`: points farther than 5% of the diagonal and twice the cut's largest node_error.
    DistanceStats point_to_mesh;
    //! The other way: from the mesh (its vertices and face centroids) to the closest input point, as
    //! fractions of the same diagonal. The point-to-mesh distance cannot see a spike or a flap that
    //! sticks out where there are no points; this can (its max is the mesh's half of the Hausdorff distance).
    DistanceStats mesh_to_points;
    //! Pairs of faces that intersect geometrically (self_intersecting_faces); 0 for a clean surface.
    std::size_t self_intersections = 0;
    //! Faces with an angle above 150 degrees (count_caps): their normals are noise, which shading shows.
    std::size_t caps = 0;
    //! Points in tiles of the cut that lie along curves, not over surface, and that the mesh does not
    //! join into one: most of the tile's points see their 8 nearest neighbours spread along a line
    //! (width, the root of the middle eigenvalue, under kLineWidthRatio of length), and three quarters
    //! or more of the tile's vertices in the mesh lie on its border. Such tiles are ribbons along the
    //! curve the points follow (a wire, a single scan line). Stretches of scan lines joined side by
    //! side (a sphere sampled as latitude rings) are surface and do not count.
    std::size_t line_points = 0;
    std::size_t points = 0; //!< in the tiles of the cut (every point of the model: a cut covers them all)
    //! Boundary loops that run along a sharp edge: four fifths of their vertices have, within three
    //! loop edge lengths, a loop vertex (themselves included) with a face whose normal is more than
    //! kSharpLoopDegrees from one of their own (the two sides of a slit along an edge of 70 degrees or
    //! less). Acute edges are where closed solids are left open (README: Known limits); a scan's own
    //! border or a hole in a smooth stretch turns far less within that reach.
    std::size_t sharp_loops = 0;
};

//! See QualityReport::line_points.
inline constexpr double kLineWidthRatio = 0.1;
//! See QualityReport::sharp_loops: the normals of the two faces of an edge of 70 degrees are 110 apart.
inline constexpr double kSharpLoopDegrees = 110.0;

//! The number of boundary loops of `mesh` whose faces turn more than `degrees` across them, judged
//! locally as QualityReport::sharp_loops says.
std::size_t count_sharp_loops(const Mesh& mesh, double degrees = kSharpLoopDegrees);

//! Per node of `h`: whether a vertex of `mesh` names it (kVertexCluster), i.e. its tile shows in the
//! mesh; every node when no vertex names any (a mesh without the property). The surface leaves out
//! tiles of strays far off, which the hierarchy puts in clusters of their own.
std::vector<char> nodes_in_mesh(const Hierarchy& h, const Mesh& mesh);

//! How measure_quality picks the points its point_to_mesh distances count far.
struct QualityOptions
{
    //! One flag per point of `h` (in the order of QualityReport::point_to_mesh's points): the points to
    //! count far, in place of the bound QualityReport::point_to_mesh names; null = that bound. Levels
    //! of one chain are compared over the same points so (`mrtile lods`).
    const std::vector<char>* far_points = nullptr;
    //! When not null, set to one flag per point: 1 for the points counted far.
    std::vector<char>* far_points_found = nullptr;
};

//! \throw InvalidInput if `cut` is not a partition of the points, a vertex of `mesh` is not finite,
//! `mesh` has no faces (no distance to it exists; mesh_cut never returns such a mesh), or
//! `options.far_points` does not have one flag per point.
QualityReport measure_quality(const Hierarchy& h, const Cut& cut, const Mesh& mesh, const QualityOptions& options = {});

//! Paper eq. 4-6 for a cut (see QualityReport::e_rms). \throw InvalidInput if `cut` is not a partition.
double e_rms(const Hierarchy& h, const Cut& cut);

} // namespace mrt
