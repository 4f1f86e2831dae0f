#pragma once
//! \file refine_mesh.h
//! \brief Incremental refinement (and coarsening) of a cut's mesh: a finer cut meshed by changing only
//! the tiles it splits, a coarser one by changing only the tiles it merges (the "any cut" issue's
//! incremental form; what mesh_cut rebuilds whole, in place).
//! \details mesh_cut builds one global manifold (the surface front, holes, the vertex fit): any change
//! of the cut rebuilds all of it, at about 1 ms per tile. refine_mesh changes only the tiles that the
//! finer cut splits. Each one's region (its fan, f:tile = the node, and the faces between tiles around
//! its vertices: the strips to its neighbours' rims) is removed, and the region's outline, kept
//! exactly, is triangulated again (constrained Delaunay in the region's mean plane) with the §4.2
//! pseudo-tile points of the node's descendants in the finer cut inside it: their hull points (input
//! points) and fan apexes, then moved along the plane's normal to fit the descendants' points in least
//! squares. Nothing beyond the outline changes, so the mesh stays a 2-manifold, a closed surface stays
//! closed with its genus, and no crack can open between refined and untouched tiles. The price, measured
//! in the README against a fresh mesh_cut of the same cut: 1.06-1.3× its mean distance on a noisy torus,
//! 1.5× on the bunny refined by two levels, 1.4-3.7× its maximum, 1.2-1.6× its faces (more where one
//! step refines a coarse curved tile many levels deep, and refinements chained over many steps drift:
//! the bunny refined in five halvings, 4× the mean distance); none of mesh_cut's repairs (holes,
//! pieces, slivers); a tile whose region, or else its fan alone, is not one disc that can be
//! re-triangulated without folding in its plane or crossing the faces around it is left
//! as it was (LocalRefineStats::kept), unless such tiles hold more than a tenth of the points that were
//! to change: then the cut asked for is meshed afresh (LocalRefineOptions::max_kept_share), as it is at
//! once for a step that replaces each tile by 16 or more (max_step_ratio). A new tile all of whose points
//! lie beyond its region's outline (in a neighbour's fan: mesh_cut cuts tiles at the cut's Voronoi cells,
//! a node's own points can reach into a neighbour's) is adopted by that neighbour, whose region is then
//! re-triangulated with both tiles' points (LocalRefineStats::adopted). For interactive refinement;
//! mesh_cut for the final mesh.

#include "libmrtile/cut.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/tiles.h"

#include <cstddef>

