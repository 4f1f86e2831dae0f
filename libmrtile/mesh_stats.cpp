// Quality measurement of the output meshes (paper §5 reports how close the approximations are and the
// method promises manifold tiles): exact topology counts on a triangle soup, and exact point <-> surface
// distances. The soup is the core so that a triangle set can be checked before OpenMesh, which refuses
// non-manifold edges, ever sees it. This is the one file that includes CGAL's AABB and kd trees.
#include "libmrtile/mesh_stats.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/errors.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/parallel.h"
#include "libmrtile/point_cloud.h"
#include "libmrtile/union_find.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>

namespace mrt {
namespace {

using Triangle = std::array<std::uint32_t, 3>;

struct Soup
{
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
};

// Compacts away deleted elements, so that soup indices are dense.
Soup mesh_to_soup(const Mesh& mesh)
{
    Soup soup;
    std::vector<std::uint32_t> index(mesh.n_vertices(), 0);
    soup.positions.reserve(mesh.n_vertices());
    for (const auto vh : mesh.vertices()) {
        index[vh.idx()] = static_cast<std::uint32_t>(soup.positions.size());
        soup.positions.push_back(to_vec3(mesh.point(vh)));
    }
    soup.triangles.reserve(mesh.n_faces());
    for (const auto fh : mesh.faces()) {
        Triangle t{};
        int k = 0;
        for (const auto vh : fh.vertices()) {
            assert(k < 3);
            t[k++] = index[vh.idx()];
        }
        assert(k == 3);
        soup.triangles.push_back(t);
    }
    return soup;
}

bool has_repeated_vertex(const Triangle& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

// One directed use of an edge by a face: the face's corner k goes from t[k] to t[(k+1)%3].
struct HalfEdge
{
    std::uint32_t lo, hi;  // the undirected edge
    std::uint32_t corner;  // 3 * face + k
    bool forward;          // t[k] == lo
};

constexpr std::uint32_t kNone = ~std::uint32_t{0};

// Half-edges grouped by undirected edge: edge e owns half_edges[edge_start[e] .. edge_start[e+1]).
struct EdgeTable
{
    std::vector<HalfEdge> half_edges;
    std::vector<std::uint32_t> edge_start;
    std::vector<std::uint32_t> corner_edge;  // 3 * face + k -> edge; kNone for faces left out

    std::size_t size() const { return edge_start.size() - 1; }
    std::uint32_t use_count(std::uint32_t e) const { return edge_start[e + 1] - edge_start[e]; }
};

EdgeTable build_edges(const std::vector<Triangle>& triangles, const std::vector<bool>& used_face)
{
    EdgeTable table;
    table.corner_edge.assign(3 * triangles.size(), kNone);
    for (std::uint32_t f = 0; f < triangles.size(); ++f) {
        if (!used_face[f])
            continue;
        for (std::uint32_t k = 0; k < 3; ++k) {
            const std::uint32_t a = triangles[f][k], b = triangles[f][(k + 1) % 3];
            table.half_edges.push_back({std::min(a, b), std::max(a, b), 3 * f + k, a < b});
        }
    }
    std::sort(table.half_edges.begin(), table.half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
        return std::tie(x.lo, x.hi, x.corner) < std::tie(y.lo, y.hi, y.corner);
    });
    for (std::uint32_t i = 0; i < table.half_edges.size(); ++i) {
        const HalfEdge& h = table.half_edges[i];
        if (i == 0 || h.lo != table.half_edges[i - 1].lo || h.hi != table.half_edges[i - 1].hi)
            table.edge_start.push_back(i);
        table.corner_edge[h.corner] = static_cast<std::uint32_t>(table.edge_start.size() - 1);
    }
    table.edge_start.push_back(static_cast<std::uint32_t>(table.half_edges.size()));
    return table;
}

// The corner of face f at vertex v.
std::uint32_t corner_at(const std::vector<Triangle>& triangles, std::uint32_t f, std::uint32_t v)
{
    const Triangle& t = triangles[f];
    const std::uint32_t k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    assert(t[k] == v);
    return 3 * f + k;
}

// Checks that the faces of each component can be oriented consistently: propagates a flip flag across
// every two-face edge (all edges are such when this is called), and fails on a contradiction (Möbius).
std::vector<bool> orientable_components(const std::vector<Triangle>& triangles, const EdgeTable& edges,
                                        const std::vector<std::uint32_t>& face_component,
                                        std::size_t component_count)
{
    std::vector<bool> orientable(component_count, true);
    std::vector<signed char> flip(triangles.size(), -1);
    std::vector<std::uint32_t> stack;
    for (std::uint32_t seed = 0; seed < triangles.size(); ++seed) {
        if (face_component[seed] == kNone || flip[seed] >= 0)
            continue;
        flip[seed] = 0;
        stack.push_back(seed);
        while (!stack.empty()) {
            const std::uint32_t f = stack.back();
            stack.pop_back();
            for (std::uint32_t k = 0; k < 3; ++k) {
                const std::uint32_t e = edges.corner_edge[3 * f + k];
                if (edges.use_count(e) != 2)
                    continue;
                const HalfEdge& h0 = edges.half_edges[edges.edge_start[e]];
                const HalfEdge& h1 = edges.half_edges[edges.edge_start[e] + 1];
                const HalfEdge& mine = h0.corner / 3 == f ? h0 : h1;
                const HalfEdge& other = h0.corner / 3 == f ? h1 : h0;
                const std::uint32_t g = other.corner / 3;
                // Same direction along the shared edge: exactly one of the two faces must be flipped.
                const signed char want = static_cast<signed char>(flip[f] ^ (mine.forward == other.forward));
                if (flip[g] < 0) {
                    flip[g] = want;
                    stack.push_back(g);
                } else if (flip[g] != want) {
                    orientable[face_component[f]] = false;
                }
            }
        }
    }
    return orientable;
}

TopologyStats soup_topology(const std::vector<Vec3>& positions, const std::vector<Triangle>& triangles)
{
    TopologyStats s;
    s.vertices = positions.size();
    s.faces = triangles.size();
    const std::size_t nf = triangles.size();
    if (nf >= kNone / 3)
        throw InvalidInput("topology_stats: " + std::to_string(nf) + " triangles are more than supported");
    for (std::size_t f = 0; f < nf; ++f)
        for (const std::uint32_t v : triangles[f])
            if (v >= positions.size())
                throw InvalidInput("topology_stats: triangle " + std::to_string(f) + " refers to vertex " +
                                   std::to_string(v) + " but there are only " +
                                   std::to_string(positions.size()) + " positions");

    // Used vertices, duplicates and degenerate faces (over all faces).
    std::vector<bool> vertex_used(positions.size(), false);
    std::vector<bool> face_used(nf, false);
    std::vector<Vec3> used_positions;
    for (std::size_t f = 0; f < nf; ++f) {
        face_used[f] = !has_repeated_vertex(triangles[f]);
        for (const std::uint32_t v : triangles[f]) {
            if (!vertex_used[v])
                used_positions.push_back(positions[v]);
            vertex_used[v] = true;
        }
    }
    // A vertex only in faces with a repeated index has no edge: it counts as isolated.
    std::vector<bool> vertex_in_face(positions.size(), false);
    for (std::size_t f = 0; f < nf; ++f)
        if (face_used[f])
            for (const std::uint32_t v : triangles[f])
                vertex_in_face[v] = true;
    const std::size_t used_vertices =
        static_cast<std::size_t>(std::count(vertex_in_face.begin(), vertex_in_face.end(), true));
    s.isolated_vertices = positions.size() - used_vertices;

    const double diagonal = bounding_box(used_positions).diagonal();
    const double area_floor = 1e-14 * diagonal * diagonal;
    std::vector<Triangle> sorted_faces(triangles);
    for (std::size_t f = 0; f < nf; ++f) {
        const Triangle& t = triangles[f];
        const double area =
            0.5 * norm(cross(positions[t[1]] - positions[t[0]], positions[t[2]] - positions[t[0]]));
        if (!face_used[f] || area <= area_floor)
            ++s.degenerate_faces;
        std::sort(sorted_faces[f].begin(), sorted_faces[f].end());
    }
    std::sort(sorted_faces.begin(), sorted_faces.end());
    s.duplicate_faces = static_cast<std::size_t>(
        sorted_faces.end() - std::unique(sorted_faces.begin(), sorted_faces.end()));

    // Edges, boundary, non-manifold edges, orientation.
    const EdgeTable edges = build_edges(triangles, face_used);
    s.edges = edges.size();
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        const std::uint32_t n = edges.use_count(e);
        if (n == 1)
            ++s.boundary_edges;
        if (n > 2)
            ++s.nonmanifold_edges;
        std::uint32_t forward = 0;
        for (std::uint32_t i = edges.edge_start[e]; i < edges.edge_start[e + 1]; ++i)
            forward += edges.half_edges[i].forward ? 1 : 0;
        if (n >= 2 && 2 * forward != n)
            s.consistently_oriented = false;
    }

