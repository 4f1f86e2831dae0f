// Tests of fit_vertices.h: on analytic shapes the fit lowers the mean distance and leaves the
// connectivity alone; a planar sample stays planar; height fields move only vertically; moves respect
// the limit; the result is deterministic; bad options are refused.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/errors.h"
#include "libmrtile/fit_vertices.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"

#include "tests/mesh_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace mrt {
namespace {

std::vector<Vec3> positions(const Mesh& mesh)
{
    std::vector<Vec3> out;
    for (const auto v : mesh.vertices()) {
        const Mesh::Point& p = mesh.point(v);
        out.push_back({p[0], p[1], p[2]});
    }
    return out;
}

std::vector<double> shortest_edges(const Mesh& mesh)
{
    std::vector<double> out(mesh.n_vertices(), std::numeric_limits<double>::infinity());
    for (const auto e : mesh.edges()) {
        const auto h = mesh.halfedge_handle(e, 0);
        const double l = mesh.calc_edge_length(e);
        for (const auto v : {mesh.from_vertex_handle(h), mesh.to_vertex_handle(h)})
            out[static_cast<std::size_t>(v.idx())] = std::min(out[static_cast<std::size_t>(v.idx())], l);
    }
    return out;
}

// A coarse UV sphere inscribed in a dense sample of the unit sphere: every face is a chord under the
// points. The fit pushes the vertices out; the mean distance falls by more than half (a chord's mean
// sag is 2/3 of its maximum; the best offset leaves about a third of it), connectivity and the face
// count stay, and no vertex moves farther than the limit.
TEST(FitVertices, inscribed_sphere_moves_out_and_fits_better)
{
    const std::vector<Vec3> points = shapes::sphere(20000).positions;
    Mesh mesh = testing::uv_sphere(8, 16, 1.0);
    const std::vector<Vec3> before = positions(mesh);
    const std::vector<double> shortest = shortest_edges(mesh);
    const DistanceStats d0 = point_to_mesh_distance(points, mesh);
    FitOptions o;
    o.rounds = 1;
    const FitStats s = fit_vertices(mesh, points, o);
    EXPECT_EQ(s.rounds, 1);
    const DistanceStats d1 = point_to_mesh_distance(points, mesh);
    EXPECT_LT(d1.mean, 0.5 * d0.mean);
    const std::vector<Vec3> after = positions(mesh);
    ASSERT_EQ(after.size(), before.size());
    for (std::size_t i = 0; i < after.size(); ++i) {
        EXPECT_GT(norm(after[i]), 1.0) << "vertex " << i << " should move outward";
        EXPECT_LE(distance(after[i], before[i]), o.max_move * shortest[i] * (1 + 1e-12));
    }
    const TopologyStats t = topology_stats(mesh);
    EXPECT_EQ(t.faces, 2u * 16u * 7u);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.genus, 0);
    // More rounds only re-assign points: not worse.
    o.rounds = 2;
    Mesh again = testing::uv_sphere(8, 16, 1.0);
    fit_vertices(again, points, o);
    EXPECT_LE(point_to_mesh_distance(points, again).mean, d1.mean * 1.001);
}

