// Beyond the paper (§4.3 builds the surface from input points, so it interpolates): the output is
// meant to approximate the sample at a given size, and an interpolating mesh wastes half its error
// budget by lying on one side of a curved surface. Least squares over the vertex heights (one unknown
// per vertex, along its normal) is the cheapest fit that keeps the connectivity, and so every topology
// guarantee of the surface stage; the damping and the move limit keep it a small, safe correction.
// Edge flips (Hoppe et al. 1993's edge swap) then fix the diagonals the T1 fans chose badly: a flip
// changes two faces and never the topology.
#include "libmrtile/fit_vertices.h"

#include "libmrtile/errors.h"
#include "libmrtile/median.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/parallel.h"
#include "libmrtile/point_cloud.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace mrt {
namespace {

struct Csr
{
    std::vector<std::size_t> start; // row v: entries start[v] .. start[v + 1]
    std::vector<int> column;
    std::vector<double> value;

    double& at(int row, int col)
    {
        const auto b = column.begin() + static_cast<std::ptrdiff_t>(start[static_cast<std::size_t>(row)]);
        const auto e = column.begin() + static_cast<std::ptrdiff_t>(start[static_cast<std::size_t>(row) + 1]);
        const auto it = std::lower_bound(b, e, col);
        assert(it != e && *it == col);
        return value[static_cast<std::size_t>(it - column.begin())];
    }
    void multiply(const std::vector<double>& x, std::vector<double>& y) const
    {
        for (std::size_t r = 0; r + 1 < start.size(); ++r) {
            double s = 0.0;
            for (std::size_t k = start[r]; k < start[r + 1]; ++k)
                s += value[k] * x[static_cast<std::size_t>(column[k])];
            y[r] = s;
        }
    }
};

// Rows: each vertex and its one-ring neighbours (the pairs a face can couple), sorted.
Csr vertex_graph(const Mesh& mesh)
{
    Csr m;
    const std::size_t n = mesh.n_vertices();
    m.start.assign(n + 1, 0);
    std::vector<int> row;
    for (std::size_t v = 0; v < n; ++v) {
        const Mesh::VertexHandle vh(static_cast<int>(v));
        row.assign(1, static_cast<int>(v));
        if (!mesh.status(vh).deleted())
            for (const auto w : mesh.vv_range(vh))
                row.push_back(w.idx());
        std::sort(row.begin(), row.end());
        row.erase(std::unique(row.begin(), row.end()), row.end());
        m.column.insert(m.column.end(), row.begin(), row.end());
        m.start[v + 1] = m.column.size();
    }
    m.value.assign(m.column.size(), 0.0);
    return m;
}

// Jacobi-preconditioned conjugate gradients, sequential (so the result is the same on every run).
std::vector<double> solve(const Csr& m, const std::vector<double>& b)
{
    const std::size_t n = b.size();
    std::vector<double> x(n, 0.0), r = b, z(n), p(n), q(n), inverse_diagonal(n, 1.0);
    for (std::size_t v = 0; v < n; ++v)
        for (std::size_t k = m.start[v]; k < m.start[v + 1]; ++k)
            if (static_cast<std::size_t>(m.column[k]) == v && m.value[k] > 0.0)
                inverse_diagonal[v] = 1.0 / m.value[k];
    auto dot_n = [&](const std::vector<double>& a, const std::vector<double>& c) {
        double s = 0.0;
        for (std::size_t i = 0; i < n; ++i)
            s += a[i] * c[i];
        return s;
    };
    for (std::size_t i = 0; i < n; ++i)
        z[i] = inverse_diagonal[i] * r[i];
    p = z;
    double rz = dot_n(r, z);
    // A residual a millionth of the start is far below what the points can tell apart.
    const double stop = 1e-12 * std::max(rz, std::numeric_limits<double>::min());
    for (int iteration = 0; iteration < 500 && rz > stop; ++iteration) {
        m.multiply(p, q);
        const double pq = dot_n(p, q);
        if (!(pq > 0.0))
            break;
        const double step = rz / pq;
        for (std::size_t i = 0; i < n; ++i) {
            x[i] += step * p[i];
            r[i] -= step * q[i];
            z[i] = inverse_diagonal[i] * r[i];
        }
        const double rz_next = dot_n(r, z);
        const double beta = rz_next / rz;
        rz = rz_next;
        for (std::size_t i = 0; i < n; ++i)
            p[i] = z[i] + beta * p[i];
    }
    return x;
}

// Each vertex's shortest incident edge (infinity for a vertex without edges).
std::vector<double> shortest_edges(const Mesh& mesh)
{
    std::vector<double> shortest(mesh.n_vertices(), std::numeric_limits<double>::infinity());
    for (const auto e : mesh.edges()) {
        const auto h = mesh.halfedge_handle(e, 0);
        const auto a = static_cast<std::size_t>(mesh.from_vertex_handle(h).idx());
        const auto c = static_cast<std::size_t>(mesh.to_vertex_handle(h).idx());
        const double length = mesh.calc_edge_length(e);
        shortest[a] = std::min(shortest[a], length);
        shortest[c] = std::min(shortest[c], length);
    }
    return shortest;
}

// Unit directions the vertices move along: area-weighted normals, or `axis` for a vertical fit.
std::vector<Vec3> move_directions(const Mesh& mesh, bool vertical, const Vec3& axis)
{
    std::vector<Vec3> d(mesh.n_vertices(), vertical ? axis : Vec3{});
    if (vertical)
        return d;
    for (const auto f : mesh.faces()) {
        const std::array<Vec3, 3> p = face_corners(mesh, f);
        const Vec3 area_normal = cross(p[1] - p[0], p[2] - p[0]);
        for (const auto v : mesh.fv_range(f))
            d[static_cast<std::size_t>(v.idx())] = d[static_cast<std::size_t>(v.idx())] + area_normal;
    }
    for (Vec3& x : d)
        x = squared_norm(x) > 0.0 ? normalized(x) : Vec3{};
    return d;
}

// The points whose closest face is one face: a stretch of PointsByFace::ids.
struct IdRange
{
    const std::uint32_t* first = nullptr;
    const std::uint32_t* last = nullptr;
    const std::uint32_t* begin() const { return first; }
    const std::uint32_t* end() const { return last; }
    std::size_t size() const { return static_cast<std::size_t>(last - first); }
    bool empty() const { return first == last; }
};

// The points on each face, in increasing order, as compressed rows (one allocation, not one per face:
// the fit asks for them every round).
struct PointsByFace
{
    std::vector<std::size_t> start; // face f: ids[start[f] .. start[f + 1]]
    std::vector<std::uint32_t> ids;

