#pragma once
// Small analytic meshes for the exporter tests: a closed UV sphere and flat/undulating grids whose
// neighbours share their border vertices exactly (as adjacent tiles of a tileset do).
#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace mrt::testing {

inline void add_checked_face(Mesh& mesh, Mesh::VertexHandle a, Mesh::VertexHandle b, Mesh::VertexHandle c)
{
    if (!mesh.add_face(a, b, c).is_valid())
        throw std::logic_error("fixture: OpenMesh refused a face");
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

} // namespace mrt::testing