// The per-round move limit is taken from the edges before the first round as well: a vertex moving
// away from its neighbours lengthens its own edges, and a limit taken from them alone compounded. On
// ten points of a sphere, three rounds moved one fan's apex 2.45 of its starting shortest
// edges (limit 3 × 0.5 = 1.5; it ended 1.5 diagonals from every point); now at most the limit, plus
// half an edge that the relaxation before each round may slide a vertex.
TEST(FitVertices, the_move_limit_does_not_grow_with_the_moves)
{
    PointCloud ten; // ten random points of the unit sphere (an unseen-input sweep's file)
    ten.positions = {
        {-0.7190908482924668, -0.47252824736405885, -0.5095345006425683},
        {0.691483839716439, -0.6438393328645872, 0.32759885968588687},
        {0.6518634848755612, 0.663379914978442, 0.3674249385780505},
        {-0.37602754786287995, -0.6297584524395178, -0.679711390833796},
        {-0.3330101091743923, -0.049759630418293524, -0.9416093916100744},
        {-0.5173218486830002, 0.13940037652247383, -0.8443610838383039},
        {-0.1627428261678106, 0.39140750873856406, -0.9057123906814926},
        {-0.7440964880496697, -0.5085377230523487, 0.4332548911494026},
        {-0.06757400509426263, -0.9730790498393558, -0.22034272531503538},
        {0.6554740229796301, 0.6359620174865794, 0.4073157467043214}};
    const Hierarchy h = build_hierarchy(ten);
    // The fan of the one tile, as the surface stage makes it (mesh_cut now meshes so small a solid as
    // its convex hull, which needs no fit), fitted as mesh_cut fits a surface.
    const Mesh start = build_surface(h, make_tiles(h, cut_by_tolerance(h, 0.002)));
    Mesh fitted = start;
    fit_vertices(fitted, h.cloud.positions);
    ASSERT_EQ(fitted.n_vertices(), start.n_vertices());
    ASSERT_GT(start.n_faces(), 0u);
    const std::vector<Vec3> before = positions(start), after = positions(fitted);
    const std::vector<double> shortest = shortest_edges(start);
    const FitOptions o;
    for (std::size_t i = 0; i < after.size(); ++i)
        EXPECT_LE(distance(after[i], before[i]), (o.rounds * o.max_move + 0.5) * shortest[i]) << "vertex " << i;
}

// 5,000 seeded points on the plane z = 0.5 over [0, 4]², under the tests' flat grid meshes.
std::vector<Vec3> points_on_a_plane(unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 4.0);
    std::vector<Vec3> points(5000);
    for (Vec3& p : points)
        p = {u(rng), u(rng), 0.5};
    return points;
}

// Points exactly on a plane under a flat grid mesh: nothing to fit, every vertex stays on the plane.
TEST(FitVertices, planar_sample_stays_planar)
{
    const std::vector<Vec3> points = points_on_a_plane(7);
    Mesh mesh = testing::grid_mesh(8, 8, 0.0, 0.0, 0.5, [](double, double) { return 0.5; });
    fit_vertices(mesh, points);
    for (const Vec3& p : positions(mesh))
        EXPECT_NEAR(p.z, 0.5, 1e-12);
}

// Strays over a planar sample (birds over flat ground) do not lift the mesh: in least squares one point
// far off outweighed the dozen under a vertex (QA round 60: ground vertices lifted 6 m toward birds 13 m
// away). Strays at 1 (within twice an edge of their face: the local median rule) and 3 (beyond it) over
// a mesh of 0.5 cells; with stray_reach 0 they pull.
TEST(FitVertices, strays_over_a_plane_do_not_lift_it)
{
    std::vector<Vec3> points = points_on_a_plane(60);
    for (const double height : {1.0, 3.0})
        for (int k = 0; k < 5; ++k)
            points.push_back({0.4 + 0.8 * k, 0.6 + 0.7 * k, 0.5 + height});
    const auto highest = [&](double stray_reach) {
        Mesh mesh = testing::grid_mesh(8, 8, 0.0, 0.0, 0.5, [](double, double) { return 0.5; });
        FitOptions o;
        o.points_per_vertex = 0; // every point, strays included
        o.stray_reach = stray_reach;
        fit_vertices(mesh, points, o);
        double z = -std::numeric_limits<double>::infinity();
        for (const Vec3& p : positions(mesh))
            z = std::max(z, p.z);
        return z;
    };
    EXPECT_NEAR(highest(FitOptions{}.stray_reach), 0.5, 1e-12);
    EXPECT_GT(highest(0.0), 0.52);
}

// Points on a tilted plane under a flat mesh: both diagonals of every quad fit them exactly, so their
// errors differ by rounding only, and no edge may flip on that (on an L-shaped plate, flips on such
// noise spread an in-plane fold from 2 crossing pairs to 23, which the untangling then lifted out of
// the plane by 6% of the diagonal).
TEST(FitVertices, no_flips_on_rounding_noise_in_a_plane)
{
    const auto plane = [](double x, double y) { return 0.5 + 0.3 * x - 0.2 * y; };
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 4.0);
    std::vector<Vec3> points(5000);
    for (Vec3& p : points) {
        p.x = u(rng);
        p.y = u(rng);
        p.z = plane(p.x, p.y);
    }
    Mesh mesh = testing::grid_mesh(8, 8, 0.0, 0.0, 0.5, plane);
    FitOptions o;
    o.relax.iterations = 0; // the grid stays as it is: only the flips are under test
    const FitStats stats = fit_vertices(mesh, points, o);
    EXPECT_EQ(stats.flips, 0u);
    for (const Vec3& p : positions(mesh))
        EXPECT_NEAR(p.z, plane(p.x, p.y), 1e-12);
}