    PointsByFace(std::size_t faces, const std::vector<ClosestPoint>& closest) : start(faces + 1, 0), ids(closest.size())
    {
        for (const ClosestPoint& c : closest)
            ++start[static_cast<std::size_t>(c.face) + 1];
        for (std::size_t f = 0; f < faces; ++f)
            start[f + 1] += start[f];
        std::vector<std::size_t> fill(start.begin(), start.end() - 1);
        for (std::size_t i = 0; i < closest.size(); ++i)
            ids[fill[static_cast<std::size_t>(closest[i].face)]++] = static_cast<std::uint32_t>(i);
    }
    IdRange on(std::size_t f) const { return {ids.data() + start[f], ids.data() + start[f + 1]}; }
};

// Sum over the points of both lists of the squared distance to the nearer of two triangles.
double squared_error(const std::vector<Vec3>& points, const IdRange& ids0, const IdRange& ids1,
                     const std::array<Vec3, 3>& t0, const std::array<Vec3, 3>& t1)
{
    double sum = 0.0;
    for (const IdRange* ids : {&ids0, &ids1})
        for (std::uint32_t i : *ids) {
            const Vec3& p = points[i];
            sum += std::min(squared_distance(p, closest_point_on_triangle(p, t0[0], t0[1], t0[2])),
                            squared_distance(p, closest_point_on_triangle(p, t1[0], t1[1], t1[2])));
        }
    return sum;
}

// Flips the edges whose two faces fit their points better the other way round (Hoppe et al.'s edge
// swap): fans are stars of long wedges around their apex, and on a curved tile the diagonal the fan
// chose is often the worse one. A flip keeps the surface an oriented 2-manifold (OpenMesh's is_flip_ok:
// not on the border, the other diagonal not already an edge) and must not fold: both new faces keep
// within 60 degrees of the old pair's normal. The two faces of a flip are not touched again in the
// pass (their points are stale). On a mesh with tile ids (mesh.h), a flipped face keeps its tile id only
// if both faces had the same one, and becomes a gap face otherwise.
std::size_t flip_edges(Mesh& mesh, const std::vector<Vec3>& points, const std::vector<ClosestPoint>& closest, const Vec3* up,
                       const std::vector<Mesh::Point>& start_position, double max_angle)
{
    OpenMesh::FPropHandleT<int> tile;
    OpenMesh::FPropHandleT<bool> gap;
    const bool has_tiles = mesh.get_property_handle(tile, kFaceTile) && mesh.get_property_handle(gap, kFaceGap);
    const PointsByFace on_face(mesh.n_faces(), closest);
    std::vector<bool> done(mesh.n_faces(), false);
    const double min_cos = 0.5;
    std::size_t flips = 0;
    for (const auto e : mesh.edges()) {
        if (mesh.is_boundary(e) || !mesh.is_flip_ok(e))
            continue;
        const auto h0 = mesh.halfedge_handle(e, 0), h1 = mesh.halfedge_handle(e, 1);
        const auto f0 = mesh.face_handle(h0), f1 = mesh.face_handle(h1);
        if (done[static_cast<std::size_t>(f0.idx())] || done[static_cast<std::size_t>(f1.idx())])
            continue;
        const IdRange ids0 = on_face.on(static_cast<std::size_t>(f0.idx()));
        const IdRange ids1 = on_face.on(static_cast<std::size_t>(f1.idx()));
        if (ids0.empty() && ids1.empty())
            continue;
        // h0 = a -> b in f0 = (a, b, c); h1 = b -> a in f1 = (b, a, d); flipped: (c, a, d) and (d, b, c).
        const Vec3 a = to_vec3(mesh.point(mesh.from_vertex_handle(h0))), b = to_vec3(mesh.point(mesh.to_vertex_handle(h0)));
        const Vec3 c = to_vec3(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h0))));
        const Vec3 d = to_vec3(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h1))));
        const std::array<Vec3, 3> old0{a, b, c}, old1{b, a, d}, new0{c, a, d}, new1{d, b, c};
        // Never flip to a face without area, here or where the vertices started: the self-intersection
        // check may put them back (three points of one straight hull edge are collinear there).
        const auto start = [&](Mesh::VertexHandle vh) { return to_vec3(start_position[static_cast<std::size_t>(vh.idx())]); };
        const Vec3 sa = start(mesh.from_vertex_handle(h0)), sb = start(mesh.to_vertex_handle(h0));
        const Vec3 sc = start(mesh.to_vertex_handle(mesh.next_halfedge_handle(h0)));
        const Vec3 sd = start(mesh.to_vertex_handle(mesh.next_halfedge_handle(h1)));
        if (!has_area(c, a, d) || !has_area(d, b, c) || !has_area(sc, sa, sd) || !has_area(sd, sb, sc))
            continue;
        const Vec3 n_old = normalized(cross(b - a, c - a) + cross(a - b, d - b));
        const Vec3 n0 = normalized(cross(a - c, d - c)), n1 = normalized(cross(b - d, c - d));
        if (!(dot(n0, n_old) > min_cos) || !(dot(n1, n_old) > min_cos))
            continue;
        if (up && (!(dot(n0, *up) > 0.0) || !(dot(n1, *up) > 0.0)))
            continue; // a height field stays a graph
        // No flip makes a cap (a face with an angle near 180 degrees) that was not there: its normal
        // is noise, and a cap fits a ridge of points only as a crease that shading shows.
        // (The old faces' angles matter only when the new ones pass max_angle: most flips stop there.)
        const double new_angle = std::max(largest_angle(c, a, d), largest_angle(d, b, c));
        if (new_angle > max_angle && new_angle > std::max(largest_angle(a, b, c), largest_angle(b, a, d)))
            continue;
        const double before = squared_error(points, ids0, ids1, old0, old1);
        const double after = squared_error(points, ids0, ids1, new0, new1);
        // Rounding is not a misfit: in a flat part both errors are ~1e-30 and a flip on their noise
        // only spreads an in-plane fold (an L-shaped plate: 2 crossing pairs became 23).
        const double noise = 1e-12 * dot(b - a, b - a) * static_cast<double>(ids0.size() + ids1.size());
        if (!(after < 0.98 * before) || !(before - after > noise))
            continue;
        const bool same_tile = !has_tiles || mesh.property(tile, f0) == mesh.property(tile, f1);
        mesh.flip(e);
        if (!same_tile) {
            mesh.property(tile, f0) = mesh.property(tile, f1) = -1;
            mesh.property(gap, f0) = mesh.property(gap, f1) = true;
        }
        done[static_cast<std::size_t>(f0.idx())] = done[static_cast<std::size_t>(f1.idx())] = true;
        ++flips;
    }
    return flips;
}