    // Fans: corners (face, vertex) joined across every two-face edge, at both of its end points. The
    // fans around a vertex are the classes of its corners.
    UnionFind fans(3 * nf);
    for (std::uint32_t e = 0; e < edges.size(); ++e) {
        if (edges.use_count(e) != 2)
            continue;
        const HalfEdge& h0 = edges.half_edges[edges.edge_start[e]];
        const HalfEdge& h1 = edges.half_edges[edges.edge_start[e] + 1];
        const std::uint32_t f0 = h0.corner / 3, f1 = h1.corner / 3;
        for (const std::uint32_t v : {h0.lo, h0.hi})
            fans.unite(corner_at(triangles, f0, v), corner_at(triangles, f1, v));
    }
    std::vector<std::uint32_t> fan_count(positions.size(), 0);
    for (std::uint32_t c = 0; c < 3 * nf; ++c)
        if (face_used[c / 3] && fans.find(c) == c)
            ++fan_count[triangles[c / 3][c % 3]];
    s.nonmanifold_vertices =
        static_cast<std::size_t>(std::count_if(fan_count.begin(), fan_count.end(), [](auto n) { return n > 1; }));

    // Boundary loops: at each end point, a boundary edge continues into the other boundary edge of its
    // own fan (an open fan has exactly two ends). Chains of edges joined that way are the loops.
    std::vector<std::uint32_t> boundary_index(edges.size(), kNone);
    std::vector<std::uint32_t> boundary_edge_list;
    for (std::uint32_t e = 0; e < edges.size(); ++e)
        if (edges.use_count(e) == 1) {
            boundary_index[e] = static_cast<std::uint32_t>(boundary_edge_list.size());
            boundary_edge_list.push_back(e);
        }
    UnionFind loops(boundary_edge_list.size());
    {
        std::vector<std::uint32_t> fan_end_count(3 * nf, 0), fan_first_end(3 * nf, kNone);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> fan_pairs;  // (fan root, boundary edge)
        for (std::uint32_t b = 0; b < boundary_edge_list.size(); ++b) {
            const HalfEdge& h = edges.half_edges[edges.edge_start[boundary_edge_list[b]]];
            for (const std::uint32_t v : {h.lo, h.hi}) {
                const std::uint32_t root = fans.find(corner_at(triangles, h.corner / 3, v));
                if (fan_end_count[root]++ == 0)
                    fan_first_end[root] = b;
                else
                    fan_pairs.push_back({root, b});
            }
        }
        // Join only fans with exactly two boundary ends; a fan cut by a non-manifold edge may have one.
        for (const auto& [root, b] : fan_pairs)
            if (fan_end_count[root] == 2)
                loops.unite(fan_first_end[root], b);
    }

