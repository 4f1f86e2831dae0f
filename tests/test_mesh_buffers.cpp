// Tests of mesh_buffers.h: axis mapping, per-file offset, deleted elements, normals and colours.
// OpenMesh copies a default-constructed (uninitialized) VectorT when a vertex is added; the fixtures set
// every value they use right after, so GCC's warning about that copy does not apply.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "formats/mesh_buffers.h"
#include "libmrtile/errors.h"
#include "mesh_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mrt {
namespace {

using testing::grid_mesh;
using testing::uv_sphere;

TEST(MeshBuffers, z_up_rotates_into_y_up_and_back)
{
    const Vec3 p{1, 2, 3};
    EXPECT_EQ(to_output_frame(p, UpAxis::Z), (Vec3{1, 3, -2}));
    EXPECT_EQ(to_output_frame(p, UpAxis::Y), p);
    EXPECT_EQ(from_output_frame(to_output_frame(p, UpAxis::Z), UpAxis::Z), p);
    // A proper rotation (determinant +1): x cross y still gives z, so faces keep their winding.
    const Vec3 x = to_output_frame({1, 0, 0}, UpAxis::Z), y = to_output_frame({0, 1, 0}, UpAxis::Z);
    EXPECT_EQ(cross(x, y), to_output_frame({0, 0, 1}, UpAxis::Z));
}

TEST(MeshBuffers, positions_relative_to_rounded_centre)
{
    const Mesh mesh = uv_sphere(8, 12, 2.0, {10.4, -3.6, 7.0});
    MeshBufferOptions in_face_order;
    in_face_order.gpu_order = false; // so that buffer triangle f is mesh face f
    const MeshBuffers b = make_mesh_buffers(mesh, in_face_order);
    EXPECT_EQ(b.offset, (Vec3{10, 7, 4})); // centre (10.4, -3.6, 7) in y-up is (10.4, 7, 3.6)
    ASSERT_EQ(b.vertex_count(), mesh.n_vertices());
    ASSERT_EQ(b.face_count(), mesh.n_faces());
    std::array<float, 3> lo{1e9f, 1e9f, 1e9f}, hi{-1e9f, -1e9f, -1e9f};
    // Vertices are numbered by first use, so compare as sets via the face corners.
    for (std::size_t f = 0; f < b.face_count(); ++f) {
        std::size_t k = 0;
        for (const auto v : mesh.fv_range(mesh.face_handle(static_cast<int>(f)))) {
            const auto& p = mesh.point(v);
            const Vec3 expected = to_output_frame({p[0], p[1], p[2]}, UpAxis::Z) - b.offset;
            const std::uint32_t i = b.indices[3 * f + k++];
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(b.positions[3 * i + static_cast<std::size_t>(c)], static_cast<float>(expected[c]));
        }
    }
    for (std::size_t i = 0; i < b.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], b.positions[i]);
        hi[i % 3] = std::max(hi[i % 3], b.positions[i]);
    }
    EXPECT_EQ(b.min, lo);
    EXPECT_EQ(b.max, hi);
}

