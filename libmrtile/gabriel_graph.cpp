// Paper §4.1, Fig. 3: the Gabriel graph of the cluster centres defines which clusters are neighbours,
// and so which points are reclassified after a split. Exact construction via the Delaunay graph
// (Gabriel ⊆ Delaunay): a Delaunay edge pq is Gabriel iff the site nearest to its midpoint m is not
// strictly closer than |pm|, which CGAL's nearest_vertex answers exactly by walking the triangulation.
#include "libmrtile/gabriel_graph.h"

#include "libmrtile/errors.h"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace mrt {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<std::uint32_t, Kernel>;
using Tds = CGAL::Triangulation_data_structure_3<VertexBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, Tds>;

} // namespace

namespace {

// Builds the triangulation and calls visit(a, b) for every finite edge (each once).
template <typename Visit>
void for_each_delaunay_edge(const std::vector<Vec3>& points, Visit visit)
{
    // Insert in input order (not spatially sorted) so that coincident points always merge into the
    // first of them, as documented; the triangulation itself does not depend on the order.
    // CGAL's exact fallback dies in GMP on a NaN or an infinity, and the Gabriel test squares distances
    // (QA round 59: SIGFPE on a NaN; at 1e300 every Delaunay edge was kept): refused, naming the point.
    for (std::size_t i = 0; i < points.size(); ++i)
        for (int k = 0; k < 3; ++k)
            if (!(std::abs(points[i][k]) <= kMaxGraphCoordinate))
                throw InvalidInput("delaunay_graph/gabriel_graph: point " + std::to_string(i) +
                                   " has a NaN, infinite or larger than 1e100 coordinate");
    Delaunay dt;
    Delaunay::Vertex_handle hint;
    for (std::uint32_t i = 0; i < points.size(); ++i) {
        const Vec3& p = points[i];
        const std::size_t before = dt.number_of_vertices();
        Delaunay::Vertex_handle v = dt.insert(Kernel::Point_3(p.x, p.y, p.z), hint);
        if (dt.number_of_vertices() == before)
            continue; // coincident with an earlier point: merged into it
        v->info() = i;
        hint = v;
    }
    for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e)
        visit(dt, e->first->vertex(e->second), e->first->vertex(e->third));
}

void sort_lists(std::vector<std::vector<std::uint32_t>>& adjacency)
{
    for (auto& list : adjacency)
        std::sort(list.begin(), list.end());
}

} // namespace

std::vector<std::vector<std::uint32_t>> delaunay_graph(const std::vector<Vec3>& points)
{
    std::vector<std::vector<std::uint32_t>> adjacency(points.size());
    if (points.size() < 2)
        return adjacency;
    for_each_delaunay_edge(points, [&](const Delaunay&, Delaunay::Vertex_handle a, Delaunay::Vertex_handle b) {
        adjacency[a->info()].push_back(b->info());
        adjacency[b->info()].push_back(a->info());
    });
    sort_lists(adjacency);
    return adjacency;
}

std::vector<std::vector<std::uint32_t>> gabriel_graph(const std::vector<Vec3>& points)
{
    std::vector<std::vector<std::uint32_t>> adjacency(points.size());
    if (points.size() < 2)
        return adjacency;
    for_each_delaunay_edge(points, [&](const Delaunay& dt, Delaunay::Vertex_handle a, Delaunay::Vertex_handle b) {
        const Vec3& p = points[a->info()];
        const Vec3& q = points[b->info()];
        const Vec3 m = (p + q) * 0.5;
        const Delaunay::Vertex_handle nearest = dt.nearest_vertex(Kernel::Point_3(m.x, m.y, m.z), a->cell());
        if (nearest != a && nearest != b && !is_gabriel_edge(p, q, points[nearest->info()]))
            return;
        adjacency[a->info()].push_back(b->info());
        adjacency[b->info()].push_back(a->info());
    });
    sort_lists(adjacency);
    return adjacency;
}

} // namespace mrt