// Vertical mode on a height field over the plane normal to axis `up` (2 = z, 0 = x): the two other
// coordinates of every vertex are bit-identical, the height fits the wave better.
void expect_vertical_fit(int up)
{
    const int a = (up + 1) % 3, b = (up + 2) % 3;
    auto place = [&](double x, double y, double height) { // x, y in the plane, height along `up`
        double c[3];
        c[a] = x;
        c[b] = y;
        c[up] = height;
        return Vec3{c[0], c[1], c[2]};
    };
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 8.0);
    std::vector<Vec3> points(20000);
    for (Vec3& p : points) {
        const double x = u(rng), y = u(rng);
        p = place(x, y, testing::wave(x, y));
    }
    Mesh mesh = testing::grid_mesh(6, 6, 0.0, 0.0, 8.0 / 6, testing::wave);
    for (const auto v : mesh.vertices()) {
        const Mesh::Point p = mesh.point(v);
        const Vec3 q = place(p[0], p[1], p[2]);
        mesh.set_point(v, Mesh::Point(q.x, q.y, q.z));
    }
    const std::vector<Vec3> before = positions(mesh);
    const double d0 = point_to_mesh_distance(points, mesh).mean;
    FitOptions o;
    o.vertical = true;
    o.axis = place(0, 0, 1);
    o.relax.iterations = 0; // the fit alone moves along the axis (its relaxation slides within the surface)
    fit_vertices(mesh, points, o);
    const std::vector<Vec3> after = positions(mesh);
    for (std::size_t i = 0; i < after.size(); ++i) {
        EXPECT_EQ(after[i][a], before[i][a]);
        EXPECT_EQ(after[i][b], before[i][b]);
    }
    EXPECT_LT(point_to_mesh_distance(points, mesh).mean, 0.8 * d0);
    o.axis = {};
    EXPECT_THROW(fit_vertices(mesh, points, o), InvalidInput);
}

TEST(FitVertices, vertical_mode_keeps_a_graph_along_its_axis)
{
    expect_vertical_fit(2);
    expect_vertical_fit(0);
}

// The pipeline runs the fit by default: on a noisy torus the fitted mesh is closer to the points than
// the interpolating one, with the same faces and topology, and two runs give identical positions.
TEST(FitVertices, mesh_cut_fits_by_default_and_is_deterministic)
{
    const Hierarchy h = build_hierarchy(shapes::torus(20000));
    const Cut cut = cut_by_tolerance(h, 0.005);
    MeshOptions off;
    off.fit.rounds = 0;
    const MeshResult plain = mesh_cut(h, cut, off);
    const MeshResult fitted = mesh_cut(h, cut);
    const MeshResult again = mesh_cut(h, cut);
    EXPECT_EQ(fitted.fit.rounds, FitOptions{}.rounds);
    EXPECT_EQ(fitted.mesh.n_faces(), plain.mesh.n_faces());
    const TopologyStats t = topology_stats(fitted.mesh);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.genus, 1);
    EXPECT_LT(measure_quality(h, cut, fitted.mesh).point_to_mesh.mean,
              0.9 * measure_quality(h, cut, plain.mesh).point_to_mesh.mean);
    EXPECT_EQ(positions(fitted.mesh), positions(again.mesh));
    // The closest-face queries run in fixed chunks: one thread or three give the same mesh.
    MeshOptions one, three;
    one.fit.threads = 1;
    three.fit.threads = 3;
    EXPECT_EQ(positions(mesh_cut(h, cut, one).mesh), positions(mesh_cut(h, cut, three).mesh));
}

