#pragma once
//! \file remove_slivers.h
//! \brief Beyond the paper: caps and needles (faces without width) removed by edge flips and short-edge
//! collapses, last, so that shading shows the surface and not the seams between tiles.
//! \details Gap strips (§4.3) join two tile rims that run side by side, often with the vertices of one
//! rim a hair off an edge of the other: the strip then holds "caps", faces with an angle near 180
//! degrees, whose normals point anywhere. Flat shading draws them as dark cracks and smooth shading
//! smears them over their vertices' normals (a sphere's cut at tolerance 0.002 had 5% caps, the bunny's
//! 12%). A cap's long edge is flipped when the other diagonal of its quad is better (smaller largest
//! angle) and the quad is nearly flat; that leaves a needle where four vertices were in a row, and a
//! needle's short edge is collapsed into one of its ends. Neither moves the surface by more than a sliver's
//! width. Every operation keeps the mesh an oriented 2-manifold with the same boundary loops and
//! genus (OpenMesh's is_flip_ok / is_collapse_ok; border vertices are never collapsed) and refuses to
//! turn any face by more than `max_turn_degrees`.
//! \code
//!   Mesh m = mesh_cut(h, cut).mesh;           // mesh_cut runs it before the fit (MeshOptions::slivers)
//!   SliverOptions o;
//!   o.cap_angle_degrees = 170;                // only the worst caps
//!   SliverStats s = remove_slivers(m, o);
//! \endcode

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <cstddef>

namespace mrt {

struct SliverOptions
{
    //! A face with an angle above this (degrees) is a cap. 180 = off (no flips, no collapses).
    double cap_angle_degrees = 150.0;
    //! A face whose shortest edge is under this fraction of its longest is a needle (0 = no collapses).
    double needle_ratio = 0.0;
    //! No flip or collapse turns a face's normal by more than this (degrees), nor makes a flipped face
    //! turn from its quad's vertex normals by more: the cleanup never folds the surface.
    double max_turn_degrees = 45.0;
    //! A flip moves the surface by the cap's apex's distance from the plane of the face across the long
    //! edge: at most this fraction of the long edge (on a flat or smoothly curved surface a thin cap's
    //! apex lies almost in that plane; a fatter cap on a coarse mesh, or one across a crease, may not).
    double max_flip_height = 0.05;
    //! Keep a height field a graph over the plane normal to `axis`: every face changed must face up it
    //! (mesh_cut sets both in height-field mode, as for the fit).
    bool vertical = false;
    Vec3 axis{0, 0, 1};
    //! Passes over the mesh (each flips and collapses what it finds; the work ends earlier when a pass
    //! changes nothing).
    int passes = 4;
};

struct SliverStats
{
    std::size_t caps_before = 0;    //!< caps and needles found before the first pass
    std::size_t needles_before = 0;
    std::size_t flips = 0;          //!< edges flipped
    std::size_t collapses = 0;      //!< edges collapsed (one vertex and two faces each)
    std::size_t caps_after = 0;     //!< caps and needles left
    std::size_t needles_after = 0;
};

//! Faces with an angle above `cap_angle_degrees` (the cleanup's measure, for quality reports).
std::size_t count_caps(const Mesh& mesh, double cap_angle_degrees = 150.0);

//! \throw InvalidInput if an option is out of range (what remove_slivers checks first).
void check_sliver_options(const SliverOptions& options);

//! \brief Flips and collapses away the caps and needles of `mesh` (see the file comment). Deterministic.
//! Deleted elements are garbage-collected, so handles taken before the call are invalid afterwards;
//! the mesh properties (mesh.h) follow their elements. Updates face and vertex normals.
//! \throw InvalidInput if an option is out of range.
SliverStats remove_slivers(Mesh& mesh, const SliverOptions& options = {});

} // namespace mrt