// The closest point to each point among the faces around its previous closest face: from that face,
// step to the nearest face sharing an edge with it while that is closer (at most a few steps). Not
// exact in general (a local minimum), exact enough for the assignment of a least-squares fit after
// small moves, and several times cheaper than a tree query. Fixed chunks: independent of the threads.
std::vector<ClosestPoint> nearby_closest_points(const Mesh& mesh, const std::vector<Vec3>& points,
                                                const std::vector<ClosestPoint>& previous, std::size_t threads)
{
    std::vector<ClosestPoint> out(points.size());
    constexpr int kMaxSteps = 16;
    run_parallel_ranges(points.size(), 4096, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const Vec3& p = points[i];
            auto closest_on = [&](Mesh::FaceHandle f) {
                const std::array<Vec3, 3> t = face_corners(mesh, f);
                return closest_point_on_triangle(p, t[0], t[1], t[2]);
            };
            Mesh::FaceHandle best(previous[i].face);
            Vec3 at = closest_on(best);
            double d = squared_distance(p, at);
            Mesh::FaceHandle came_from; // the face of the step before: farther than `best`, not asked again
            for (int step = 0; step < kMaxSteps; ++step) {
                Mesh::FaceHandle next = best;
                for (const auto g : mesh.ff_range(best)) {
                    if (g == came_from)
                        continue;
                    const Vec3 q = closest_on(g);
                    const double e = squared_distance(p, q);
                    if (e < d) {
                        d = e;
                        at = q;
                        next = g;
                    }
                }
                if (next == best)
                    break;
                came_from = best;
                best = next;
            }
            out[i] = {best.idx(), at};
        }
    });
    return out;
}

