#pragma once
// Small analytic meshes for the exporter tests: a closed UV sphere and flat/undulating grids whose
// neighbours share their border vertices exactly (as adjacent tiles of a tileset do).
#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

namespace mrt::testing {

inline void add_checked_face(Mesh& mesh, Mesh::VertexHandle a, Mesh::VertexHandle b, Mesh::VertexHandle c)
{
    if (!mesh.add_face(a, b, c).is_valid())
        throw std::logic_error("fixture: OpenMesh refused a face");
}

//! Gives `mesh` the library's properties (mesh.h) as if it were one tile's fan: every vertex of
//! cluster `node`, every face a fan face (not a gap face) of tile `node`. Added where missing.
inline void mark_as_one_tile(Mesh& mesh, int node)
{
    OpenMesh::VPropHandleT<int> cluster;
    OpenMesh::FPropHandleT<int> tile;
    OpenMesh::FPropHandleT<bool> gap;
    if (!mesh.get_property_handle(cluster, kVertexCluster))
        mesh.add_property(cluster, kVertexCluster);
    if (!mesh.get_property_handle(tile, kFaceTile))
        mesh.add_property(tile, kFaceTile);
    if (!mesh.get_property_handle(gap, kFaceGap))
        mesh.add_property(gap, kFaceGap);
    for (const auto v : mesh.vertices())
        mesh.property(cluster, v) = node;
    for (const auto f : mesh.faces()) {
        mesh.property(tile, f) = node;
        mesh.property(gap, f) = false;
    }
}

//! Closed UV sphere (poles + `rings`-1 parallels of `segments` vertices), outward CCW faces.
//! Vertex normals are left zero so that writers must compute them.
inline Mesh uv_sphere(int rings, int segments, double radius, const Vec3& centre = {}, bool colors = false)
{
    Mesh mesh;
    if (colors)
        mesh.request_vertex_colors();
    auto add = [&](double theta, double phi) {
        const Vec3 p = centre + Vec3{std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)} * radius;
        const auto v = mesh.add_vertex(Mesh::Point(p.x, p.y, p.z));
        mesh.set_normal(v, Mesh::Normal(0, 0, 0));
        if (colors)
            mesh.set_color(v, Mesh::Color(static_cast<unsigned char>(255 * theta / M_PI),
                                          static_cast<unsigned char>(255 * phi / (2 * M_PI)), 128, 255));
        return v;
    };
    const auto north = add(0, 0);
    std::vector<std::vector<Mesh::VertexHandle>> ring(static_cast<std::size_t>(rings - 1));
    for (int r = 1; r < rings; ++r)
        for (int s = 0; s < segments; ++s)
            ring[static_cast<std::size_t>(r - 1)].push_back(add(M_PI * r / rings, 2 * M_PI * s / segments));
    const auto south = add(M_PI, 0);
    const auto n = static_cast<std::size_t>(segments);
    for (std::size_t s = 0; s < n; ++s) {
        const std::size_t t = (s + 1) % n;
        add_checked_face(mesh, north, ring.front()[s], ring.front()[t]);
        for (std::size_t r = 0; r + 1 < ring.size(); ++r) {
            add_checked_face(mesh, ring[r][s], ring[r + 1][s], ring[r + 1][t]);
            add_checked_face(mesh, ring[r][s], ring[r + 1][t], ring[r][t]);
        }
        add_checked_face(mesh, ring.back()[s], south, ring.back()[t]);
    }
    return mesh;
}

//! z = height(x, y) sampled on the (nx+1) x (ny+1) grid starting at (x0, y0) with spacing `step`
//! (z-up, CCW seen from +z). Vertex positions are computed from integer grid coordinates, so two
//! grids sharing a border produce bit-identical border vertices.
template <typename Height>
Mesh grid_mesh(int nx, int ny, double x0, double y0, double step, Height height)
{
    Mesh mesh;
    std::vector<Mesh::VertexHandle> v;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            const double x = x0 + step * i, y = y0 + step * j;
            v.push_back(mesh.add_vertex(Mesh::Point(x, y, height(x, y))));
            mesh.set_normal(v.back(), Mesh::Normal(0, 0, 0));
        }
    auto at = [&](int i, int j) { return v[static_cast<std::size_t>(j * (nx + 1) + i)]; };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            add_checked_face(mesh, at(i, j), at(i + 1, j), at(i + 1, j + 1));
            add_checked_face(mesh, at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    return mesh;
}