// Edge flips: on a torus cut, flipping the edges whose faces fit better the other way lowers the mean
// distance with the same faces, and the surface stays a closed oriented genus-1 manifold.
TEST(FitVertices, edge_flips_lower_the_error_and_keep_the_topology)
{
    const Hierarchy h = build_hierarchy(shapes::torus(20000));
    const Cut cut = cut_by_tolerance(h, 0.005);
    MeshOptions no_flips;
    no_flips.fit.flip_edges = false;
    const MeshResult plain = mesh_cut(h, cut, no_flips);
    const MeshResult flipped = mesh_cut(h, cut);
    EXPECT_EQ(plain.fit.flips, 0u);
    EXPECT_GT(flipped.fit.flips, 0u);
    EXPECT_EQ(flipped.mesh.n_faces(), plain.mesh.n_faces());
    const TopologyStats t = topology_stats(flipped.mesh);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.nonmanifold_vertices, 0u);
    EXPECT_TRUE(t.consistently_oriented);
    EXPECT_EQ(t.genus, 1);
    EXPECT_LT(measure_quality(h, cut, flipped.mesh).point_to_mesh.mean,
              0.95 * measure_quality(h, cut, plain.mesh).point_to_mesh.mean);
}

// Self-intersections: unchecked, the fit of a coarse torus cut pulls faces across each other at a few
// places (the interpolating mesh has none); with the check (default) the corners of intersecting faces go
// back and the fitted mesh has none either, still closer to the points than the interpolating one.
TEST(FitVertices, the_fit_adds_no_self_intersections_on_a_torus)
{
    const Hierarchy h = build_hierarchy(shapes::torus(40000));
    {
        const Cut cut = cut_by_tolerance(h, 0.01);
        MeshOptions plain, unchecked, fit_only;
        // The fit's own check, without the untangling after it (untangle.h), which would hide the pairs.
        plain.untangle.max_rounds = unchecked.untangle.max_rounds = fit_only.untangle.max_rounds = 0;
        plain.fit.rounds = 0;
        unchecked.fit.revert_intersections = false;
        const MeshResult interpolating = mesh_cut(h, cut, plain);
        const MeshResult loose = mesh_cut(h, cut, unchecked);
        const MeshResult checked = mesh_cut(h, cut, fit_only);
        EXPECT_TRUE(self_intersecting_faces(interpolating.mesh).empty());
        EXPECT_FALSE(self_intersecting_faces(loose.mesh).empty()) << "the fixture should need the check";
        EXPECT_TRUE(self_intersecting_faces(checked.mesh).empty());
        EXPECT_GT(checked.fit.reverted, 0u);
        EXPECT_LT(measure_quality(h, cut, checked.mesh).point_to_mesh.mean,
                  measure_quality(h, cut, interpolating.mesh).point_to_mesh.mean);
    }
}

TEST(FitVertices, bad_options_are_refused_and_empty_input_is_a_no_op)
{
    Mesh mesh = testing::uv_sphere(4, 8, 1.0);
    const std::vector<Vec3> points{{0, 0, 1}, {1, 0, 0}};
    FitOptions o;
    o.rounds = -1;
    EXPECT_THROW(fit_vertices(mesh, points, o), InvalidInput);
    o = {};
    o.damping = 0.0;
    EXPECT_THROW(fit_vertices(mesh, points, o), InvalidInput);
    o = {};
    o.max_move = std::nan("");
    EXPECT_THROW(fit_vertices(mesh, points, o), InvalidInput);
    for (const double reach : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
        o = {};
        o.stray_reach = reach;
        EXPECT_THROW(fit_vertices(mesh, points, o), InvalidInput) << reach;
    }
    const std::vector<Vec3> before = positions(mesh);
    EXPECT_EQ(fit_vertices(mesh, {}).rounds, 0);
    EXPECT_EQ(positions(mesh), before);
}

// A NaN vertex is refused like a NaN point (QA round 59: it stayed NaN without a word).
TEST(FitVertices, a_vertex_that_is_not_finite_is_refused)
{
    Mesh mesh = testing::uv_sphere(8, 16, 1.0);
    mesh.set_point(Mesh::VertexHandle(5), Mesh::Point(0.0, std::numeric_limits<double>::quiet_NaN(), 0.0));
    EXPECT_THROW(fit_vertices(mesh, shapes::sphere(500).positions), InvalidInput);
}

} // namespace
} // namespace mrt
