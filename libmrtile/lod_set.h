#pragma once
//! \file lod_set.h
//! \brief Streamed level-of-detail sets: global levels whose error halves per level, and a 3D Tiles
//! tile tree over them (chosen here; formats/write_3d_tiles.h only serialises it).
//! \details
//! Levels: level 0 is the tolerance cut at the tolerance of the best cut that fits one tile
//! (cut_by_budget; the tolerance cut is no finer, and the levels' tolerance cuts nest; the cuts meshed,
//! LodLevel::cut, nearly: mesh_cut's small-object and dropped-fan rounds can refine a few nodes of a
//! level below the next level's cut; and an automatic level with a hole where the finest level has
//! none, between tiles that straddle a thin part, has the nodes around it refined to the next level's,
//! so that its cut is then finer there than its tolerance asks), each next level halves the
//! scale-free tolerance, the last is the hierarchy's leaves. Each level is meshed *globally* (one
//! manifold surface per level), so tiles of one level cut from it share their border vertices exactly.
//! Tiles: a tile is a hierarchy node (its region) at a level. Its content is the level's faces owned
//! by the cut nodes inside the region. Its children are the largest regions below it whose content at
//! the next level fits `max_tile_triangles` (REPLACE refinement: the children together cover exactly
//! the parent's points). Where a tile meets a tile of another level (a neighbour not yet refined, of
//! any level), borders differ: each level gives the faces across a border to one side or the other.
//! So a tile also holds the faces around its vertices that its neighbours own (LodTile::overlap_faces:
//! both levels' faces across the border overlap it), and carries a skirt (a strip hanging from the
//! borders of all that along the surface normal) as deep as twice the larger of its level's plane
//! distances and the errors, where the border is, of every coarser level a viewer can show across it
//! (from the first level at which the tile's ancestor no longer holds the neighbour's points).
//! Geometric error of a level = the largest node_error (cut.h: distance of a point to its tile plane,
//! or the tile's coverage gap) over the level's cut (model units), forced non-increasing with the
//! level. A tile's = the largest node_error of the level's cut nodes in its region, never above its
//! level's (a smooth region refines later than a rough one of the same level), and a parent's raised
//! to its children's (errors fall down the tree; a child is not lowered to understate what it shows);
//! the finest level's tiles get 0, and a tile whose error is 0 at a coarser level has no children (a
//! client never refines it). Errors, plane distances and boxes count only the cut nodes that the
//! level's mesh shows (a vertex names them): stray points the surface leaves out set none of them.
//! In make_lod_tiles (with or without the tile tree), node errors are floored by what the mesh shows:
//! a cut node's error is at least how far its vertices lie from the nearest sample point beyond two
//! point spacings (node_spacing), and a level's error at least its largest (raised level by level
//! from the finest, so errors still fall): a coarse level whose fitted vertices stand off the sample
//! is not shown from where that is plain (QA round 57: a corridor's 12-face root, 2.87 m off, had
//! error 1.0 m; now 2.64).
//! Strays far off that the finest level does not show (birds over a terrain) set no error: a level's
//! error is how far it can differ from the finest level, so in make_lod_tiles a point farther than two
//! spacings from the finest mesh counts in its node's plane distance only as that less its distance to
//! the finest mesh (checked only in the tail of a node's plane distances: a clean sample keeps its
//! errors bit for bit), a coverage gap that is the space between a node's children, one of which no
//! finest tile shows, is not carried up, and the vertices standing for such nodes (or for nodes of
//! fewer than 16 points that the finest level does not show) floor their node's error by their
//! distance to the finest surface (0 across a hole of it).
//! A tile's box is that of its content and its descendants' (the region's when it has none).

#include "libmrtile/cut.h"
#include "libmrtile/reconstruct.h"

#include <cstddef>
#include <functional>
#include <vector>