inline double wave(double x, double y) { return 0.25 * std::sin(0.7 * x) * std::cos(0.5 * y); }

//! Vertex shader runs per triangle of an index buffer on a GPU modelled as a FIFO cache of 16
//! transformed vertices (the classic ACMR; 0.5 is the ideal of a large regular mesh, 3 the worst).
template <typename Index>
double vertex_cache_misses_per_triangle(const std::vector<Index>& indices, std::size_t vertex_count)
{
    constexpr std::size_t kCache = 16;
    std::vector<std::size_t> stamp(vertex_count, 0); // when the vertex entered the cache, 0 = never
    std::size_t clock = 0, misses = 0;
    for (const Index i : indices)
        if (stamp[i] == 0 || clock - stamp[i] >= kCache) {
            stamp[i] = ++clock; // a miss pushes one entry in; entries older than kCache pushes are gone
            ++misses;
        }
    return indices.empty() ? 0.0 : static_cast<double>(misses) / static_cast<double>(indices.size() / 3);
}

//! \brief How far the triangles of an index buffer are from the faces of `mesh`, whatever their order.
//! \details Each face's corners, mapped by `expected`, are matched with the buffer triangle whose
//! centroid is nearest (a hash grid of cells about a triangle wide) and compared corner by corner, in the face's
//! winding (any rotation): the result is the largest corner distance, infinity when some face has no
//! triangle near it, or when the counts differ.
template <typename Expected>
double worst_triangle_mismatch(const Mesh& mesh, Expected expected, const std::vector<Vec3>& positions,
                               const std::vector<std::size_t>& indices)
{
    if (indices.size() != 3 * mesh.n_faces() || indices.empty())
        return std::numeric_limits<double>::infinity();
    Vec3 lo = positions.at(indices[0]), hi = lo;
    for (const std::size_t i : indices)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], positions.at(i)[a]);
            hi[a] = std::max(hi[a], positions.at(i)[a]);
        }
    const double cell = std::max(norm(hi - lo) / std::sqrt(static_cast<double>(mesh.n_faces())), 1e-12);
    const auto key = [cell](const Vec3& p) {
        return std::array<long long, 3>{static_cast<long long>(std::floor(p.x / cell)), static_cast<long long>(std::floor(p.y / cell)),
                                        static_cast<long long>(std::floor(p.z / cell))};
    };
    std::map<std::array<long long, 3>, std::vector<std::size_t>> grid;
    const auto centroid = [&](std::size_t t) {
        return (positions[indices[3 * t]] + positions[indices[3 * t + 1]] + positions[indices[3 * t + 2]]) / 3.0;
    };
    for (std::size_t t = 0; t < indices.size() / 3; ++t)
        grid[key(centroid(t))].push_back(t);
    double worst = 0;
    for (const auto f : mesh.faces()) {
        std::array<Vec3, 3> corner = face_corners(mesh, f);
        for (Vec3& p : corner)
            p = expected(p);
        const Vec3 c = (corner[0] + corner[1] + corner[2]) / 3.0;
        const auto home = key(c);
        double best = std::numeric_limits<double>::infinity();
        for (long long dx = -1; dx <= 1; ++dx)
            for (long long dy = -1; dy <= 1; ++dy)
                for (long long dz = -1; dz <= 1; ++dz) {
                    const auto it = grid.find({home[0] + dx, home[1] + dy, home[2] + dz});
                    if (it == grid.end())
                        continue;
                    for (const std::size_t t : it->second)
                        for (std::size_t r = 0; r < 3; ++r) {
                            double d = 0;
                            for (std::size_t j = 0; j < 3; ++j)
                                d = std::max(d, norm(positions[indices[3 * t + (j + r) % 3]] - corner[j]));
                            best = std::min(best, d);
                        }
                }
        worst = std::max(worst, best);
    }
    return worst;
}

} // namespace mrt::testing
