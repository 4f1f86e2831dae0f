// Output stage, common part of every mesh writer: the half-edge mesh becomes flat arrays in the
// exporter's frame. Done once here so that glTF, Draco-in-glTF and bare .drc agree on vertex order,
// normals and precision handling (float32 relative to a per-file double offset), and so that every
// renderer gets its triangles in GPU-cache order (meshoptimizer is included here and nowhere else in
// the libraries).
#include "formats/mesh_buffers.h"

#include "libmrtile/errors.h"
#include "libmrtile/median.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace mrt {
namespace {

// Triangles in vertex-cache order (those before `split_triangle` and those after apart, each among
// themselves), then vertices in order of first use by them (meshoptimizer), so a GPU transforms each
// vertex about once and reads the vertex buffer front to back.
void reorder_for_gpu(std::vector<std::uint32_t>& indices, std::vector<Mesh::VertexHandle>& used, std::size_t split_triangle)
{
    std::vector<unsigned int> cached(indices.size());
    const std::size_t split = 3 * split_triangle;
    if (split > 0)
        meshopt_optimizeVertexCache(cached.data(), indices.data(), split, used.size());
    if (split < indices.size())
        meshopt_optimizeVertexCache(cached.data() + split, indices.data() + split, indices.size() - split, used.size());
    std::vector<unsigned int> remap(used.size());
    meshopt_optimizeVertexFetchRemap(remap.data(), cached.data(), cached.size(), used.size());
    meshopt_remapIndexBuffer(indices.data(), cached.data(), cached.size(), remap.data());
    std::vector<Mesh::VertexHandle> reordered(used.size());
    for (std::size_t i = 0; i < used.size(); ++i) {
        assert(remap[i] < used.size()); // every vertex in `used` is referenced by some face
        reordered[remap[i]] = used[i];
    }
    used = std::move(reordered);
}

} // namespace

Vec3 to_output_frame(const Vec3& v, UpAxis up)
{
    return up == UpAxis::Z ? Vec3{v.x, v.z, -v.y} : v;
}

Vec3 from_output_frame(const Vec3& v, UpAxis up)
{
    return up == UpAxis::Z ? Vec3{v.x, -v.z, v.y} : v;
}

void check_up_axis(UpAxis up)
{
    if (up != UpAxis::Y && up != UpAxis::Z)
        throw InvalidInput("up_axis " + std::to_string(static_cast<int>(up)) + " is neither UpAxis::Y nor UpAxis::Z");
}