    // Components: faces sharing a vertex.
    UnionFind vertex_sets(positions.size());
    for (std::size_t f = 0; f < nf; ++f)
        if (face_used[f]) {
            vertex_sets.unite(triangles[f][0], triangles[f][1]);
            vertex_sets.unite(triangles[f][0], triangles[f][2]);
        }
    std::vector<std::uint32_t> vertex_component(positions.size(), kNone);
    for (std::uint32_t v = 0; v < positions.size(); ++v) {
        if (!vertex_in_face[v])
            continue;
        const std::uint32_t root = vertex_sets.find(v);
        if (vertex_component[root] == kNone)
            vertex_component[root] = static_cast<std::uint32_t>(s.components++);
        vertex_component[v] = vertex_component[root];
    }
    std::vector<std::uint32_t> face_component(nf, kNone);
    std::vector<long> chi(s.components, 0);
    std::vector<long> component_loops(s.components, 0);
    for (std::uint32_t v = 0; v < positions.size(); ++v)
        if (vertex_in_face[v])
            ++chi[vertex_component[v]];
    for (std::size_t f = 0; f < nf; ++f)
        if (face_used[f]) {
            face_component[f] = vertex_component[triangles[f][0]];
            ++chi[face_component[f]];
        }
    for (std::uint32_t e = 0; e < edges.size(); ++e)
        --chi[face_component[edges.half_edges[edges.edge_start[e]].corner / 3]];
    for (std::uint32_t b = 0; b < boundary_edge_list.size(); ++b)
        if (loops.find(b) == b) {
            ++s.boundary_loops;
            const std::uint32_t e = boundary_edge_list[b];
            ++component_loops[face_component[edges.half_edges[edges.edge_start[e]].corner / 3]];
        }
    s.euler_characteristic = std::accumulate(chi.begin(), chi.end(), 0L);

    if (s.nonmanifold_edges > 0 || s.nonmanifold_vertices > 0) {
        s.genus = -1;
        return s;
    }
    const std::vector<bool> orientable = orientable_components(triangles, edges, face_component, s.components);
    long genus = 0;
    for (std::size_t c = 0; c < s.components; ++c) {
        if (!orientable[c]) {
            s.genus = -1;
            return s;
        }
        const long twice = 2 - chi[c] - component_loops[c];
        assert(twice >= 0 && twice % 2 == 0);
        genus += twice / 2;
    }
    s.genus = static_cast<int>(genus);
    return s;
}

// ---- distances ----------------------------------------------------------------------------------

using Kernel = CGAL::Simple_cartesian<double>;
using CgalPoint = Kernel::Point_3;
using CgalTriangle = Kernel::Triangle_3;

CgalPoint to_cgal(const Vec3& p) { return {p.x, p.y, p.z}; }

void check_finite(const std::vector<Vec3>& points, const char* function)
{
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!is_finite(points[i]))
            throw InvalidInput(std::string(function) + ": point " + std::to_string(i) + " is not finite");
}

// Checks the points and returns their bounding-box diagonal, the unit of the reported distances.
double checked_diagonal(const std::vector<Vec3>& points, const char* function)
{
    check_finite(points, function);
    const double diagonal = bounding_box(points).diagonal();
    if (!(diagonal > 0.0))
        throw InvalidInput(std::string(function) + ": the points' bounding box has zero diagonal, so "
                                                   "distances relative to it are undefined");
    return diagonal;
}