namespace mrt {


struct LodSetOptions
{
    //! Largest number of triangles in one tile (skirts included). Exceeded only by a tile whose region
    //! cannot be split at its level (a leaf, or a node whose children lie below the level's cut) and by
    //! a root whose level 0 cannot be made as small (a level's faces of one cut node stay together).
    std::size_t max_tile_triangles = 65536;
    //! Triangles of level 0 (when no tolerances are given); 0 = max_tile_triangles. Level 0 is cut to
    //! three quarters of it, since a tileset's root must fit one tile (skirts included): with `tileset`,
    //! more than max_tile_triangles is an InvalidInput. A plain LOD chain (`mrtile lods`) starts coarser.
    std::size_t first_level_triangles = 0;
    //! Number of levels; 0 = halve the tolerance until the cut reaches the hierarchy's leaves (at most
    //! max_levels), leaving out a level whose next finer one has less than 1.5× its tiles (a step
    //! that adds a few tiles costs a whole mesh and shows nothing new), level 0 included: where the
    //! finest mesh fits level 0's budget it is the one level.
    std::size_t levels = 0;
    //! The most levels `levels = 0` makes (each halves the tolerance: 2^-16 of level 0's is below any
    //! scan's noise); an explicit `levels` may ask for more.
    std::size_t max_levels = 16;
    //! Explicit scale-free tolerances, coarse to fine (overrides levels). With either, a level whose
    //! cut is no finer than the one before is left out (below the build's tolerance every cut is the
    //! leaves): the result's `levels.size()` can be less than asked, and a caller that promised a
    //! number of levels compares it (the CLI prints a note).
    std::vector<double> tolerances;
    //! Build the 3D Tiles tile tree (false: levels only, for `mrtile lods`).
    bool tileset = true;
    //! Add skirts and overlaps to tiles (3D Tiles only).
    bool skirts = true;
    //! How every level is meshed (mesh_cut's options; defaults as there).
    MeshOptions mesh;
    //! Levels are meshed in parallel on this many threads (0 = one per hardware thread). The result
    //! does not depend on it: every level is meshed on its own, deterministically.
    std::size_t threads = 0;
    //! Called once per level when its mesh is done (levels done so far, levels in all), from the thread
    //! that meshed it, one call at a time. A 1M-point set takes a minute: tools show where it is.
    std::function<void(std::size_t done, std::size_t total)> progress;
};

struct LodLevel
{
    double tolerance = 0.0;       //!< scale-free tolerance of the level's cut
    Cut cut;
    Mesh mesh;                    //!< the whole level, one manifold surface
    double geometric_error = 0.0; //!< model units (see file comment)
    double max_plane_distance = 0.0; //!< raw largest point-to-tile-plane distance over the cut
    //! SurfaceStats::looks_airborne of its meshing (false for a level read from a model).
    bool looks_airborne = false;
};

struct LodTile
{
    std::int32_t region = 0;      //!< hierarchy node whose points the tile covers
    std::size_t level = 0;
    Mesh mesh;                    //!< content (may be empty for a region with no faces)
    BoundingBox box;              //!< contains the content and every descendant's box
    double geometric_error = 0.0;
    std::vector<std::size_t> children;
    std::size_t skirt_faces = 0;  //!< of the content's faces, those of its skirts: the last ones
    std::size_t overlap_faces = 0; //!< of the content's faces, those owned by neighbours (see the file comment)
};

struct LodSet
{
    std::vector<LodLevel> levels;
    std::vector<LodTile> tiles; //!< tiles[0] is the root; empty when options.tileset is false
};

//! Grows every tile's box to contain its children's (3D Tiles: a child's bounding volume lies inside
//! its parent's), bottom-up; a tile's children come after it in `tiles`.
void nest_tile_boxes(std::vector<LodTile>& tiles);

//! \brief The levels and, with options.tileset, the tile tree over them: make_lod_tiles(h,
//! make_lod_levels(h, options), options).
//! \throw InvalidInput for options out of range (max_tile_triangles < 64, tolerances not decreasing).
LodSet make_lod_set(const Hierarchy& h, const LodSetOptions& options = {});

//! \brief The meshed levels alone, coarse to fine: the expensive part of a LOD set (a minute for 1M
//! points), which a model file can store (model_file.h, StoredLevels) so that later exports only cut
//! tiles. Uses every option but `tileset`, `skirts` and (past level 0's size) `max_tile_triangles`.
std::vector<LodLevel> make_lod_levels(const Hierarchy& h, const LodSetOptions& options = {});

//! \brief A LOD set over levels made by make_lod_levels for the same hierarchy (e.g. loaded with the
//! model): the tile tree when options.tileset (cheap: it cuts the level meshes, it meshes nothing).
//! The caller vouches that `levels` belong to `h`. \throw InvalidInput for no levels, bad options, a
//! level's cut that is no partition of h, or levels not coarse to fine (each tolerance below the one
//! before, no geometric error above it).
LodSet make_lod_tiles(const Hierarchy& h, std::vector<LodLevel> levels, const LodSetOptions& options = {});

} // namespace mrt