// Which points are strays (FitOptions::stray_reach): farther from the plane of their closest face than
// kStrayResiduals times the median distance of the points on that face and its neighbours (at least
// kStrayFloor of its longest edge, so that exactly planar parts, whose median is 0, keep every point
// within a fraction of an edge), or than stray_reach times its longest edge. The median is local: a
// coarse mesh stands off a curved part or a sharp edge by much of an edge, and all the points there
// with it.
constexpr double kStrayResiduals = 8.0;
constexpr double kStrayFloor = 0.1;

std::vector<char> stray_points(const Mesh& mesh, const std::vector<Vec3>& points, const std::vector<ClosestPoint>& closest,
                               double stray_reach)
{
    if (!(stray_reach > 0.0))
        return {};
    const std::size_t faces = mesh.n_faces();
    std::vector<Vec3> normal(faces);
    std::vector<double> longest(faces, 0.0);
    for (const auto f : mesh.faces()) {
        std::array<Vec3, 3> p;
        int k = 0;
        for (const auto vh : mesh.fv_range(f))
            p[static_cast<std::size_t>(k++)] = to_vec3(mesh.point(vh));
        const Vec3 area_normal = cross(p[1] - p[0], p[2] - p[0]);
        normal[static_cast<std::size_t>(f.idx())] = squared_norm(area_normal) > 0.0 ? normalized(area_normal) : Vec3{};
        longest[static_cast<std::size_t>(f.idx())] =
            std::sqrt(std::max({squared_norm(p[1] - p[0]), squared_norm(p[2] - p[1]), squared_norm(p[0] - p[2])}));
    }
    std::vector<double> off(points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        off[i] = std::abs(dot(normal[static_cast<std::size_t>(closest[i].face)], closest[i].point - points[i]));
    const PointsByFace on_face(faces, closest);
    std::vector<char> stray(points.size(), 0);
    std::vector<double> near;
    for (const auto f : mesh.faces()) {
        const auto fi = static_cast<std::size_t>(f.idx());
        if (on_face.on(fi).empty())
            continue;
        near.clear();
        for (const std::uint32_t i : on_face.on(fi))
            near.push_back(off[i]);
        for (const auto g : mesh.ff_range(f))
            for (const std::uint32_t i : on_face.on(static_cast<std::size_t>(g.idx())))
                near.push_back(off[i]);
        const double typical = std::max(upper_median_in_place(near), kStrayFloor * longest[fi]);
        const double reach = std::min(stray_reach * longest[fi], kStrayResiduals * typical);
        for (const std::uint32_t i : on_face.on(fi))
            stray[i] = off[i] > reach;
    }
    return stray;
}

// The damped least-squares system over the vertex heights t (one per vertex, along `direction`): each
// point adds the square of its signed distance to the plane of its closest face, linear in the heights
// of that face's corners through the barycentric coordinates of its closest point (point-to-plane, as in
// ICP); strays (stray_points) add nothing. Damping: a fraction of the mean diagonal on every vertex.
// False if no point constrains anything.
bool normal_equations(const Mesh& mesh, const std::vector<Vec3>& points, const std::vector<ClosestPoint>& closest,
                      const std::vector<Vec3>& direction, double damping, const std::vector<char>& stray, Csr& m, std::vector<double>& b)
{
    const std::size_t n = mesh.n_vertices();
    m = vertex_graph(mesh);
    b.assign(n, 0.0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!stray.empty() && stray[i])
            continue;
        const Mesh::FaceHandle f(closest[i].face);
        std::array<int, 3> v{};
        std::array<Vec3, 3> p;
        int k = 0;
        for (const auto vh : mesh.fv_range(f)) {
            v[static_cast<std::size_t>(k)] = vh.idx();
            p[static_cast<std::size_t>(k++)] = to_vec3(mesh.point(vh));
        }
        const Vec3 area_normal = cross(p[1] - p[0], p[2] - p[0]);
        const double twice_area = norm(area_normal);
        if (!(twice_area > 0.0))
            continue;
        const Vec3 normal = area_normal / twice_area;
        // Barycentric coordinates of the closest point (on the face, so all in [0, 1]).
        const Vec3 c = closest[i].point;
        std::array<double, 3> l{norm(cross(p[1] - c, p[2] - c)) / twice_area, norm(cross(p[2] - c, p[0] - c)) / twice_area, 0.0};
        l[2] = std::max(0.0, 1.0 - l[0] - l[1]);
        std::array<double, 3> a{};
        for (std::size_t j = 0; j < 3; ++j)
            a[j] = l[j] * dot(normal, direction[static_cast<std::size_t>(v[j])]);
        const double residual = dot(normal, c - points[i]);
        for (std::size_t j = 0; j < 3; ++j) {
            b[static_cast<std::size_t>(v[j])] -= a[j] * residual;
            for (std::size_t q = 0; q < 3; ++q)
                m.at(v[j], v[q]) += a[j] * a[q];
        }
    }
    double diagonal_sum = 0.0;
    std::size_t constrained = 0;
    for (std::size_t v = 0; v < n; ++v) {
        const double d = m.at(static_cast<int>(v), static_cast<int>(v));
        if (d > 0.0) {
            diagonal_sum += d;
            ++constrained;
        }
    }
    if (constrained == 0)
        return false;
    const double mu = damping * diagonal_sum / static_cast<double>(constrained);
    for (std::size_t v = 0; v < n; ++v)
        m.at(static_cast<int>(v), static_cast<int>(v)) += mu;
    return true;
}

