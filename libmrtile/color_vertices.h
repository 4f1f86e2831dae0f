#pragma once
//! \file color_vertices.h
//! \brief Beyond the paper: the input's point colours carried onto the mesh's vertices.
//! \details Scanners and photogrammetry deliver coloured points, and a mesh for a renderer should keep
//! the colour. Each point (every k-th, as the fit samples them) lends its colour to the three corners
//! of its closest face, weighted by its barycentric coordinates there, so a vertex averages the points
//! around it (scan noise in the colours is smoothed the way the positions are) and a coarse cut's large
//! faces still get the colours of the points they stand for. A vertex no point lends to (a rare corner
//! of a fan with no point near it) takes the mean of its coloured neighbours.
//! \code
//!   MeshResult r = mesh_cut(h, cut);               // mesh_cut runs it when h.cloud has colours
//!   color_vertices(r.mesh, h.cloud, ColorOptions{}); // or on any mesh of the same points
//!   // r.mesh.has_vertex_colors(); writers put them in PLY (red green blue alpha) and glTF (COLOR_0)
//! \endcode

#include "libmrtile/mesh.h"
#include "libmrtile/point_cloud.h"

#include <cstddef>

namespace mrt {

struct ColorOptions
{
    //! Colour the vertices when the points have colours (mesh_cut; false = leave the mesh uncoloured).
    bool enabled = true;
    //! Use at most about this many points per vertex (every k-th point): a vertex's colour averages a
    //! few dozen points at most; a fine sample under a coarse mesh would cost time for nothing. 0 = every
    //! point.
    std::size_t points_per_vertex = 16;
    //! Threads for the closest-face queries (0 = one per hardware thread); the result does not depend on it.
    std::size_t threads = 0;
};

//! \brief Gives every vertex of `mesh` a colour from the colours of `cloud` (see the file comment) and
//! requests the mesh's vertex colour property. The mesh must be in the cloud's coordinates (positions
//! relative to its origin, as mesh_cut makes them). Deterministic. Returns the number of points used;
//! 0 (and the mesh left as it is) when the cloud has no colours, the mesh no face, or !options.enabled.
//! \throw InvalidInput if the cloud has colours but not one per point.
std::size_t color_vertices(Mesh& mesh, const PointCloud& cloud, const ColorOptions& options = {});

} // namespace mrt
