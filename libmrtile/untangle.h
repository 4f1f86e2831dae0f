#pragma once
//! \file untangle.h
//! \brief Removes geometric self-intersections from a manifold mesh by small local edits.
//! \details Beyond the paper: the surface stage (surface.h) guarantees a combinatorial 2-manifold, not
//! an embedded one. Where the sample is thinner than a tile (the bunny's ear tips, a thin rim), a gap
//! face chosen on one side can pass through a fan on the other: a few faces in ten thousand, invisible
//! in a viewer, fatal for a 3D printer, a boolean or a volume. Each face of an intersecting pair is
//! offered, in turn, a flip of each of its edges, then moves of its corners and then of their
//! neighbours (toward the centre of their neighbours, or across the surface), then a collapse of
//! each of its edges either way (OpenMesh's is_collapse_ok: no change of topology); the first edit that
//! lowers the number of intersections of the faces it changes, without turning a face by more than
//! max_turn_degrees or moving a vertex by more than `max_move` of its shortest edge, is kept. Topology
//! does not change (flips and collapses are OpenMesh's is_flip_ok and is_collapse_ok ones), except that a gap face on the border still
//! overlapping another face at the end is removed (UntangleOptions::remove_border_folds). A tip folded
//! over itself around one vertex, which no flip or move unfolds, is collapsed; what is left
//! (out of budget or tries) pairs_after counts.

#include "libmrtile/mesh.h"

#include <cstddef>
#include <utility>
#include <vector>

namespace mrt {

struct UntangleOptions
{
    //! Rounds over the faces still intersecting (each round re-finds the pairs).
    int max_rounds = 6;
    //! Largest move of a vertex, as a fraction of its shortest edge.
    double max_move = 0.75;
    //! Largest turn of a face's normal an edit may cause (a flip: of either new face against the old pair).
    double max_turn_degrees = 60.0;
    //! Work bound: at most this many triangle-pair tests per face of the mesh, in all, but at least
    //! 400,000 (and each face is tried at most twice). A clean surface's few crossings take far less (the bunny: under 2 per face);
    //! a crumpled one (noise meshed below its floor, thousands of crossings) stops here instead of
    //! taking a minute. 10 stopped a 1M-point fandisk's 735 pairs at 207 (40: 11, as 200 did), in the
    //! same time.
    double tests_per_face = 40.0;
    //! Last, a gap face (f:gap) on the mesh's border that still overlaps another face is removed when
    //! that keeps the mesh a manifold (one border edge, its third corner inside): the hole beside it
    //! grows by that face. In flat parts with holes a fill beside a hole can fold over a neighbouring
    //! face in the plane, where no flip or move helps. Meshes without f:gap keep every face.
    bool remove_border_folds = true;
    //! Height fields: every face an edit changes must still face up `axis` (the mesh stays a graph).
    bool vertical = false;
    Vec3 axis{0, 0, 1};
};

struct UntangleStats
{
    std::size_t pairs_before = 0; //!< intersecting face pairs found first
    std::size_t pairs_after = 0;  //!< left at the end (0 on success)
    std::size_t flips = 0;
    std::size_t moves = 0;
    std::size_t collapses = 0; //!< edges collapsed (a fold around one vertex), the vertex removed
    std::size_t tests = 0; //!< triangle pairs tested (see UntangleOptions::tests_per_face)
    std::size_t removed_faces = 0; //!< border gap faces removed (UntangleOptions::remove_border_folds)
};

//! \throw InvalidInput unless max_rounds >= 0, max_move >= 0 and finite, max_turn_degrees in [0, 180],
//! tests_per_face in [0, 1e9] and, with `vertical`, the axis is non-zero (untangle and mesh_cut check it
//! first, whether or not the mesh crosses itself).
void check_untangle_options(const UntangleOptions& options);

//! \brief Lowers the self-intersections of `mesh` (self_intersecting_faces in mesh_stats.h) by local
//! edge flips and vertex moves. Deterministic. A flip across two tiles marks both faces as gap faces
//! (f:tile -1, f:gap true), as fit_vertices does. Vertex and face normals of changed faces are updated.
//! \throw InvalidInput if the mesh is not a manifold triangle mesh, or as check_untangle_options.
UntangleStats untangle(Mesh& mesh, const UntangleOptions& options = {});

//! The same, from the mesh's intersecting pairs as self_intersecting_faces gives them (a caller that
//! has just found them, such as fit_vertices (FitStats::intersecting_pairs), spares the test of the whole mesh).
//! \throw InvalidInput if a pair does not name two distinct faces of the mesh.
UntangleStats untangle(Mesh& mesh, const UntangleOptions& options, std::vector<std::pair<int, int>> pairs);

} // namespace mrt