// The GPU order: the same triangles in the same winding, vertices numbered by first use, and fewer
// vertex shader runs per triangle than a scattered face order (a FIFO cache model of our own).
TEST(MeshBuffers, gpu_order_keeps_the_triangles_and_improves_the_vertex_cache)
{
    Mesh mesh = grid_mesh(60, 60, 0.0, 0.0, 1.0, testing::wave);
    // A face order without locality: face k * 7919 mod n (7919 is a prime that does not divide n).
    std::vector<std::array<Mesh::VertexHandle, 3>> faces;
    for (const auto f : mesh.faces()) {
        std::array<Mesh::VertexHandle, 3> corners;
        int k = 0;
        for (const auto v : mesh.fv_range(f))
            corners[static_cast<std::size_t>(k++)] = v;
        faces.push_back(corners);
    }
    Mesh shuffled;
    for (const auto v : mesh.vertices()) {
        shuffled.add_vertex(mesh.point(v));
        shuffled.set_normal(shuffled.vertex_handle(static_cast<unsigned>(v.idx())), Mesh::Normal(0, 0, 0));
    }
    std::vector<std::size_t> order;
    for (std::size_t k = 0; k < faces.size(); ++k)
        order.push_back(k * 7919 % faces.size());
    for (const std::size_t f : order) {
        std::array<Mesh::VertexHandle, 3> c;
        for (std::size_t k = 0; k < 3; ++k)
            c[k] = shuffled.vertex_handle(static_cast<unsigned>(faces[f][k].idx()));
        testing::add_checked_face(shuffled, c[0], c[1], c[2]);
    }
    ASSERT_EQ(shuffled.n_faces(), mesh.n_faces());
    MeshBufferOptions plain;
    plain.gpu_order = false;
    const MeshBuffers before = make_mesh_buffers(shuffled, plain);
    const MeshBuffers after = make_mesh_buffers(shuffled);
    ASSERT_EQ(after.vertex_count(), before.vertex_count());
    std::vector<Vec3> positions(after.vertex_count());
    for (std::size_t i = 0; i < positions.size(); ++i)
        positions[i] = Vec3{after.positions[3 * i], after.positions[3 * i + 1], after.positions[3 * i + 2]} + after.offset;
    const std::vector<std::size_t> corners(after.indices.begin(), after.indices.end());
    EXPECT_LT(testing::worst_triangle_mismatch(shuffled, [](const Vec3& p) { return to_output_frame(p, UpAxis::Z); }, positions, corners),
              1e-6); // float positions of a 60-unit grid
    std::uint32_t next = 0;
    for (const std::uint32_t i : after.indices) {
        ASSERT_LE(i, next) << "vertices are numbered by first use";
        next = std::max(next, i + 1);
    }
    const double before_acmr = testing::vertex_cache_misses_per_triangle(before.indices, before.vertex_count());
    const double after_acmr = testing::vertex_cache_misses_per_triangle(after.indices, after.vertex_count());
    EXPECT_GT(before_acmr, 2.5);
    EXPECT_LT(after_acmr, 0.8);
}

// split_face: the triangles of the faces from it on come last, each part in GPU order among its own
// (one vertex array, two index ranges: a plain tile's surface and skirts); first_face/end_face keep
// only a range of faces and their vertices (a Draco tile's skirts, encoded apart).
TEST(MeshBuffers, a_split_keeps_each_part_of_the_faces_apart)
{
    const Mesh mesh = grid_mesh(30, 30, 0.0, 0.0, 1.0, testing::wave);
    const std::size_t split = mesh.n_faces() - 300;
    const auto frame = [](const Vec3& p) { return to_output_frame(p, UpAxis::Z); };
    // The faces [first, end) of the mesh as a mesh of their own, to compare triangles with.
    const auto part = [&](std::size_t first, std::size_t end) {
        Mesh out;
        for (const auto v : mesh.vertices())
            out.add_vertex(mesh.point(v));
        for (std::size_t f = first; f < end; ++f) {
            std::array<Mesh::VertexHandle, 3> c;
            int k = 0;
            for (const auto v : mesh.fv_range(Mesh::FaceHandle(static_cast<int>(f))))
                c[static_cast<std::size_t>(k++)] = out.vertex_handle(static_cast<unsigned>(v.idx()));
            testing::add_checked_face(out, c[0], c[1], c[2]);
        }
        return out;
    };
    const auto triangles = [](const MeshBuffers& b, std::size_t first, std::size_t end, std::vector<Vec3>& positions) {
        positions.resize(b.vertex_count());
        for (std::size_t i = 0; i < positions.size(); ++i)
            positions[i] = Vec3{b.positions[3 * i], b.positions[3 * i + 1], b.positions[3 * i + 2]} + b.offset;
        return std::vector<std::size_t>(b.indices.begin() + static_cast<std::ptrdiff_t>(3 * first),
                                        b.indices.begin() + static_cast<std::ptrdiff_t>(3 * end));
    };
    MeshBufferOptions two_parts;
    two_parts.split_face = split;
    const MeshBuffers b = make_mesh_buffers(mesh, two_parts);
    EXPECT_EQ(b.split_triangle, split);
    EXPECT_EQ(b.face_count(), mesh.n_faces());
    EXPECT_EQ(b.vertex_count(), mesh.n_vertices());
    std::vector<Vec3> positions;
    const std::vector<std::size_t> head = triangles(b, 0, split, positions);
    EXPECT_LT(testing::worst_triangle_mismatch(part(0, split), frame, positions, head), 1e-6);
    const std::vector<std::size_t> tail = triangles(b, split, b.face_count(), positions);
    EXPECT_LT(testing::worst_triangle_mismatch(part(split, mesh.n_faces()), frame, positions, tail), 1e-6);
    EXPECT_EQ(make_mesh_buffers(mesh).split_triangle, mesh.n_faces());

    MeshBufferOptions last;
    last.first_face = split;
    const MeshBuffers skirts = make_mesh_buffers(mesh, last);
    EXPECT_EQ(skirts.face_count(), mesh.n_faces() - split);
    EXPECT_LT(skirts.vertex_count(), mesh.n_vertices() / 2); // only the vertices of those faces
    const std::vector<std::size_t> own = triangles(skirts, 0, skirts.face_count(), positions);
    EXPECT_LT(testing::worst_triangle_mismatch(part(split, mesh.n_faces()), frame, positions, own), 1e-6);
}

