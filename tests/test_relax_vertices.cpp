// Tests of relax_vertices.h: a jittered flat grid is evened out within its plane (border fixed, same
// connectivity, better angles); vertices on a crease stay; a height field keeps facing up; the sphere
// and the bunny get closer to their points after the fit; deterministic; bad options are refused.
// OpenMesh copies a default-constructed (uninitialized) VectorT when a vertex is added; the fixtures set
// every value they use right after, so GCC's warning about that copy does not apply.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "formats/read_points.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/relax_vertices.h"
#include "libmrtile/shapes.h"

#include "tests/mesh_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace mrt {
namespace {

double smallest_angle_degrees(const Mesh& mesh)
{
    double smallest = 180.0;
    for (const auto f : mesh.faces()) {
        const std::array<Vec3, 3> p = face_corners(mesh, f);
        for (std::size_t k = 0; k < 3; ++k) {
            const Vec3 u = p[(k + 1) % 3] - p[k], v = p[(k + 2) % 3] - p[k];
            smallest = std::min(smallest, std::atan2(norm(cross(u, v)), dot(u, v)) * 180.0 / M_PI);
        }
    }
    return smallest;
}

// A 20 x 20 grid in z = 0 whose interior vertices (except those within `keep` of x = 10) are jittered
// by up to 0.2 of the spacing (no face turns over).
Mesh jittered_grid(double keep = 0.0)
{
    Mesh mesh = testing::grid_mesh(20, 20, 0.0, 0.0, 1.0, [](double, double) { return 0.0; });
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-0.2, 0.2);
    for (const auto v : mesh.vertices()) {
        auto p = mesh.point(v);
        if (!mesh.is_boundary(v) && std::abs(p[0] - 10.0) > keep) {
            p[0] += jitter(rng);
            p[1] += jitter(rng);
            mesh.set_point(v, p);
        }
    }
    return mesh;
}

TEST(RelaxVertices, evens_out_a_flat_grid_within_its_plane)
{
    Mesh mesh = jittered_grid();
    const Mesh original = mesh;
    const double before = smallest_angle_degrees(mesh);
    const RelaxStats stats = relax_vertices(mesh);
    EXPECT_GT(stats.moves, 300u);
    EXPECT_EQ(stats.creases, 0u);
    EXPECT_GT(smallest_angle_degrees(mesh), before + 5.0);
    ASSERT_EQ(mesh.n_vertices(), original.n_vertices());
    ASSERT_EQ(mesh.n_faces(), original.n_faces());
    for (const auto v : mesh.vertices()) {
        EXPECT_EQ(mesh.point(v)[2], 0.0) << "stays in the plane";
        if (mesh.is_boundary(v)) {
            EXPECT_EQ(mesh.point(v), original.point(v)) << "the border stays put";
        }
    }
    for (const auto f : mesh.faces())
        EXPECT_GT(mesh.normal(f)[2], 0.0) << "no face turned over";
    // Deterministic.
    Mesh again = jittered_grid();
    relax_vertices(again);
    for (const auto v : mesh.vertices())
        EXPECT_EQ(mesh.point(v), again.point(v));
}

// The grid folded at x = 10 into a right angle: the fold's vertices are on a crease and stay, the
// flat sides' vertices move (within their planes).
TEST(RelaxVertices, creases_stay_put)
{
    Mesh mesh = jittered_grid(1.5);
    for (const auto v : mesh.vertices()) {
        auto p = mesh.point(v);
        if (p[0] > 10.0)
            mesh.set_point(v, Mesh::Point(10.0, p[1], p[0] - 10.0));
    }
    std::vector<Mesh::Point> fold;
    for (const auto v : mesh.vertices())
        if (mesh.point(v)[0] == 10.0 && mesh.point(v)[2] == 0.0 && !mesh.is_boundary(v))
            fold.push_back(mesh.point(v));
    ASSERT_EQ(fold.size(), 19u);
    const Mesh original = mesh;
    const RelaxStats stats = relax_vertices(mesh);
    EXPECT_GE(stats.creases, 19u);
    EXPECT_GT(stats.moves, 100u);
    for (const auto v : mesh.vertices()) {
        const auto& p = original.point(v);
        bool on_fold = false;
        for (const auto& q : fold)
            on_fold = on_fold || q == p;
        // Vertices whose one-ring crosses the fold are creases: the fold line stays where it was.
        if (on_fold) {
            EXPECT_EQ(mesh.point(v), p);
        }
    }
}

TEST(RelaxVertices, a_height_field_keeps_facing_up)
{
    Mesh mesh = testing::grid_mesh(20, 20, 0.0, 0.0, 1.0, testing::wave);
    RelaxOptions o;
    o.vertical = true;
    o.iterations = 5;
    o.step = 1.0;
    relax_vertices(mesh, o);
    mesh.update_face_normals();
    for (const auto f : mesh.faces())
        EXPECT_GT(mesh.normal(f)[2], 0.0);
}

// Through mesh_cut (the fit relaxes before each round): evenly spread vertices are placed better on curved surfaces; the topology and
// the face count stay those of the unrelaxed mesh.
TEST(RelaxVertices, sphere_and_bunny_get_closer_to_their_points)
{
    const Hierarchy sphere = build_hierarchy(shapes::sphere(20000));
    const Hierarchy bunny = build_hierarchy(read_points(std::string(MRTILE_SHARED_DATA) + "/bun_zipper.ply"));
    struct Case { const Hierarchy* h; double tolerance; double at_most; };
    for (const Case& c : {Case{&sphere, 0.002, 0.85}, Case{&bunny, 0.002, 0.98}}) {
        const Cut cut = cut_by_tolerance(*c.h, c.tolerance);
        MeshOptions off;
        off.fit.relax.iterations = 0;
        const MeshResult plain = mesh_cut(*c.h, cut, off);
        const MeshResult relaxed = mesh_cut(*c.h, cut);
        EXPECT_GT(relaxed.fit.relax.moves, 0u);
        EXPECT_EQ(relaxed.mesh.n_faces(), plain.mesh.n_faces());
        const TopologyStats a = topology_stats(plain.mesh), b = topology_stats(relaxed.mesh);
        EXPECT_EQ(a.genus, b.genus);
        EXPECT_EQ(a.boundary_loops, b.boundary_loops);
        EXPECT_EQ(b.nonmanifold_edges + b.nonmanifold_vertices, 0u);
        const double before = point_to_mesh_distance(c.h->cloud.positions, plain.mesh).mean;
        const double after = point_to_mesh_distance(c.h->cloud.positions, relaxed.mesh).mean;
        EXPECT_LT(after, c.at_most * before) << c.tolerance;
    }
}

TEST(RelaxVertices, options_are_checked)
{
    Mesh mesh = jittered_grid();
    RelaxOptions o;
    o.step = 0.0;
    EXPECT_THROW(relax_vertices(mesh, o), InvalidInput);
    o = {};
    o.iterations = -1;
    EXPECT_THROW(relax_vertices(mesh, o), InvalidInput);
    o = {};
    o.crease_degrees = 200;
    EXPECT_THROW(relax_vertices(mesh, o), InvalidInput);
    o = {};
    o.vertical = true;
    o.axis = {0, 0, 0};
    EXPECT_THROW(relax_vertices(mesh, o), InvalidInput);
    o = {};
    o.iterations = 0;
    const Mesh original = mesh;
    EXPECT_EQ(relax_vertices(mesh, o).moves, 0u);
    for (const auto v : mesh.vertices())
        EXPECT_EQ(mesh.point(v), original.point(v));
}

} // namespace
} // namespace mrt
