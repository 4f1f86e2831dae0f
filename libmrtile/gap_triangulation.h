#pragma once
//! \file gap_triangulation.h
//! \brief The Delaunay step of the gap triangulation (paper §4.3, Algorithm 2): all Delaunay
//! triangles of the tile boundary points, in 3D, or in 2D on a projection plane for functional data.
//! \details This is the one file that includes CGAL's triangulations (and gives their convex hull and
//! a polygon's constrained triangulation). The pruning of the triangles
//! (one-tile triangles, local alpha radius) and the manifold extraction live in surface_front.cpp and
//! surface_holes.cpp (build_surface, in surface.cpp, runs them).

#include "libmrtile/vec3.h"

#include <array>
#include <cstdint>
#include <vector>

namespace mrt {

struct DelaunayOptions
{
    //! false: 3D Delaunay tetrahedralisation, every finite facet is a triangle. true: 2D Delaunay
    //! triangulation of the points projected onto the plane spanned by `axis_u`, `axis_v`.
    bool projected = false;
    Vec3 axis_u{1, 0, 0}; //!< first projection axis (projected mode only)
    Vec3 axis_v{0, 1, 0}; //!< second projection axis (projected mode only)
};

struct DelaunayTriangles
{
    //! Triangles as point indices, each sorted ascending; the list is sorted and has no repeats.
    std::vector<std::array<std::uint32_t, 3>> triangles;
    //! representative[i] = i, or the index of an earlier point at the same (projected) position,
    //! which Delaunay keeps in its place; such duplicates appear in no triangle.
    std::vector<std::uint32_t> representative;
};

//! Delaunay triangles of the points. Deterministic: the same points give the same result.
DelaunayTriangles delaunay_triangles(const std::vector<Vec3>& points, const DelaunayOptions& options = {});

//! The convex hull's triangles as point indices, each wound counter-clockwise seen from outside (a
//! closed genus-0 surface through every hull point), sorted; empty when the points span no volume.
//! Deterministic. Made from the facets of the 3D Delaunay triangulation that face its infinite vertex.
std::vector<std::array<std::uint32_t, 3>> convex_hull_triangles(const std::vector<Vec3>& points);

//! \brief The constrained Delaunay triangulation of a simple polygon with points inside it, as the
//! local refinement of a mesh (refine_mesh.h) re-triangulates a tile's outline with its descendants'
//! points. Vertices 0 .. polygon.size()-1 are the polygon's corners (counter-clockwise), the rest the
//! inside points in order. Every triangle is counter-clockwise and lies inside the polygon; every
//! polygon edge is a triangle edge. Inside points that coincide with another point appear in no
//! triangle. Empty when the polygon is not simple (edges that cross or touch) or when an inside point
//! lies on or outside the outline. Deterministic.
std::vector<std::array<std::uint32_t, 3>> polygon_triangles(const std::vector<std::array<double, 2>>& polygon,
                                                            const std::vector<std::array<double, 2>>& inside);

} // namespace mrt
