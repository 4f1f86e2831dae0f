// Tests of remove_slivers.h: a cap's long edge is flipped and nothing moves; a needle's short edge is
// collapsed into one end; flips never turn a height field over; on meshes of real
// cuts the caps (and the creases they draw) are gone while topology and distances stay; bad options
// are refused.
#include "formats/read_points.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/remove_slivers.h"
#include "libmrtile/shapes.h"

#include "tests/mesh_fixtures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace mrt {
namespace {

Mesh::VertexHandle add(Mesh& mesh, double x, double y, double z) { return mesh.add_vertex(Mesh::Point(x, y, z)); }

double largest_angle_degrees(const Mesh& mesh, Mesh::FaceHandle f)
{
    auto fv = mesh.cfv_iter(f);
    const Vec3 p = to_vec3(mesh.point(*fv)), q = to_vec3(mesh.point(*++fv)), r = to_vec3(mesh.point(*++fv));
    const auto corner = [](const Vec3& u, const Vec3& v, const Vec3& w) {
        return std::atan2(norm(cross(u - w, v - w)), dot(u - w, v - w)) * 180.0 / M_PI;
    };
    return std::max({corner(q, r, p), corner(r, p, q), corner(p, q, r)});
}

std::size_t measured_caps(const Mesh& mesh, double degrees = 150.0)
{
    std::size_t caps = 0;
    for (const auto f : mesh.faces())
        caps += largest_angle_degrees(mesh, f) > degrees;
    return caps;
}

// Interior edges whose faces' normals differ by more than `degrees`.
std::size_t count_folds(Mesh& mesh, double degrees)
{
    mesh.update_face_normals();
    std::size_t folds = 0;
    for (const auto e : mesh.edges())
        if (!mesh.is_boundary(e)) {
            const auto n0 = mesh.normal(mesh.face_handle(mesh.halfedge_handle(e, 0)));
            const auto n1 = mesh.normal(mesh.face_handle(mesh.halfedge_handle(e, 1)));
            folds += (n0 | n1) < std::cos(degrees * M_PI / 180.0);
        }
    return folds;
}

std::vector<Mesh::Point> points_of(const Mesh& mesh)
{
    std::vector<Mesh::Point> out;
    for (const auto v : mesh.vertices())
        out.push_back(mesh.point(v));
    return out;
}

TEST(RemoveSlivers, cap_flipped_nothing_moved)
{
    // Quad a, d, b, c with c a hair above the diagonal ab: (a, b, c) is a cap (angle ~179 degrees).
    Mesh mesh;
    const auto a = add(mesh, 0, 0, 0), b = add(mesh, 2, 0, 0), c = add(mesh, 1, 0.01, 0), d = add(mesh, 1, -0.5, 0);
    testing::add_checked_face(mesh, a, b, c);
    testing::add_checked_face(mesh, b, a, d);
    ASSERT_EQ(measured_caps(mesh), 1u);
    const std::vector<Mesh::Point> before = points_of(mesh);
    const SliverStats stats = remove_slivers(mesh);
    EXPECT_EQ(stats.caps_before, 1u);
    EXPECT_EQ(stats.flips, 1u);
    EXPECT_EQ(stats.caps_after, 0u);
    EXPECT_EQ(measured_caps(mesh), 0u);
    EXPECT_EQ(points_of(mesh), before);
    EXPECT_EQ(mesh.n_faces(), 2u);
    // The new diagonal is c-d, and both faces still face +z.
    bool has_cd = false;
    for (const auto e : mesh.edges()) {
        const auto h = mesh.halfedge_handle(e, 0);
        const auto u = mesh.from_vertex_handle(h), v = mesh.to_vertex_handle(h);
        has_cd = has_cd || (u == c && v == d) || (u == d && v == c);
    }
    EXPECT_TRUE(has_cd);
    mesh.update_face_normals();
    for (const auto f : mesh.faces())
        EXPECT_GT(mesh.normal(f)[2], 0.99);
}

TEST(RemoveSlivers, no_flip_turns_a_height_field_over)
{
    // A height field over z: the flip would turn a face to face down. With the vertical option it stays.
    Mesh field;
    {
        const auto a = add(field, 0, 0, 0), b = add(field, 2, 0, 0), c = add(field, 1, 0.01, 0.0), d = add(field, 1, 0.02, 0.5);
        testing::add_checked_face(field, a, b, c);
        testing::add_checked_face(field, b, a, d);
    }
    Mesh free_mesh = field;
    SliverOptions vertical;
    vertical.vertical = true;
    vertical.max_turn_degrees = 90.0;
    EXPECT_EQ(remove_slivers(field, vertical).flips, 0u);
    SliverOptions free_options;
    free_options.max_turn_degrees = 90.0;
    const SliverStats free_stats = remove_slivers(free_mesh, free_options);
    EXPECT_EQ(free_stats.flips, 1u); // so the vertical refusal above is the height-field rule, not another
    free_mesh.update_face_normals();
    bool some_down = false;
    for (const auto f : free_mesh.faces())
        some_down = some_down || free_mesh.normal(f)[2] <= 0.0;
    EXPECT_TRUE(some_down);
}

TEST(RemoveSlivers, needle_collapsed_into_an_end_topology_kept)
{
    // A closed UV sphere with one vertex of a ring moved next to its neighbour: the faces at that
    // edge become needles. Collapsing it keeps the sphere closed with genus 0 and moves no vertex.
    Mesh mesh = testing::uv_sphere(12, 16, 1.0);
    const auto v = Mesh::VertexHandle(5), w = Mesh::VertexHandle(6); // neighbours on the first ring
    mesh.point(v) = mesh.point(w) + (mesh.point(v) - mesh.point(w)) * 0.01;
    SliverOptions options;
    options.cap_angle_degrees = 180.0;
    options.needle_ratio = 0.1;
    const std::size_t vertices = mesh.n_vertices();
    const SliverStats stats = remove_slivers(mesh, options);
    EXPECT_GE(stats.collapses, 1u);
    EXPECT_EQ(stats.needles_after, 0u);
    EXPECT_EQ(mesh.n_vertices(), vertices - stats.collapses);
    const TopologyStats t = topology_stats(mesh);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.genus, 0);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.nonmanifold_vertices, 0u);
    for (const auto u : mesh.vertices()) // every vertex still on the unit sphere (none moved)
        EXPECT_NEAR(mesh.point(u).norm(), 1.0, 1e-12);
}