// Indices of the points sorted along a Z-order curve (21 bits per axis), so that consecutive points
// are close in space; ties keep index order, so the order is deterministic.
std::vector<std::size_t> morton_order(const std::vector<Vec3>& points)
{
    const BoundingBox box = bounding_box(points);
    const Vec3 size = box.size();
    const double extent = std::max({size.x, size.y, size.z});
    const double scale = extent > 0.0 ? double((1u << 21) - 1) / extent : 0.0;
    auto spread = [](std::uint64_t v) {  // inserts two zero bits between the 21 low bits of v
        v &= 0x1fffff;
        v = (v | v << 32) & 0x1f00000000ffffULL;
        v = (v | v << 16) & 0x1f0000ff0000ffULL;
        v = (v | v << 8) & 0x100f00f00f00f00fULL;
        v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
        v = (v | v << 2) & 0x1249249249249249ULL;
        return v;
    };
    std::vector<std::pair<std::uint64_t, std::size_t>> keyed(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Vec3 q = (points[i] - box.min) * scale;
        keyed[i] = {spread(std::uint64_t(q.x)) | spread(std::uint64_t(q.y)) << 1 | spread(std::uint64_t(q.z)) << 2,
                    i};
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<std::size_t> order(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        order[i] = keyed[i].second;
    return order;
}

// Sums in index order so that the result does not depend on how the distances were computed.
DistanceStats summarize(const std::vector<double>& squared_distances, double diagonal, const FarPoints& far_points = {})
{
    const double far_beyond = std::max(far_points.beyond, kFarFraction * diagonal);
    DistanceStats stats;
    stats.diagonal = diagonal;
    if (far_points.found)
        far_points.found->assign(squared_distances.size(), 0);
    if (squared_distances.empty())
        return stats;
    double sum = 0.0, near_sum = 0.0, sum_squares = 0.0, max = 0.0;
    for (std::size_t i = 0; i < squared_distances.size(); ++i) {
        const double d2 = squared_distances[i];
        const double d = std::sqrt(d2);
        sum += d;
        sum_squares += d2;
        max = std::max(max, d);
        const bool far = far_points.given ? (*far_points.given)[i] != 0 : d > far_beyond;
        if (far) {
            ++stats.far;
            if (far_points.found)
                (*far_points.found)[i] = 1;
        } else {
            near_sum += d;
        }
    }
    const double n = static_cast<double>(squared_distances.size());
    stats.mean = sum / n / diagonal;
    const std::size_t near = squared_distances.size() - stats.far;
    stats.near_mean = near > 0 ? near_sum / static_cast<double>(near) / diagonal : 0.0;
    stats.max = max / diagonal;
    stats.rms = std::sqrt(sum_squares / n) / diagonal;
    // Order statistics on a copy: nth_element is linear and the input order stays what the caller gave.
    std::vector<double> sorted = squared_distances;
    const auto at_fraction = [&](double fraction) {
        const auto k = static_cast<std::ptrdiff_t>(fraction * (n - 1.0));
        std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
        return std::sqrt(sorted[static_cast<std::size_t>(k)]) / diagonal;
    };
    stats.median = at_fraction(0.5);
    stats.p99 = at_fraction(0.99);
    return stats;
}

} // namespace

TopologyStats topology_stats(const Mesh& mesh)
{
    const Soup soup = mesh_to_soup(mesh);
    return soup_topology(soup.positions, soup.triangles);
}

TopologyStats topology_stats(const std::vector<Vec3>& positions, const std::vector<std::array<std::uint32_t, 3>>& triangles)
{
    return soup_topology(positions, triangles);
}

namespace {

// The boxes of a vector of triangles by iterator (AABB_traits' BboxMap: a readable property map).
struct TriangleBoxes
{
    using key_type = std::vector<CgalTriangle>::const_iterator;
    using value_type = CGAL::Bbox_3;
    using reference = const CGAL::Bbox_3&;
    using category = boost::readable_property_map_tag;
    key_type first;
    const std::vector<CGAL::Bbox_3>* boxes = nullptr;

    friend reference get(const TriangleBoxes& map, key_type at)
    {
        return (*map.boxes)[static_cast<std::size_t>(at - map.first)];
    }
};

// The closest point of `soup` to every point, with the soup index of its triangle. Queries run in Morton
// order in fixed chunks, each chunk on one thread: the hint chain (and so the choice among exactly tied
// faces) depends on the chunks only, never on the number of threads.
std::vector<std::pair<std::uint32_t, Vec3>> soup_closest_points(const std::vector<Vec3>& points, const Soup& soup,
                                                                std::size_t threads)
{
    using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<CgalTriangle>::const_iterator>;
    using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive, TriangleBoxes>>;
    std::vector<CgalTriangle> triangles;
    triangles.reserve(soup.triangles.size());
    for (const Triangle& t : soup.triangles)
        triangles.emplace_back(to_cgal(soup.positions[t[0]]), to_cgal(soup.positions[t[1]]),
                               to_cgal(soup.positions[t[2]]));
    // Each triangle's box once: the build otherwise recomputes it on every level of the tree (the same
    // boxes, so the same tree).
    std::vector<CGAL::Bbox_3> boxes;
    boxes.reserve(triangles.size());
    for (const CgalTriangle& t : triangles)
        boxes.push_back(t.bbox());
    Tree tree(CGAL::AABB_traits<Kernel, Primitive, TriangleBoxes>(TriangleBoxes{triangles.cbegin(), &boxes}));
    tree.insert(triangles.cbegin(), triangles.cend());
    // The closest point of the previous query is the hint of the next one: in Morton order the two are
    // close, so the search sphere starts small. This replaces CGAL's kd-tree of hints (a third faster).
    tree.do_not_accelerate_distance_queries();
    tree.build(); // before the threads: queries on a built tree only read it
    const std::vector<std::size_t> order = morton_order(points);
    std::vector<std::pair<std::uint32_t, Vec3>> out(points.size());
    run_parallel_ranges(order.size(), 4096, threads, [&](std::size_t begin, std::size_t end) {
        Tree::Point_and_primitive_id hint(triangles[0].vertex(0), triangles.cbegin()); // per range
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t i = order[k];
            hint = tree.closest_point_and_primitive(to_cgal(points[i]), hint);
            out[i] = {static_cast<std::uint32_t>(hint.second - triangles.cbegin()),
                      Vec3{hint.first.x(), hint.first.y(), hint.first.z()}};
        }
    });
    return out;
}

} // namespace