// Moves every vertex by its height along its direction, at most `max_move` × its shortest edge (edge
// lengths taken before any move of this round, or before the fit's first round if shorter). A face whose normal would turn by more than 60° (a thin
// gap face whose corners move apart along different normals can fold over its neighbours) halves the
// moves of its corners, up to kMaxHalvings times, then keeps them still.
void move_vertices(Mesh& mesh, const std::vector<double>& heights, const std::vector<Vec3>& direction, double max_move,
                   const std::vector<double>& start_shortest, FitStats& stats, double& moved_sum, std::size_t& moved_count)
{
    constexpr int kMaxHalvings = 6;
    const double min_cos = 0.5;
    const std::size_t n = mesh.n_vertices();
    const std::vector<double> shortest = shortest_edges(mesh);
    std::vector<double> move(n, 0.0);
    for (const auto vh : mesh.vertices()) {
        const std::size_t v = static_cast<std::size_t>(vh.idx());
        if (!std::isfinite(shortest[v]))
            continue;
        // Edge lengths as they were before the first round bound every round too: a vertex moving
        // away from its neighbours lengthens its edges, and a limit taken from them alone grew round by
        // round (on ten points of a sphere one vertex went 1.5 diagonals out in three rounds).
        const double limit = max_move * std::min(shortest[v], start_shortest[v]);
        move[v] = std::isfinite(heights[v]) ? heights[v] : 0.0;
        if (std::abs(move[v]) > limit) {
            move[v] = std::copysign(limit, move[v]);
            ++stats.clamped;
        }
    }
    auto moved = [&](Mesh::VertexHandle vh) {
        const std::size_t v = static_cast<std::size_t>(vh.idx());
        return to_vec3(mesh.point(vh)) + direction[v] * move[v];
    };
    for (int pass = 0; pass <= kMaxHalvings; ++pass) {
        std::vector<bool> damp(n, false);
        bool any = false;
        for (const auto f : mesh.faces()) {
            std::array<Vec3, 3> before, after;
            std::array<std::size_t, 3> corner{};
            std::size_t k = 0;
            for (const auto vh : mesh.fv_range(f)) {
                corner[k] = static_cast<std::size_t>(vh.idx());
                before[k] = to_vec3(mesh.point(vh));
                after[k++] = moved(vh);
            }
            const Vec3 n0 = normalized(cross(before[1] - before[0], before[2] - before[0]));
            const Vec3 n1 = normalized(cross(after[1] - after[0], after[2] - after[0]));
            if (dot(n0, n1) < min_cos && squared_norm(n0) > 0.0) {
                for (std::size_t c : corner)
                    damp[c] = damp[c] || move[c] != 0.0;
                any = any || move[corner[0]] != 0.0 || move[corner[1]] != 0.0 || move[corner[2]] != 0.0;
            }
        }
        if (!any)
            break;
        for (std::size_t v = 0; v < n; ++v)
            if (damp[v])
                move[v] = pass < kMaxHalvings ? 0.5 * move[v] : 0.0;
    }
    for (const auto vh : mesh.vertices()) {
        const std::size_t v = static_cast<std::size_t>(vh.idx());
        mesh.point(vh) += Mesh::Point(direction[v].x, direction[v].y, direction[v].z) * move[v];
        moved_sum += std::abs(move[v]);
        ++moved_count;
    }
}

