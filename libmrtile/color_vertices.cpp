// Beyond the paper (which meshes positions only): the points' colours onto the vertices. Splatting each
// point onto the corners of its closest face, by barycentric weight, is the discrete counterpart of
// sampling the surface's colour where the point lies, and reuses the exact closest-face query the
// quality measures and the fit already trust (CGAL AABB tree, deterministic on any thread count).
#include "libmrtile/color_vertices.h"

#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace mrt {
namespace {

// Barycentric coordinates of q (on or near triangle a, b, c) with respect to its corners, clamped to
// the triangle (the closest point lies on it, rounding aside).
std::array<double, 3> barycentric(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 v0 = b - a, v1 = c - a, v2 = q - a;
    const double d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1), d20 = dot(v2, v0), d21 = dot(v2, v1);
    const double denom = d00 * d11 - d01 * d01;
    if (!(denom > 0.0))
        return {1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0}; // a face without area: share equally
    const double v = std::clamp((d11 * d20 - d01 * d21) / denom, 0.0, 1.0);
    const double w = std::clamp((d00 * d21 - d01 * d20) / denom, 0.0, 1.0 - v);
    return {1.0 - v - w, v, w};
}

} // namespace

std::size_t color_vertices(Mesh& mesh, const PointCloud& cloud, const ColorOptions& options)
{
    // One colour per point or none: fewer were read past their end (QA round 51: 10 colours, 4,000 points).
    if (cloud.has_colors() && cloud.colors.size() != cloud.positions.size())
        throw InvalidInput("color_vertices: the cloud has " + std::to_string(cloud.colors.size()) + " colours for " +
                           std::to_string(cloud.positions.size()) + " points (one per point, or none)");
    if (!options.enabled || !cloud.has_colors() || mesh.n_faces() == 0 || cloud.empty())
        return 0;
    const std::size_t n = mesh.n_vertices();
    const std::size_t stride = sample_stride(cloud.size(), options.points_per_vertex * n);
    std::vector<Vec3> sample; // sample[k] is cloud point k * stride
    for (std::size_t i = 0; i < cloud.size(); i += stride)
        sample.push_back(cloud.positions[i]);
    const std::vector<ClosestPoint> closest = closest_points(sample, mesh, options.threads);

    // Weighted sums per vertex, accumulated in point order (deterministic).
    std::vector<std::array<double, 4>> sum(n, {0.0, 0.0, 0.0, 0.0});
    std::vector<double> weight(n, 0.0);
    for (std::size_t k = 0; k < sample.size(); ++k) {
        const Mesh::FaceHandle f(closest[k].face);
        std::array<Mesh::VertexHandle, 3> corner;
        std::array<Vec3, 3> p;
        int j = 0;
        for (const auto v : mesh.fv_range(f)) {
            corner[static_cast<std::size_t>(j)] = v;
            p[static_cast<std::size_t>(j)] = to_vec3(mesh.point(v));
            ++j;
        }
        const std::array<double, 3> b = barycentric(closest[k].point, p[0], p[1], p[2]);
        const auto& color = cloud.colors[k * stride];
        for (std::size_t c = 0; c < 3; ++c) {
            const auto v = static_cast<std::size_t>(corner[c].idx());
            weight[v] += b[c];
            for (std::size_t ch = 0; ch < 4; ++ch)
                sum[v][ch] += b[c] * color[ch];
        }
    }
    // Vertices no point lent to take the mean of their coloured neighbours, ring by ring.
    std::vector<char> known(n, 0);
    for (std::size_t v = 0; v < n; ++v)
        if (weight[v] > 0.0) {
            for (double& s : sum[v])
                s /= weight[v];
            known[v] = 1;
        }
    for (;;) {
        std::vector<std::size_t> filled;
        for (const auto vh : mesh.vertices()) {
            const auto v = static_cast<std::size_t>(vh.idx());
            if (known[v])
                continue;
            std::array<double, 4> mean{0.0, 0.0, 0.0, 0.0};
            int count = 0;
            for (const auto w : mesh.vv_range(vh))
                if (known[static_cast<std::size_t>(w.idx())]) {
                    for (std::size_t ch = 0; ch < 4; ++ch)
                        mean[ch] += sum[static_cast<std::size_t>(w.idx())][ch];
                    ++count;
                }
            if (count > 0) {
                for (std::size_t ch = 0; ch < 4; ++ch)
                    sum[v][ch] = mean[ch] / count;
                filled.push_back(v);
            }
        }
        if (filled.empty())
            break;
        for (const std::size_t v : filled)
            known[v] = 1;
    }
    mesh.request_vertex_colors();
    for (const auto vh : mesh.vertices()) {
        const auto v = static_cast<std::size_t>(vh.idx());
        Mesh::Color c(128, 128, 128, 255); // a piece no point lies near (not produced by mesh_cut)
        if (known[v])
            for (int ch = 0; ch < 4; ++ch)
                c[ch] = static_cast<unsigned char>(std::lround(std::clamp(sum[v][static_cast<std::size_t>(ch)], 0.0, 255.0)));
        mesh.set_color(vh, c);
    }
    return sample.size();
}

} // namespace mrt