DistanceStats point_to_mesh_distance(const std::vector<Vec3>& points, const Mesh& mesh, double far_beyond)
{
    FarPoints far_points;
    far_points.beyond = far_beyond;
    return point_to_mesh_distance(points, mesh, far_points);
}

DistanceStats point_to_mesh_distance(const std::vector<Vec3>& points, const Mesh& mesh, const FarPoints& far_points)
{
    if (far_points.given && far_points.given->size() != points.size())
        throw InvalidInput("point_to_mesh_distance: " + std::to_string(far_points.given->size()) + " far flags for " +
                           std::to_string(points.size()) + " points");
    if (points.empty()) {
        if (far_points.found)
            far_points.found->clear();
        return {};
    }
    const double diagonal = checked_diagonal(points, "point_to_mesh_distance");
    const Soup soup = mesh_to_soup(mesh);
    if (soup.triangles.empty())
        throw InvalidInput("point_to_mesh_distance: the mesh has no face to measure the distance to");
    const auto closest = soup_closest_points(points, soup, 0);
    std::vector<double> squared(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        squared[i] = squared_norm(points[i] - closest[i].second);
    return summarize(squared, diagonal, far_points);
}

namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using ExactPoint = Epick::Point_3;

} // namespace

bool triangles_meet(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b)
{
    const auto p = [](const Vec3& q) { return ExactPoint(q.x, q.y, q.z); };
    const Epick::Triangle_3 ta(p(a[0]), p(a[1]), p(a[2])), tb(p(b[0]), p(b[1]), p(b[2]));
    return !ta.is_degenerate() && !tb.is_degenerate() && CGAL::do_intersect(ta, tb);
}

// Whether faces f and g meet other than in the corners and edges they share (CGAL's strict face
// intersection): no shared corner, any contact; one shared corner, the edge opposite it in either face
// touching the other face; a shared edge, the two faces folded onto each other (coplanar, same side).
bool faces_intersect(const Mesh& mesh, Mesh::FaceHandle f, Mesh::FaceHandle g)
{
    for (const Mesh::FaceHandle h : {f, g})
        if (!h.is_valid() || h.idx() >= static_cast<int>(mesh.n_faces()) || (mesh.has_face_status() && mesh.status(h).deleted()))
            throw InvalidInput("faces_intersect: face handle " + std::to_string(h.idx()) + " is no face of the mesh (or a deleted one)");
    return corners_intersect(mesh, face_vertices(mesh, f), face_vertices(mesh, g));
}