// Puts the corners of self-intersecting faces back where the fit found them, while that changes
// something (at most kMaxPasses tests). The first test covers the faces near vertices that moved by more
// than a tenth of their shortest edge (two rings of faces around them: smaller moves hardly carry a face
// through another one that was clear of it), each later one only the faces near what the previous one put
// back. Pairs the surface had before the fit stay: their corners are already at their start. Returns the
// number of vertices put back.
std::size_t revert_intersecting(Mesh& mesh, const std::vector<Mesh::Point>& start_position, FitStats& stats)
{
    constexpr int kMaxPasses = 4;
    constexpr double kSignificantMove = 0.1;
    std::vector<bool> near(mesh.n_faces(), false);
    auto mark_around = [&](Mesh::VertexHandle vh) { // faces at the vertex and at its neighbours: two rings
        for (const auto w : mesh.vv_range(vh))
            for (const auto f : mesh.vf_range(w))
                near[static_cast<std::size_t>(f.idx())] = true;
    };
    const std::vector<double> shortest = shortest_edges(mesh);
    for (const auto vh : mesh.vertices()) {
        const auto v = static_cast<std::size_t>(vh.idx());
        if ((mesh.point(vh) - start_position[v]).norm() > kSignificantMove * shortest[v])
            mark_around(vh);
    }
    // The first pass tests the whole mesh (it costs the same as testing the faces near moved vertices,
    // which are nearly all of them), acts on the pairs among those faces only, and keeps every pair:
    // with the faces the reverts change since, they give the pairs at the end (FitStats::pairs_known).
    std::vector<std::pair<int, int>> all_pairs;
    std::vector<char> changed(mesh.n_faces(), 0);
    std::size_t reverted = 0;
    for (int pass = 0; pass < kMaxPasses; ++pass) {
        std::vector<int> among;
        for (std::size_t f = 0; f < near.size(); ++f)
            if (near[f])
                among.push_back(static_cast<int>(f));
        if (among.empty())
            break;
        std::vector<std::pair<int, int>> pairs;
        if (pass == 0) {
            all_pairs = self_intersecting_faces(mesh);
            stats.pairs_known = true;
            for (const auto& p : all_pairs)
                if (near[static_cast<std::size_t>(p.first)] && near[static_cast<std::size_t>(p.second)])
                    pairs.push_back(p);
        } else {
            pairs = self_intersecting_faces(mesh, &among);
        }
        std::fill(near.begin(), near.end(), false); // the next pass looks only around what this one moves
        for (const auto& [a, b] : pairs)
            for (const int f : {a, b})
                for (const auto vh : mesh.fv_range(Mesh::FaceHandle(f))) {
                    const Mesh::Point& start = start_position[static_cast<std::size_t>(vh.idx())];
                    if (mesh.point(vh) != start) {
                        mesh.point(vh) = start;
                        mark_around(vh);
                        for (const auto g : mesh.vf_range(vh))
                            changed[static_cast<std::size_t>(g.idx())] = 1;
                        ++reverted;
                    }
                }
    }
    if (stats.pairs_known) {
        // Pairs of unchanged faces are as they were; any other pair has a changed face.
        std::vector<int> moved;
        for (std::size_t f = 0; f < changed.size(); ++f)
            if (changed[f])
                moved.push_back(static_cast<int>(f));
        for (const auto& p : all_pairs)
            if (!changed[static_cast<std::size_t>(p.first)] && !changed[static_cast<std::size_t>(p.second)])
                stats.intersecting_pairs.push_back(p);
        for (const auto& p : intersecting_pairs_with(mesh, moved))
            stats.intersecting_pairs.push_back(p);
        std::sort(stats.intersecting_pairs.begin(), stats.intersecting_pairs.end());
        stats.intersecting_pairs.erase(std::unique(stats.intersecting_pairs.begin(), stats.intersecting_pairs.end()),
                                       stats.intersecting_pairs.end());
    }
    return reverted;
}

} // namespace

