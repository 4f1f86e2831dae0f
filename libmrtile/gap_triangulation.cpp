// Delaunay step of the gap triangulation (paper §4.3): the paper triangulates the pseudo-tile boundary
// points with Delaunay, in 2D on the x-y projection for functional data and in 3D otherwise, and then
// removes "undesired" triangles. CGAL's exact-predicate triangulations give the same, robustly, for
// degenerate (cospherical, coplanar) input; this file only wraps them and lists the triangles (and,
// from the same 3D triangulation, the convex hull that stands in for a cloud too small to tile).
#include "libmrtile/gap_triangulation.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <iterator>
#include <limits>
#include <numeric>
#include <utility>

namespace mrt {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb3 = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, Kernel>;
using Tds3 = CGAL::Triangulation_data_structure_3<Vb3>;
using Delaunay3 = CGAL::Delaunay_triangulation_3<Kernel, Tds3>;
using Vb2 = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Kernel>;
using Tds2 = CGAL::Triangulation_data_structure_2<Vb2>;
using Delaunay2 = CGAL::Delaunay_triangulation_2<Kernel, Tds2>;
using Triangle = std::array<std::uint32_t, 3>;
// Constrained 2D triangulation: vertex info = input index, face info = inside the polygon.
using CdtVb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, Kernel>;
using CdtFb = CGAL::Triangulation_face_base_with_info_2<char, Kernel, CGAL::Constrained_triangulation_face_base_2<Kernel>>;
using CdtTds = CGAL::Triangulation_data_structure_2<CdtVb, CdtFb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, CdtTds, CGAL::No_constraint_intersection_tag>;

Triangle sorted(std::uint32_t a, std::uint32_t b, std::uint32_t c)
{
    Triangle t{a, b, c};
    std::sort(t.begin(), t.end());
    return t;
}

// Duplicates are merged by the triangulation in an order that depends on its spatial sort; we merge
// them ourselves first so that the kept point is always the one with the smallest index.
std::vector<std::uint32_t> representatives(const std::vector<std::array<double, 3>>& coords)
{
    std::vector<std::uint32_t> order(coords.size());
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        return coords[a] != coords[b] ? coords[a] < coords[b] : a < b;
    });
    std::vector<std::uint32_t> rep(coords.size());
    for (std::size_t i = 0; i < order.size(); ++i)
        rep[order[i]] = (i > 0 && coords[order[i]] == coords[order[i - 1]]) ? rep[order[i - 1]] : order[i];
    return rep;
}

// The 3D Delaunay input: each distinct point once (its representative), with its index as info.
std::vector<std::pair<Kernel::Point_3, std::uint32_t>> distinct_points_3(const std::vector<std::array<double, 3>>& coords,
                                                                         const std::vector<std::uint32_t>& representative)
{
    std::vector<std::pair<Kernel::Point_3, std::uint32_t>> input;
    for (std::uint32_t i = 0; i < coords.size(); ++i)
        if (representative[i] == i)
            input.emplace_back(Kernel::Point_3(coords[i][0], coords[i][1], coords[i][2]), i);
    return input;
}

} // namespace

DelaunayTriangles delaunay_triangles(const std::vector<Vec3>& points, const DelaunayOptions& options)
{
    DelaunayTriangles out;
    std::vector<std::array<double, 3>> coords(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3& p = points[i];
        coords[i] = options.projected ? std::array<double, 3>{dot(p, options.axis_u), dot(p, options.axis_v), 0.0}
                                      : std::array<double, 3>{p.x, p.y, p.z};
    }
    out.representative = representatives(coords);

    if (options.projected) {
        std::vector<std::pair<Kernel::Point_2, std::uint32_t>> input;
        for (std::uint32_t i = 0; i < points.size(); ++i)
            if (out.representative[i] == i)
                input.emplace_back(Kernel::Point_2(coords[i][0], coords[i][1]), i);
        Delaunay2 dt(input.begin(), input.end());
        if (dt.dimension() == 2)
            for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
                out.triangles.push_back(sorted(f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()));
    } else {
        const auto input = distinct_points_3(coords, out.representative);
        Delaunay3 dt(input.begin(), input.end());
        if (dt.dimension() == 3) {
            for (auto f = dt.finite_facets_begin(); f != dt.finite_facets_end(); ++f) {
                const int i = f->second;
                const auto& c = f->first;
                out.triangles.push_back(sorted(c->vertex((i + 1) & 3)->info(), c->vertex((i + 2) & 3)->info(),
                                               c->vertex((i + 3) & 3)->info()));
            }
        } else if (dt.dimension() == 2) {
            // Coplanar points: the triangulation is planar and its facets are the cells' faces.
            for (auto f = dt.finite_facets_begin(); f != dt.finite_facets_end(); ++f) {
                const auto& c = f->first;
                out.triangles.push_back(sorted(c->vertex(0)->info(), c->vertex(1)->info(), c->vertex(2)->info()));
            }
        }
    }
    std::sort(out.triangles.begin(), out.triangles.end());
    out.triangles.erase(std::unique(out.triangles.begin(), out.triangles.end()), out.triangles.end());
    return out;
}