bool corners_intersect(const Mesh& mesh, const std::array<Mesh::VertexHandle, 3>& a, const std::array<Mesh::VertexHandle, 3>& b)
{
    int shared = 0;
    std::array<int, 3> in_b{-1, -1, -1}; // for each corner of f, its position in g (-1: none)
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (a[static_cast<std::size_t>(i)] == b[static_cast<std::size_t>(j)]) {
                in_b[static_cast<std::size_t>(i)] = j;
                ++shared;
            }
    // Apart by their boxes, two faces without a shared corner cannot cross: the exact predicates below
    // cost ten times as much (QA round 78: capping a 324k-point fandisk's holes on trial tested every
    // pair of a cap's faces, 3 s of an 11 s run). The same answers.
    const auto corners = [&](const std::array<Mesh::VertexHandle, 3>& f) {
        return std::array<Vec3, 3>{to_vec3(mesh.point(f[0])), to_vec3(mesh.point(f[1])), to_vec3(mesh.point(f[2]))};
    };
    if (shared == 0 && !triangle_box(corners(a)).meets(triangle_box(corners(b))))
        return false;
    const auto p = [&](Mesh::VertexHandle v) { const auto& q = mesh.point(v); return ExactPoint(q[0], q[1], q[2]); };
    const Epick::Triangle_3 ta(p(a[0]), p(a[1]), p(a[2])), tb(p(b[0]), p(b[1]), p(b[2]));
    if (ta.is_degenerate() || tb.is_degenerate())
        return false; // no area: nothing to cross (the callers never make such faces)
    if (shared == 0)
        return CGAL::do_intersect(ta, tb);
    if (shared == 1) {
        int i = 0;
        while (in_b[static_cast<std::size_t>(i)] < 0)
            ++i;
        const int j = in_b[static_cast<std::size_t>(i)];
        const Epick::Segment_3 opposite_a(p(a[static_cast<std::size_t>((i + 1) % 3)]), p(a[static_cast<std::size_t>((i + 2) % 3)]));
        const Epick::Segment_3 opposite_b(p(b[static_cast<std::size_t>((j + 1) % 3)]), p(b[static_cast<std::size_t>((j + 2) % 3)]));
        return CGAL::do_intersect(opposite_a, tb) || CGAL::do_intersect(opposite_b, ta);
    }
    if (shared == 2) {
        Mesh::VertexHandle r, s, e0, e1;
        for (int i = 0; i < 3; ++i)
            if (in_b[static_cast<std::size_t>(i)] < 0)
                r = a[static_cast<std::size_t>(i)];
        for (const auto v : b)
            if (v != a[0] && v != a[1] && v != a[2])
                s = v;
        bool first = true;
        for (int i = 0; i < 3; ++i)
            if (in_b[static_cast<std::size_t>(i)] >= 0) {
                (first ? e0 : e1) = a[static_cast<std::size_t>(i)];
                first = false;
            }
        return CGAL::coplanar(p(e0), p(e1), p(r), p(s)) &&
               CGAL::coplanar_orientation(p(e0), p(e1), p(r), p(s)) == CGAL::POSITIVE;
    }
    return false; // the same corners: a duplicate face, which a manifold mesh does not have
}

std::vector<std::pair<int, int>> intersecting_pairs_with(const Mesh& mesh, const std::vector<int>& faces)
{
    using FaceBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int>;
    auto box_of = [&](int f) {
        double lo[3], hi[3];
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::numeric_limits<double>::max();
            hi[k] = std::numeric_limits<double>::lowest();
        }
        for (const auto v : mesh.fv_range(Mesh::FaceHandle(f)))
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], mesh.point(v)[k]);
                hi[k] = std::max(hi[k], mesh.point(v)[k]);
            }
        return FaceBox(lo, hi, f);
    };
    std::vector<int> chosen = faces;
    std::sort(chosen.begin(), chosen.end());
    chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
    std::vector<FaceBox> some, all;
    for (const int f : chosen)
        if (f >= 0 && static_cast<std::size_t>(f) < mesh.n_faces() && !mesh.status(Mesh::FaceHandle(f)).deleted())
            some.push_back(box_of(f));
    if (some.empty())
        return {};
    for (const auto f : mesh.faces())
        all.push_back(box_of(f.idx()));
    std::vector<std::pair<int, int>> out;
    CGAL::box_intersection_d(some.begin(), some.end(), all.begin(), all.end(), [&](const FaceBox& a, const FaceBox& b) {
        if (a.info() != b.info() && faces_intersect(mesh, Mesh::FaceHandle(a.info()), Mesh::FaceHandle(b.info())))
            out.push_back({std::min(a.info(), b.info()), std::max(a.info(), b.info())});
    });
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

std::vector<std::pair<int, int>> self_intersecting_faces(const Mesh& mesh, const std::vector<int>* among)
{
    // Exact predicates, as faces_intersect: with the inexact kernel of the distances, faces of a flat
    // fan that share only its centre were taken for crossings when their plane is tilted off the axes
    // (QA round 28: one tile of an exactly planar cloud, 18 faces, 7 "pairs", none by faces_intersect).
    using SurfaceMesh = CGAL::Surface_mesh<ExactPoint>;
    SurfaceMesh sm;
    std::vector<SurfaceMesh::Vertex_index> vertex(mesh.n_vertices());
    for (const auto v : mesh.vertices()) {
        const auto& p = mesh.point(v);
        vertex[static_cast<std::size_t>(v.idx())] = sm.add_vertex(ExactPoint(p[0], p[1], p[2]));
    }
    std::vector<int> face_of; // surface-mesh face -> mesh face handle index
    for (const auto f : mesh.faces()) {
        std::array<SurfaceMesh::Vertex_index, 3> t;
        std::size_t k = 0;
        for (const auto v : mesh.fv_range(f))
            t[k++] = vertex[static_cast<std::size_t>(v.idx())];
        if (sm.add_face(t[0], t[1], t[2]) == SurfaceMesh::null_face())
            throw InvalidInput("self_intersecting_faces: the mesh is not a manifold triangle mesh");
        face_of.push_back(f.idx());
    }
    std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
    if (among) {
        std::vector<int> index_of(static_cast<std::size_t>(mesh.n_faces()), -1); // mesh face -> surface-mesh face
        for (std::size_t k = 0; k < face_of.size(); ++k)
            index_of[static_cast<std::size_t>(face_of[k])] = static_cast<int>(k);
        std::vector<SurfaceMesh::Face_index> range;
        for (const int f : *among)
            if (f >= 0 && static_cast<std::size_t>(f) < index_of.size() && index_of[static_cast<std::size_t>(f)] >= 0)
                range.push_back(SurfaceMesh::Face_index(static_cast<SurfaceMesh::size_type>(index_of[static_cast<std::size_t>(f)])));
        CGAL::Polygon_mesh_processing::self_intersections(range, sm, std::back_inserter(pairs));
    } else {
        CGAL::Polygon_mesh_processing::self_intersections(sm, std::back_inserter(pairs));
    }
    std::vector<std::pair<int, int>> out;
    out.reserve(pairs.size());
    for (const auto& [a, b] : pairs) {
        const int fa = face_of[static_cast<std::size_t>(a.idx())], fb = face_of[static_cast<std::size_t>(b.idx())];
        out.push_back({std::min(fa, fb), std::max(fa, fb)});
    }
    std::sort(out.begin(), out.end()); // CGAL's order depends on its box sorting: sort for determinism
    return out;
}