MeshBuffers make_mesh_buffers(const Mesh& mesh, const MeshBufferOptions& options)
{
    check_up_axis(options.up_axis);
    constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
    const bool has_status = mesh.has_vertex_status() && mesh.has_face_status();
    auto face_deleted = [&](Mesh::FaceHandle f) { return has_status && mesh.status(f).deleted(); };
    auto vertex_deleted = [&](Mesh::VertexHandle v) { return has_status && mesh.status(v).deleted(); };

    // Number used vertices in the order of their first use by a face: deterministic, and keeps the
    // index buffer local (good for caches and for Draco's sequential fallback).
    std::vector<std::uint32_t> new_index(mesh.n_vertices(), kUnused);
    std::vector<Mesh::VertexHandle> used;
    MeshBuffers out;
    out.indices.reserve(mesh.n_faces() * 3);
    const std::size_t end_face = std::min(options.end_face, mesh.n_faces());
    for (std::size_t i = options.first_face; i < end_face; ++i) {
        const Mesh::FaceHandle f(static_cast<int>(i));
        if (face_deleted(f))
            continue;
        if (i < options.split_face)
            ++out.split_triangle;
        int corners = 0;
        for (const auto v : mesh.fv_range(f)) {
            if (vertex_deleted(v))
                throw InvalidInput("mesh: face " + std::to_string(f.idx()) + " uses deleted vertex " +
                                   std::to_string(v.idx()) + " (garbage-collect the mesh first)");
            std::uint32_t& id = new_index[static_cast<std::size_t>(v.idx())];
            if (id == kUnused) {
                if (used.size() >= kUnused)
                    throw InvalidInput("mesh: more than 4294967294 vertices");
                id = static_cast<std::uint32_t>(used.size());
                used.push_back(v);
            }
            out.indices.push_back(id);
            ++corners;
        }
        if (corners != 3)
            throw InvalidInput("mesh: face " + std::to_string(f.idx()) + " has " + std::to_string(corners) +
                               " corners, expected a triangle");
    }
    if (out.indices.empty())
        throw InvalidInput("mesh: no faces to write");
    if (options.gpu_order)
        reorder_for_gpu(out.indices, used, out.split_triangle);

    const UpAxis up = options.up_axis;
    std::vector<Vec3> frame_positions(used.size());
    Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
    Vec3 hi = -lo;
    for (std::size_t i = 0; i < used.size(); ++i) {
        const Vec3 p = to_vec3(mesh.point(used[i]));
        if (!is_finite(p))
            throw InvalidInput("mesh: vertex " + std::to_string(used[i].idx()) + " has a non-finite position");
        frame_positions[i] = to_output_frame(p, up);
        lo = min(lo, frame_positions[i]);
        hi = max(hi, frame_positions[i]);
    }
    if (options.offset) {
        out.offset = *options.offset;
    } else {
        const Vec3 c = (lo + hi) * 0.5;
        out.offset = {std::round(c.x), std::round(c.y), std::round(c.z)};
    }

    out.positions.resize(used.size() * 3);
    for (int k = 0; k < 3; ++k) {
        out.min[static_cast<std::size_t>(k)] = std::numeric_limits<float>::infinity();
        out.max[static_cast<std::size_t>(k)] = -std::numeric_limits<float>::infinity();
    }
    for (std::size_t i = 0; i < used.size(); ++i) {
        const Vec3 local = frame_positions[i] - out.offset;
        for (int k = 0; k < 3; ++k) {
            const float value = static_cast<float>(local[k]);
            // A vertex farther than 3.4e38 from the offset became an infinite float in the file. The
            // message names the vertex farthest from the median along the axis, the one set far (QA
            // round 59: with the offset at the box's centre, the first one over was any other vertex).
            if (!std::isfinite(value)) {
                std::vector<double> along(used.size());
                for (std::size_t j = 0; j < used.size(); ++j)
                    along[j] = frame_positions[j][k];
                const double median = upper_median_in_place(along);
                std::size_t far = i;
                for (std::size_t j = 0; j < used.size(); ++j)
                    if (std::abs(frame_positions[j][k] - median) > std::abs(frame_positions[far][k] - median))
                        far = j;
                char distance[32];
                std::snprintf(distance, sizeof distance, "%.6g", frame_positions[far][k] - out.offset[k]);
                throw InvalidInput("mesh: vertex " + std::to_string(used[far].idx()) + " lies " + distance +
                                   " from the offset along an axis, beyond the 3.4e38 a 32-bit float can store");
            }
            const auto ku = static_cast<std::size_t>(k);
            out.positions[i * 3 + ku] = value;
            out.min[ku] = std::min(out.min[ku], value);
            out.max[ku] = std::max(out.max[ku], value);
        }
    }

    if (options.normals) {
        // Area-weighted face normals (unnormalized cross products) of the non-deleted faces, computed
        // only when some used vertex lacks a usable stored normal.
        std::vector<Vec3> normals(used.size());
        std::vector<char> needs_face_normal(used.size(), 0);
        bool any_missing = false;
        for (std::size_t i = 0; i < used.size(); ++i) {
            const Vec3 n = mesh.has_vertex_normals() ? to_vec3(mesh.normal(used[i])) : Vec3{};
            const double length = norm(n);
            if (std::isfinite(length) && length > 1e-300) {
                normals[i] = n / length;
            } else {
                needs_face_normal[i] = 1;
                any_missing = true;
            }
        }
        if (any_missing) {
            std::vector<Vec3> sums(used.size());
            for (std::size_t t = 0; t < out.face_count(); ++t) {
                const std::uint32_t a = out.indices[3 * t], b = out.indices[3 * t + 1], c = out.indices[3 * t + 2];
                const Vec3 pa = to_vec3(mesh.point(used[a]));
                const Vec3 n = cross(to_vec3(mesh.point(used[b])) - pa, to_vec3(mesh.point(used[c])) - pa);
                sums[a] += n;
                sums[b] += n;
                sums[c] += n;
            }
            const Vec3 up_dir = up == UpAxis::Z ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
            for (std::size_t i = 0; i < used.size(); ++i) {
                if (!needs_face_normal[i])
                    continue;
                const double length = norm(sums[i]);
                normals[i] = length > 0.0 && std::isfinite(length) ? sums[i] / length : up_dir;
            }
        }
        out.normals.resize(used.size() * 3);
        for (std::size_t i = 0; i < used.size(); ++i) {
            // Unit length in double, so within 1e-7 of unit in float (validators allow 5e-4).
            const Vec3 n = to_output_frame(normals[i], up);
            for (int k = 0; k < 3; ++k)
                out.normals[i * 3 + static_cast<std::size_t>(k)] = static_cast<float>(n[k]);
        }
    }

    if (options.colors && mesh.has_vertex_colors()) {
        out.colors.resize(used.size() * 4);
        for (std::size_t i = 0; i < used.size(); ++i) {
            const auto& c = mesh.color(used[i]);
            for (std::size_t k = 0; k < 4; ++k)
                out.colors[i * 4 + k] = c[static_cast<int>(k)];
        }
    }
    return out;
}

std::vector<std::uint16_t> linear_colors(const std::vector<std::uint8_t>& srgb)
{
    std::array<std::uint16_t, 256> curve{};
    for (std::size_t c = 0; c < curve.size(); ++c) {
        const double e = static_cast<double>(c) / 255.0;
        const double linear = e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
        curve[c] = static_cast<std::uint16_t>(std::lround(linear * 65535.0));
    }
    std::vector<std::uint16_t> out(srgb.size());
    for (std::size_t i = 0; i < srgb.size(); ++i)
        out[i] = i % 4 == 3 ? static_cast<std::uint16_t>(srgb[i] * 257u) : curve[srgb[i]];
    return out;
}

} // namespace mrt