namespace mrt {

struct LocalRefineOptions
{
    //! A tile is re-triangulated only where every new face turns less than this from the tile's plane
    //! (degrees): a patch that is no graph over its plane would fold. Such a tile stays as it was.
    double max_tilt_degrees = 85.0;
    //! A descendant's point closer than this fraction of that descendant's point spacing to the outline
    //! or to a point already taken is left out: it would only add slivers.
    double min_separation = 0.5;
    //! Move the new vertices along the plane's normal to fit the descendants' points (least squares
    //! over the re-triangulated patch; false: they stay on the input points and fitted apexes).
    bool fit = true;
    //! Then fit the new vertices as mesh_cut's fit does (fit_vertices with `remesh.fit`'s rounds and
    //! points per vertex, vertical on a height field; no edge flips): each round relaxes them within the
    //! surface and fits them along their normals to their tiles' points, on a copy of their faces and the
    //! ring around them; only the new vertices take the result, nothing beyond the outlines moves. The
    //! per-region fit above fits along one normal and leaves the pseudo-tile points bunched along the
    //! descendants' rims. Measured (session 43): a 40k-point torus refined from tolerance 0.005 to 0.002,
    //! 1.91x the mean and 3.4x the maximum distance of a fresh mesh_cut without it, 1.21x and 1.6x with it;
    //! 0.01 to 0.005: 1.77x to 1.32x the mean, the maximum 1.14x to 0.77x; the benchmark's rows 12-25%
    //! nearer (the bunny row 0.000212 to 0.000158 of the diagonal, fresh 0.000139). New faces that then
    //! cross a face beyond the copy get their new corners put back, and every region's new faces are
    //! tested against all faces near them (as no_crossings now does in every mode; a terrain in a
    //! random run kept 3 crossing faces when only two rings were tested). Costs 3.5-7x the step's time (the
    //! bunny row 0.12 to 0.44 s), so it is off by default: interaction wants the speed, and mesh_cut of
    //! result.cut gives the fresh mesh at any time.
    bool refit = false;
    //! Test the new faces of each region against the faces of the mesh near them (those within two
    //! rings of its outline, then every face filed in a grid), and leave the region as it was (or try
    //! its fan alone) where one crosses: a region steep in its plane can fold over its surroundings
    //! (bunny, tolerance 0.01 → 0.002: 30 crossing pairs without it, none with it), or reach past the
    //! rings to a thin part's other side (until session 53 only the rings were tested without `refit`:
    //! the bunny's budget cut 200 → 400 in place kept 27 crossing pairs, QA round 67). Takes about 1.6×
    //! the time, and the grid a pass over the mesh per call.
    bool no_crossings = true;
    //! How the descendants' pseudo tiles are built (§4.2: node sample, hull, fitted apex).
    TileOptions tiles;
    //! Where the tiles left as they were (LocalRefineStats::kept) hold more than this share of the points
    //! whose tiles were to change, the cut asked for is meshed afresh instead (mesh_cut with `remesh`;
    //! LocalRefineStats::remeshed), so that the mesh is of that cut. Coarse curved tiles refined many levels
    //! at once would fold in their plane and are kept: a camera zooming in from afar (one tile) never
    //! refined, every later call keeping the same tile (QA round 49), and the bunny refined from tolerance
    //! 0.1 to 0.005 kept 8 of 8 tiles. A few kept tiles of many (the 4M torus's budget row: 5 of 986) stay,
    //! as they were. 1 or more: never mesh afresh.
    double max_kept_share = 0.1;
    //! A step that replaces each changing tile by this many tiles or more on average (or merges as many
    //! into one) meshes the cut asked for afresh instead, at once: in place, the few vertices of the coarse
    //! outlines it keeps leave long faces (QA round 49: a 40k-point torus from tolerance 0.02 to 0.0005,
    //! 49 tiles into about 1,500, kept 19 of its old vertices and had 23× the maximum distance of a fresh
    //! mesh), and a fresh mesh then costs little more. The benchmark's steps replace a tile by 5-11.
    //! Infinity: never.
    double max_step_ratio = 16.0;
    //! The options of those fresh mesh_cuts: those the mesh being changed was made with.
    MeshOptions remesh;
};

struct LocalRefineStats
{
    std::size_t refined = 0;       //!< tiles of the mesh re-triangulated with their descendants' points
    std::size_t coarsened = 0;     //!< coarsen_mesh: groups of tiles re-triangulated as their ancestor's tile
    std::size_t kept = 0;          //!< tiles the finer cut splits that were left as they were (see refine_mesh)
    //! Tiles the finer cut splits (coarsen_mesh: groups it merges) that have no face and no vertex in the
    //! mesh (mesh_cut left them out, or an earlier refinement kept none of their points): replaced in
    //! the cut with nothing to re-triangulate.
    std::size_t absent = 0;
    //! New tiles of the cut (a split node's descendants, a merge's ancestor) that had no vertex after their
    //! region was re-triangulated, their points lying in a neighbour's fan (or their region absent), and got
    //! one when that neighbour's region was re-triangulated with their points and its own.
    std::size_t adopted = 0;
    std::size_t faces_removed = 0; //!< faces of the refined tiles' regions (fans and the strips around them)
    std::size_t faces_added = 0;   //!< faces that replace them
    //! Of `kept`: tiles put back as they were after OpenMesh refused a new face (add_face returned an
    //! invalid handle). None in a random stress run over seven inputs (~3,100 tiles changed) since a
    //! triangulation that would join two outline vertices already joined outside the region is
    //! refused before any change (it made 15 refusals before).
    std::size_t refused = 0;
    //! The step was too large (LocalRefineOptions::max_step_ratio), or the in-place change kept too many
    //! tiles (max_kept_share), and the cut asked for was meshed afresh: result is mesh_cut's, `kept` 0,
    //! faces_removed / faces_added the whole old and new mesh's faces (the other counts: the in-place
    //! attempt's, 0 for a step too large).
    bool remeshed = false;
};

//! \brief Refines the mesh of a cut towards a finer cut, changing only the tiles that are split.
//! \param result a mesh_cut result (or one refine_mesh already changed): its mesh and its cut.
//! \param finer a cut at or below result.cut everywhere (refine_cut, or a cut by a smaller tolerance).
//! \details Each node of result.cut that `finer` splits is re-triangulated as the file comment says,
//! when its region (its fan, f:tile = the node, and the faces between tiles around its vertices,
//! mended where it touches itself at a vertex) is one disc whose outline and new faces do not fold in
//! the region's plane (LocalRefineOptions::max_tilt_degrees); otherwise it is left as it was and
//! counted in `kept`. result.cut becomes the cut actually meshed (the refined nodes replaced by their
//! descendants in `finer`, the kept ones staying; ordered by first point), result.tiles its size.
//! New faces: f:tile = the descendant whose points make all three corners (f:gap false), else -1
//! (f:gap true: the strips between the descendants, as mesh_cut's gap faces). New vertices: v:cluster
//! = their descendant; the split node's own vertices left on the outline go to its descendant with the
//! nearest centre, so that every vertex names a tile of the cut. Normals are recomputed; colours come
//! from the new vertex's input point (an apex: the mean of its tile's points) when the mesh has colours.
//! Cost: in proportion to the refined tiles' regions and the descendants' pseudo tiles (each built
//! from at most TileOptions::max_points of its points), plus one pass over the mesh to find the changing
//! tiles' faces and OpenMesh's garbage collection (6 tiles of a 148k-face mesh: 36 ms). Normals are
//! recomputed where faces changed only. Deterministic.
//! \throw InvalidInput if `finer` or result.cut is not a partition of the points, `finer` has nodes above
//! result.cut's, or result.mesh lacks the v:cluster / f:tile / f:gap properties (mesh.h).
LocalRefineStats refine_mesh(const Hierarchy& h, MeshResult& result, const Cut& finer,
                             const LocalRefineOptions& options = {});

//! \brief The other way (coarsen_cut's incremental mesh): the tiles of result.cut that `coarser` merges
//! into one of its nodes are replaced together by that node's tile, changing nothing else.
//! \param coarser a cut at or above result.cut everywhere (coarsen_cut, or a cut by a larger tolerance).
//! \details For each node of `coarser` that is an ancestor of several tiles of result.cut: the union of
//! their regions (fans and the strips around their vertices) must be one disc holding all their fans;
//! its outline is kept and triangulated again with the ancestor's pseudo-tile points (hull and apex),
//! heights fitted, as refine_mesh does; otherwise the tiles stay (counted in `kept`, result.cut keeps
//! them). Merged nodes' vertices left on the outline name the ancestor. Same guarantees and costs as
//! refine_mesh.
//! \throw InvalidInput as refine_mesh, or if `coarser` is finer than result.cut somewhere.
LocalRefineStats coarsen_mesh(const Hierarchy& h, MeshResult& result, const Cut& coarser,
                              const LocalRefineOptions& options = {});

//! \brief Any cut, incrementally (a camera that moved, a region given up and another refined): the
//! mesh of result.cut changed into the mesh of `cut` where they differ, by coarsen_mesh to the coarser of
//! the two cuts everywhere, then refine_mesh to the finer of that and `cut` everywhere. result.cut is
//! what was meshed: `cut`, but for tiles either step kept (stats: both steps' counts summed).
//! \throw InvalidInput as refine_mesh (any partition `cut` is accepted).
LocalRefineStats update_mesh(const Hierarchy& h, MeshResult& result, const Cut& cut, const LocalRefineOptions& options = {});

} // namespace mrt