std::vector<ClosestPoint> closest_points(const std::vector<Vec3>& points, const Mesh& mesh, std::size_t threads)
{
    if (points.empty())
        return {};
    // No diagonal needed: the points can all be one (QA round 32: the probes of a one-point tile left
    // out of a merged scan's finest mesh stopped `mesh` with "zero diagonal").
    check_finite(points, "closest_points");
    const Soup soup = mesh_to_soup(mesh);
    if (soup.triangles.empty())
        throw InvalidInput("closest_points: the mesh has no face");
    std::vector<int> face_of(soup.triangles.size()); // soup triangle -> face handle index
    std::size_t k = 0;
    for (const auto fh : mesh.faces())
        face_of[k++] = fh.idx();
    const auto closest = soup_closest_points(points, soup, threads);
    std::vector<ClosestPoint> out(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        out[i] = {face_of[closest[i].first], closest[i].second};
    return out;
}

namespace {

// The mesh's samples for mesh_to_point_distance: its vertices and face centroids.
std::vector<Vec3> mesh_samples(const Soup& soup)
{
    std::vector<Vec3> samples(soup.positions);
    samples.reserve(soup.positions.size() + soup.triangles.size());
    for (const Triangle& t : soup.triangles)
        samples.push_back((soup.positions[t[0]] + soup.positions[t[1]] + soup.positions[t[2]]) / 3.0);
    return samples;
}

} // namespace

DistanceStats mesh_to_point_distance(const Mesh& mesh, const std::vector<Vec3>& points)
{
    const Soup soup = mesh_to_soup(mesh);
    if (soup.positions.empty())
        return {};
    if (points.empty())
        throw InvalidInput("mesh_to_point_distance: no points given to measure the mesh against");
    const double diagonal = checked_diagonal(points, "mesh_to_point_distance");

    using Traits = CGAL::Search_traits_3<Kernel>;
    using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
    std::vector<CgalPoint> cgal_points;
    cgal_points.reserve(points.size());
    for (const Vec3& p : points)
        cgal_points.push_back(to_cgal(p));
    Search::Tree tree(cgal_points.begin(), cgal_points.end());
    tree.build();

    const std::vector<Vec3> samples = mesh_samples(soup);
    std::vector<double> squared(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
        const Search search(tree, to_cgal(samples[i]), 1);
        squared[i] = search.begin()->second;
    }
    return summarize(squared, diagonal);
}

std::vector<double> squared_nearest_point_distances(const Hierarchy& h, const std::vector<Vec3>& points, const std::vector<Vec3>& queries,
                                                    std::size_t threads, const std::vector<double>* near_enough,
                                                    const std::vector<std::int32_t>* first_nodes)
{
    if (near_enough && near_enough->size() != queries.size())
        throw InvalidInput("squared_nearest_point_distances: " + std::to_string(near_enough->size()) + " near-enough bounds for " +
                           std::to_string(queries.size()) + " queries");
    if (first_nodes && first_nodes->size() != queries.size())
        throw InvalidInput("squared_nearest_point_distances: " + std::to_string(first_nodes->size()) + " first nodes for " +
                           std::to_string(queries.size()) + " queries");
    if (first_nodes)
        for (const std::int32_t id : *first_nodes)
            if (id < -1 || (id >= 0 && static_cast<std::size_t>(id) >= h.nodes.size()))
                throw InvalidInput("squared_nearest_point_distances: first node " + std::to_string(id) + " is no node of the " +
                                   std::to_string(h.nodes.size()) + " of the hierarchy");
    if (points.size() != h.cloud.size() || (h.nodes.empty() && !points.empty()))
        throw InvalidInput("squared_nearest_point_distances: " + std::to_string(points.size()) + " points given for a hierarchy of " +
                           std::to_string(h.cloud.size()) + "; pass its own points (cloud or raw_positions)");
    if (queries.empty())
        return {};
    if (points.empty())
        throw InvalidInput("squared_nearest_point_distances: no points to search");
    // Each node's box around `points`: the stored ones where they are the cloud's positions (the same
    // boxes, exactly: load_model checks it), else computed (raw positions can lie outside them; a pass
    // over every point, which a caller searching a few spots of a 4M-point cloud would mostly spend
    // here). Parents come before children, so backwards every child is done first.
    const bool stored_boxes = &points == &h.cloud.positions;
    std::vector<BoundingBox> computed(stored_boxes ? 0 : h.nodes.size());
    const auto box_of = [&](std::size_t id) -> const BoundingBox& { return stored_boxes ? h.nodes[id].box : computed[id]; };
    for (std::size_t id = computed.size(); id-- > 0;) {
        const Node& n = h.nodes[id];
        BoundingBox& b = computed[id];
        if (n.is_leaf()) {
            b.min = Vec3{1, 1, 1} * std::numeric_limits<double>::infinity();
            b.max = Vec3{1, 1, 1} * -std::numeric_limits<double>::infinity();
            for (std::uint32_t i = n.begin; i < n.end; ++i) {
                b.min = min(b.min, points[i]);
                b.max = max(b.max, points[i]);
            }
        } else {
            const BoundingBox& l = computed[static_cast<std::size_t>(n.left)];
            const BoundingBox& r = computed[static_cast<std::size_t>(n.right)];
            b = {min(l.min, r.min), max(l.max, r.max)};
        }
    }
    std::vector<double> squared(queries.size());
    run_parallel_ranges(queries.size(), 256, threads, [&](std::size_t begin, std::size_t end) {
        std::vector<std::int32_t> stack;
        // Depth first from the nodes on `stack`, nearer child first, lowering `best`; ends at the first
        // leaf that holds a point within `enough`.
        const auto search_from_stack = [&](const Vec3& q, double enough, double& best) {
            while (!stack.empty()) {
                const std::size_t id = static_cast<std::size_t>(stack.back());
                stack.pop_back();
                if (!(box_of(id).squared_distance_to(q) < best))
                    continue;
                const Node& n = h.nodes[id];
                if (n.is_leaf()) {
                    for (std::uint32_t i = n.begin; i < n.end; ++i) {
                        const Vec3 d = points[i] - q;
                        best = std::min(best, d.x * d.x + d.y * d.y + d.z * d.z);
                    }
                    if (best <= enough)
                        return;
                    continue;
                }
                // The nearer child on top, searched first: its points bound the other's. A query on the
                // surface mostly lies inside both boxes (distance 0 to each): then the child whose
                // centre is nearer, which halves the leaves scanned.
                const auto& l = h.nodes[static_cast<std::size_t>(n.left)];
                const auto& r = h.nodes[static_cast<std::size_t>(n.right)];
                const double to_left = box_of(static_cast<std::size_t>(n.left)).squared_distance_to(q);
                const double to_right = box_of(static_cast<std::size_t>(n.right)).squared_distance_to(q);
                const bool left_nearer = to_left < to_right ||
                                         (to_left == to_right && squared_norm(l.centre() - q) <= squared_norm(r.centre() - q));
                stack.push_back(left_nearer ? n.right : n.left);
                stack.push_back(left_nearer ? n.left : n.right);
            }
        };
        for (std::size_t s = begin; s < end; ++s) {
            const Vec3& q = queries[s];
            const double enough = near_enough ? (*near_enough)[s] : -1.0;
            double best = std::numeric_limits<double>::infinity();
            // From the first node's subtree, then (unless a point there was near enough) from the root,
            // with the best found so far bounding it: the same result, and a query on its own tile
            // mostly ends in a leaf of it (a LOD level's vertices: 4 nodes visited instead of 60).
            const std::int32_t first = first_nodes ? (*first_nodes)[s] : -1;
            stack.assign(1, first >= 0 ? first : 0);
            for (bool from_root = first < 0;; from_root = true) {
                search_from_stack(q, enough, best);
                if (from_root || best <= enough)
                    break;
                stack.assign(1, 0);
            }
            squared[s] = best;
        }
    });
    return squared;
}

DistanceStats mesh_to_point_distance(const Mesh& mesh, const Hierarchy& h, const std::vector<Vec3>& points)
{
    const Soup soup = mesh_to_soup(mesh);
    if (soup.positions.empty())
        return {};
    if (points.empty())
        throw InvalidInput("mesh_to_point_distance: no points given to measure the mesh against");
    if (points.size() != h.cloud.size() || h.nodes.empty())
        throw InvalidInput("mesh_to_point_distance: " + std::to_string(points.size()) + " points given for a hierarchy of " +
                           std::to_string(h.cloud.size()) + "; pass its own points (cloud or raw_positions)");
    const double diagonal = checked_diagonal(points, "mesh_to_point_distance");
    const std::vector<double> squared = squared_nearest_point_distances(h, points, mesh_samples(soup), 0);
    return summarize(squared, diagonal);
}

} // namespace mrt