std::vector<std::array<std::uint32_t, 3>> convex_hull_triangles(const std::vector<Vec3>& points)
{
    std::vector<std::array<double, 3>> coords(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        coords[i] = {points[i].x, points[i].y, points[i].z};
    const auto input = distinct_points_3(coords, representatives(coords));
    Vec3 centroid{0, 0, 0};
    for (const auto& [p, i] : input)
        centroid = centroid + points[i];
    std::vector<Triangle> hull;
    Delaunay3 dt(input.begin(), input.end());
    if (dt.dimension() != 3)
        return hull;
    centroid = centroid * (1.0 / static_cast<double>(input.size())); // inside the hull: it is convex
    std::vector<Delaunay3::Cell_handle> cells;
    dt.incident_cells(dt.infinite_vertex(), std::back_inserter(cells));
    for (const auto& c : cells) {
        const int i = c->index(dt.infinite_vertex());
        Triangle t{c->vertex((i + 1) & 3)->info(), c->vertex((i + 2) & 3)->info(), c->vertex((i + 3) & 3)->info()};
        // Wind by the centroid rather than by CGAL's cell orientation convention: outward is away from it.
        const Vec3& a = points[t[0]];
        if (dot(cross(points[t[1]] - a, points[t[2]] - a), a - centroid) < 0.0)
            std::swap(t[1], t[2]);
        std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end()); // same winding, smallest first
        hull.push_back(t);
    }
    std::sort(hull.begin(), hull.end());
    return hull;
}

std::vector<Triangle> polygon_triangles(const std::vector<std::array<double, 2>>& polygon,
                                        const std::vector<std::array<double, 2>>& inside)
{
    const std::size_t n = polygon.size();
    if (n < 3)
        return {};
    Cdt cdt;
    std::vector<Cdt::Vertex_handle> corners(n);
    try {
        for (std::size_t i = 0; i < n; ++i) {
            corners[i] = cdt.insert(Kernel::Point_2(polygon[i][0], polygon[i][1]));
            corners[i]->info() = static_cast<std::uint32_t>(i);
        }
        if (cdt.number_of_vertices() != n)
            return {}; // a repeated corner
        for (std::size_t i = 0; i < n; ++i)
            cdt.insert_constraint(corners[i], corners[(i + 1) % n]);
    } catch (const std::exception&) {
        return {}; // No_constraint_intersection_tag: edges that cross or touch
    }
    // A corner strictly between two others on a constraint would have split it: the polygon touches itself.
    if (cdt.number_of_vertices() != n)
        return {};
    // Inside = reached from the infinite face across an odd number of constraints (one, for a simple polygon).
    for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f)
        f->info() = -1;
    std::vector<Cdt::Face_handle> stack{cdt.infinite_face()};
    cdt.infinite_face()->info() = 0;
    std::vector<Cdt::Face_handle> inner_seeds;
    while (!stack.empty()) {
        const Cdt::Face_handle f = stack.back();
        stack.pop_back();
        for (int k = 0; k < 3; ++k) {
            const Cdt::Face_handle g = f->neighbor(k);
            if (g->info() != -1)
                continue;
            if (cdt.is_constrained(Cdt::Edge(f, k))) {
                inner_seeds.push_back(g);
                continue;
            }
            g->info() = 0;
            stack.push_back(g);
        }
    }
    for (const Cdt::Face_handle seed : inner_seeds)
        if (seed->info() == -1) {
            seed->info() = 1;
            stack.push_back(seed);
            while (!stack.empty()) {
                const Cdt::Face_handle f = stack.back();
                stack.pop_back();
                for (int k = 0; k < 3; ++k) {
                    const Cdt::Face_handle g = f->neighbor(k);
                    if (g->info() == -1 && !cdt.is_constrained(Cdt::Edge(f, k))) {
                        g->info() = 1;
                        stack.push_back(g);
                    }
                }
            }
        }
    // The inside points, each strictly inside: located in an inside face, not on its edges.
    for (std::size_t i = 0; i < inside.size(); ++i) {
        const Kernel::Point_2 p(inside[i][0], inside[i][1]);
        Cdt::Locate_type type;
        int li = 0;
        const Cdt::Face_handle f = cdt.locate(p, type, li);
        if (type == Cdt::VERTEX)
            continue; // coincides with a point already in: appears in no triangle
        const bool on_outline = type == Cdt::EDGE && cdt.is_constrained(Cdt::Edge(f, li));
        if ((type != Cdt::FACE && type != Cdt::EDGE) || on_outline || cdt.is_infinite(f) || f->info() != 1)
            return {};
        const Cdt::Vertex_handle v = cdt.insert(p, type, f, li);
        v->info() = static_cast<std::uint32_t>(n + i);
        // Faces made by the insertion inherit nothing: they are inside, as the face they split was.
        const Cdt::Face_circulator first = cdt.incident_faces(v);
        Cdt::Face_circulator fc = first;
        do {
            fc->info() = 1;
        } while (++fc != first);
    }
    std::vector<Triangle> out;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
        if (f->info() == 1)
            out.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    std::sort(out.begin(), out.end()); // CGAL's face order follows its memory: sorted for determinism
    return out;
}

} // namespace mrt