void check_fit_options(const FitOptions& options)
{
    // max_flip_angle_degrees too: a NaN or negative limit was taken without a word (NaN refused no cap).
    if (options.rounds < 0 || options.rounds > kMaxFitRounds || !(options.damping > 0.0) || !(options.max_move >= 0.0) || !std::isfinite(options.damping) ||
        !std::isfinite(options.max_move) || (options.vertical && !(squared_norm(options.axis) > 0.0)) ||
        !(options.max_flip_angle_degrees >= 0.0 && options.max_flip_angle_degrees <= 180.0) ||
        !(options.stray_reach >= 0.0) || !std::isfinite(options.stray_reach))
        throw InvalidInput("fit_vertices: rounds must be in [0, " + std::to_string(kMaxFitRounds) + "], damping > 0, max_move >= 0 (finite), "
                           "max_flip_angle_degrees in [0, 180], stray_reach >= 0 (finite), and a vertical fit needs a non-zero axis");
    // The relaxation runs inside every round: checked here, not only once a round relaxes.
    check_relax_options(options.relax);
}

FitStats fit_vertices(Mesh& mesh, const std::vector<Vec3>& points, const FitOptions& options)
{
    check_fit_options(options);
    // A NaN vertex stayed NaN without a word (QA round 59), where the points are checked.
    if (const Mesh::VertexHandle vh = first_non_finite_vertex(mesh); vh.is_valid())
        throw InvalidInput("fit_vertices: vertex " + std::to_string(vh.idx()) + " has a NaN or infinite coordinate");
    const auto start = std::chrono::steady_clock::now();
    FitStats stats;
    if (options.rounds == 0 || points.empty() || mesh.n_faces() == 0 || options.max_move == 0.0)
        return stats;
    const std::size_t n = mesh.n_vertices();
    const std::size_t stride = sample_stride(points.size(), options.points_per_vertex * n);
    std::vector<Vec3> sample;
    if (stride > 1) {
        sample.reserve(points.size() / stride + 1);
        for (std::size_t i = 0; i < points.size(); i += stride)
            sample.push_back(points[i]);
    }
    const std::vector<Vec3>& used = stride > 1 ? sample : points;
    stats.points = used.size();
    double moved_sum = 0.0;
    std::size_t moved_count = 0;
    std::vector<Mesh::Point> start_position(n);
    for (const auto vh : mesh.vertices())
        start_position[static_cast<std::size_t>(vh.idx())] = mesh.point(vh);
    const std::vector<double> start_shortest = shortest_edges(mesh);
    std::vector<ClosestPoint> closest;
    // A vertical fit keeps a height field a graph: so does its relaxation.
    RelaxOptions relax = options.relax;
    if (options.vertical) {
        relax.vertical = true;
        relax.axis = options.axis;
    }
    for (int round = 0; round < options.rounds; ++round) {
        const RelaxStats relaxed = relax_vertices(mesh, relax);
        stats.relax.moves += relaxed.moves;
        stats.relax.creases = relaxed.creases;
        stats.relax.refused += relaxed.refused;
        // The first round asks the AABB tree; later ones walk from the previous face, since vertices
        // moved by a fraction of an edge (relaxed by less than half of one) and flips keep their faces'
        // handles.
        closest = round == 0 ? closest_points(used, mesh, options.threads) : nearby_closest_points(mesh, used, closest, options.threads);
        const std::vector<Vec3> direction = move_directions(mesh, options.vertical, normalized(options.axis));
        Csr system;
        std::vector<double> rhs;
        const std::vector<char> stray = stray_points(mesh, used, closest, options.stray_reach);
        if (!normal_equations(mesh, used, closest, direction, options.damping, stray, system, rhs))
            break; // no point constrains any vertex
        const std::vector<double> heights = solve(system, rhs);
        move_vertices(mesh, heights, direction, options.max_move, start_shortest, stats, moved_sum, moved_count);
        if (options.flip_edges) {
            const Vec3 up = normalized(options.axis);
            stats.flips += flip_edges(mesh, used, closest, options.vertical ? &up : nullptr, start_position,
                                      radians(options.max_flip_angle_degrees));
        }
        ++stats.rounds;
    }
    if (options.revert_intersections)
        stats.reverted = revert_intersecting(mesh, start_position, stats);
    stats.mean_move = moved_count > 0 ? moved_sum / static_cast<double>(moved_count) : 0.0;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    mesh.update_normals();
    return stats;
}

} // namespace mrt