TEST(MeshBuffers, computes_missing_normals_and_keeps_stored_ones)
{
    Mesh mesh = grid_mesh(3, 3, 0.0, 0.0, 1.0, [](double, double) { return 0.0; });
    const auto custom = mesh.vertex_handle(5);
    mesh.set_normal(custom, Mesh::Normal(0, 3, 4)); // stored, not unit: used after normalization
    MeshBufferOptions options;
    options.offset = Vec3{};
    const MeshBuffers b = make_mesh_buffers(mesh, options);
    ASSERT_EQ(b.normals.size(), b.positions.size());
    std::size_t customs = 0;
    for (std::size_t i = 0; i < b.vertex_count(); ++i) {
        const Vec3 n{b.normals[3 * i], b.normals[3 * i + 1], b.normals[3 * i + 2]};
        const Vec3 p = from_output_frame({b.positions[3 * i], b.positions[3 * i + 1], b.positions[3 * i + 2]}, UpAxis::Z);
        if (p == Vec3{mesh.point(custom)[0], mesh.point(custom)[1], mesh.point(custom)[2]}) {
            ++customs;
            EXPECT_NEAR(n.x, 0.0, 1e-7);
            EXPECT_NEAR(n.y, 0.8, 1e-7); // (0, 3, 4)/5 -> y-up (0, 0.8, -0.6)
            EXPECT_NEAR(n.z, -0.6, 1e-7);
        } else {
            EXPECT_EQ(n, (Vec3{0, 1, 0})); // the plane's up normal, rotated to y-up
        }
    }
    EXPECT_EQ(customs, 1u);
}

TEST(MeshBuffers, skips_deleted_faces_and_their_vertices)
{
    Mesh mesh = grid_mesh(2, 1, 0.0, 0.0, 1.0, [](double, double) { return 0.0; });
    ASSERT_EQ(mesh.n_faces(), 4u);
    // Deleting the two faces of the right cell isolates vertices 2 and 5, which are deleted too.
    mesh.delete_face(mesh.face_handle(2), true);
    mesh.delete_face(mesh.face_handle(3), true);
    const MeshBuffers b = make_mesh_buffers(mesh);
    EXPECT_EQ(b.face_count(), 2u);
    EXPECT_EQ(b.vertex_count(), 4u);
    for (const std::uint32_t i : b.indices)
        EXPECT_LT(i, 4u);
    for (std::size_t i = 0; i < b.vertex_count(); ++i)
        EXPECT_LE(b.positions[3 * i] + b.offset.x, 1.0f); // no vertex of the deleted cell (x = 2)
}

TEST(MeshBuffers, copies_colours_only_when_present_and_wanted)
{
    const Mesh coloured = uv_sphere(4, 6, 1.0, {}, true);
    const MeshBuffers b = make_mesh_buffers(coloured);
    ASSERT_EQ(b.colors.size(), 4 * b.vertex_count());
    EXPECT_EQ(b.colors[3], 255);
    MeshBufferOptions no_colors;
    no_colors.colors = false;
    EXPECT_TRUE(make_mesh_buffers(coloured, no_colors).colors.empty());
    EXPECT_TRUE(make_mesh_buffers(uv_sphere(4, 6, 1.0)).colors.empty());
}

TEST(MeshBuffers, rejects_empty_and_non_finite_meshes)
{
    Mesh empty;
    empty.add_vertex(Mesh::Point(0, 0, 0));
    EXPECT_THROW(make_mesh_buffers(empty), InvalidInput);
    Mesh bad = grid_mesh(1, 1, 0.0, 0.0, 1.0, [](double, double) { return 0.0; });
    bad.set_point(bad.vertex_handle(0), Mesh::Point(std::nan(""), 0, 0));
    EXPECT_THROW(make_mesh_buffers(bad), InvalidInput);
}

} // namespace
} // namespace mrt
