// Tests of face_sequence.h: the connectivity FaceSequence writes is, element for element, the one
// OpenMesh's add_face builds for the same triangles (refusals included), on meshes whose faces come
// in orders that make add_face relink patches and on random triangle soups that it mostly refuses.
// OpenMesh copies a default-constructed (uninitialized) VectorT when a vertex is added (see test_mesh_buffers.cpp).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "libmrtile/face_sequence.h"
#include "mesh_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

namespace mrt {
namespace {

using Triangle = std::array<int, 3>;

// Every connectivity field of both meshes, compared; `what` names the case in a failure.
void expect_same_connectivity(const Mesh& expected, const Mesh& actual, const std::string& what)
{
    ASSERT_EQ(expected.n_vertices(), actual.n_vertices()) << what;
    ASSERT_EQ(expected.n_edges(), actual.n_edges()) << what;
    ASSERT_EQ(expected.n_faces(), actual.n_faces()) << what;
    for (const auto v : expected.all_vertices())
        ASSERT_EQ(expected.halfedge_handle(v), actual.halfedge_handle(v)) << what << ": vertex " << v.idx();
    for (const auto h : expected.all_halfedges()) {
        ASSERT_EQ(expected.to_vertex_handle(h), actual.to_vertex_handle(h)) << what << ": half-edge " << h.idx();
        ASSERT_EQ(expected.face_handle(h), actual.face_handle(h)) << what << ": half-edge " << h.idx();
        ASSERT_EQ(expected.next_halfedge_handle(h), actual.next_halfedge_handle(h)) << what << ": half-edge " << h.idx();
        ASSERT_EQ(expected.prev_halfedge_handle(h), actual.prev_halfedge_handle(h)) << what << ": half-edge " << h.idx();
    }
    for (const auto f : expected.all_faces())
        ASSERT_EQ(expected.halfedge_handle(f), actual.halfedge_handle(f)) << what << ": face " << f.idx();
}

// Adds `triangles` to fresh meshes over `vertices` vertices both ways; the face indices returned must agree.
void expect_same_as_add_face(std::size_t vertices, const std::vector<Triangle>& triangles, const std::string& what)
{
    const QuietOpenMesh quiet; // add_face reports its refusals on the console
    Mesh expected, actual;
    for (std::size_t v = 0; v < vertices; ++v) {
        expected.add_vertex(OpenMesh::Vec3d(0, 0, 0));
        actual.add_vertex(OpenMesh::Vec3d(0, 0, 0));
    }
    FaceSequence sequence(vertices);
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        const Triangle& t = triangles[k];
        const int by_openmesh = expected
                                    .add_face(Mesh::VertexHandle(t[0]), Mesh::VertexHandle(t[1]),
                                              Mesh::VertexHandle(t[2]))
                                    .idx();
        ASSERT_EQ(by_openmesh, sequence.add_face(t[0], t[1], t[2])) << what << ": triangle " << k;
    }
    sequence.apply(actual);
    expect_same_connectivity(expected, actual, what);
}

std::vector<Triangle> triangles_of(const Mesh& mesh)
{
    std::vector<Triangle> out;
    for (const auto f : mesh.faces()) {
        const auto v = face_vertices(mesh, f);
        out.push_back({v[0].idx(), v[1].idx(), v[2].idx()});
    }
    return out;
}

TEST(FaceSequence, builds_what_add_face_builds_in_any_face_order)
{
    const Mesh sphere = testing::uv_sphere(12, 8, 1.0);
    const Mesh grid = testing::grid_mesh(9, 7, 0.0, 0.0, 1.0, testing::wave);
    std::mt19937 rng(7);
    for (const Mesh* mesh : {&sphere, &grid}) {
        std::vector<Triangle> triangles = triangles_of(*mesh);
        expect_same_as_add_face(mesh->n_vertices(), triangles, "in order");
        // Shuffled: faces meet existing ones from every side, so add_face relinks patches and moves
        // vertices' outgoing half-edges.
        for (int round = 0; round < 20; ++round) {
            std::shuffle(triangles.begin(), triangles.end(), rng);
            expect_same_as_add_face(mesh->n_vertices(), triangles, "shuffled " + std::to_string(round));
        }
    }
}

TEST(FaceSequence, refuses_what_add_face_refuses)
{
    // Random triangles over few vertices: complex vertices and edges, failed relinks, fans that touch
    // at one vertex; most are refused, the rest must come out the same.
    std::mt19937 rng(11);
    for (int round = 0; round < 200; ++round) {
        const int vertices = 5 + round % 20;
        std::uniform_int_distribution<int> pick(0, vertices - 1);
        std::vector<Triangle> triangles;
        while (triangles.size() < 60) {
            const Triangle t{pick(rng), pick(rng), pick(rng)};
            if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                triangles.push_back(t);
        }
        expect_same_as_add_face(static_cast<std::size_t>(vertices), triangles, "soup " + std::to_string(round));
    }
}

TEST(FaceSequence, apply_keeps_the_vertices_a_mesh_has)
{
    Mesh mesh;
    mesh.add_vertex(OpenMesh::Vec3d(1, 2, 3));
    FaceSequence sequence(1);
    const int b = sequence.add_vertex(), c = sequence.add_vertex();
    EXPECT_EQ(0, sequence.add_face(0, b, c));
    sequence.apply(mesh);
    EXPECT_EQ(3u, mesh.n_vertices());
    EXPECT_EQ(1u, mesh.n_faces());
    EXPECT_EQ(OpenMesh::Vec3d(1, 2, 3), mesh.point(Mesh::VertexHandle(0)));
}

} // namespace
} // namespace mrt