// Real cuts: the surface's gap strips and the fit's flips used to leave caps (5% of a sphere's faces,
// 12% of the bunny's at tolerance 0.002), drawn as creases by shading.
TEST(RemoveSlivers, cuts_of_a_sphere_and_the_bunny_lose_their_caps)
{
    struct Case { const char* name; PointCloud cloud; };
    std::vector<Case> cases;
    cases.push_back({"sphere", shapes::sphere(20000)});
    cases.push_back({"bunny", read_points(MRTILE_SHARED_DATA "/bun_zipper.ply")});
    for (Case& c : cases) {
        SCOPED_TRACE(c.name);
        const Hierarchy h = build_hierarchy(c.cloud);
        const Cut cut = cut_by_tolerance(h, 0.002);
        // Without the relaxation, which evens out the rims and so removes caps of its own.
        MeshOptions on;
        on.fit.relax.iterations = 0;
        MeshOptions off = on;
        off.slivers.cap_angle_degrees = 180.0;
        off.fit.max_flip_angle_degrees = 180.0;
        MeshResult old_result = mesh_cut(h, cut, off);
        MeshResult result = mesh_cut(h, cut, on);
        const std::size_t faces = result.mesh.n_faces();
        EXPECT_EQ(faces, old_result.mesh.n_faces()); // flips only, by default
        EXPECT_GT(measured_caps(old_result.mesh), faces / 25);
        EXPECT_LT(measured_caps(result.mesh), faces / 100);
        EXPECT_EQ(count_caps(old_result.mesh), measured_caps(old_result.mesh)); // the report's measure
        EXPECT_EQ(count_caps(result.mesh), measured_caps(result.mesh));
        EXPECT_LT(count_folds(result.mesh, 60.0), count_folds(old_result.mesh, 60.0) * 2 / 3);
        const TopologyStats t0 = topology_stats(old_result.mesh), t1 = topology_stats(result.mesh);
        EXPECT_EQ(t1.boundary_loops, t0.boundary_loops);
        EXPECT_EQ(t1.genus, t0.genus);
        EXPECT_EQ(t1.nonmanifold_edges, 0u);
        EXPECT_EQ(t1.nonmanifold_vertices, 0u);
        // The bunny's cut has a few dozen intersecting pairs where sheets pass close (ear, base), with or
        // without the cleanup; flips may move a few, not add many.
        const std::size_t x0 = self_intersecting_faces(old_result.mesh).size();
        EXPECT_LE(self_intersecting_faces(result.mesh).size(), x0 + x0 / 4 + 2);
        const double d0 = point_to_mesh_distance(h.cloud.positions, old_result.mesh).mean;
        const double d1 = point_to_mesh_distance(h.cloud.positions, result.mesh).mean;
        EXPECT_LT(d1, 1.05 * d0);
    }
}

TEST(RemoveSlivers, bad_options_are_refused)
{
    Mesh mesh = testing::uv_sphere(4, 6, 1.0);
    const auto refused = [&](auto change) {
        SliverOptions o;
        change(o);
        EXPECT_THROW(remove_slivers(mesh, o), InvalidInput);
    };
    refused([](SliverOptions& o) { o.cap_angle_degrees = 80.0; });
    refused([](SliverOptions& o) { o.cap_angle_degrees = std::nan(""); });
    refused([](SliverOptions& o) { o.needle_ratio = 1.0; });
    refused([](SliverOptions& o) { o.max_turn_degrees = -1.0; });
    refused([](SliverOptions& o) { o.passes = -1; });
    refused([](SliverOptions& o) { o.max_flip_height = -0.1; });
    refused([](SliverOptions& o) { o.vertical = true; o.axis = Vec3{0, 0, 0}; });
}

} // namespace
} // namespace mrt
