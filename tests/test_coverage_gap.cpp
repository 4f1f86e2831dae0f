// Tests of coverage_gap.h and of what is built on it: holes and notches of a flat surface are found
// (and nothing is found in uniform or unevenly sampled surfaces without holes), the build splits the
// clusters whose tiles would cover them, cuts refine such nodes, and the meshes keep the holes open.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/coverage_gap.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"
#include "libmrtile/tiles.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace mrt {
namespace {

const Vec3 kU{1, 0, 0}, kV{0, 1, 0};

struct Hole
{
    double x, y, r;
};

auto outside_holes(std::vector<Hole> holes)
{
    return [holes](double x, double y) {
        for (const Hole& h : holes)
            if ((x - h.x) * (x - h.x) + (y - h.y) * (y - h.y) < h.r * h.r)
                return false;
        return true;
    };
}

// Brute force: the largest distance from a spot of the disc (cx, cy, r) to its nearest sample point.
double largest_empty_distance(const std::vector<Vec3>& points, double cx, double cy, double r)
{
    double best = 0.0;
    for (int i = -20; i <= 20; ++i)
        for (int j = -20; j <= 20; ++j) {
            const double x = cx + r * i / 20.0, y = cy + r * j / 20.0;
            if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > r * r)
                continue;
            double nearest = 1e300;
            for (const Vec3& p : points)
                nearest = std::min(nearest, (p.x - x) * (p.x - x) + (p.y - y) * (p.y - y));
            best = std::max(best, std::sqrt(nearest));
        }
    return best;
}

// Whether the point (x, y) of the plane z = 0 lies under some face of the mesh (brute force).
bool covered(const Mesh& mesh, double x, double y)
{
    for (const auto f : mesh.faces()) {
        std::array<OpenMesh::Vec3d, 3> c;
        int k = 0;
        for (const auto v : mesh.fv_range(f))
            c[static_cast<std::size_t>(k++)] = mesh.point(v);
        double d[3];
        for (int e = 0; e < 3; ++e) {
            const auto& a = c[static_cast<std::size_t>(e)];
            const auto& b = c[static_cast<std::size_t>((e + 1) % 3)];
            d[e] = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
        }
        if ((d[0] >= 0 && d[1] >= 0 && d[2] >= 0) || (d[0] <= 0 && d[1] <= 0 && d[2] <= 0))
            return true;
    }
    return false;
}

// The share of spots of the disc (inner 90% of its radius) that the mesh covers.
double covered_share(const Mesh& mesh, const Hole& hole)
{
    int spots = 0, hits = 0;
    for (int i = -6; i <= 6; ++i)
        for (int j = -6; j <= 6; ++j) {
            if (i * i + j * j > 36)
                continue;
            ++spots;
            hits += covered(mesh, hole.x + 0.9 * hole.r * i / 6.0, hole.y + 0.9 * hole.r * j / 6.0) ? 1 : 0;
        }
    return static_cast<double>(hits) / spots;
}

double projected_area(const Mesh& mesh)
{
    double area = 0.0;
    for (const auto f : mesh.faces()) {
        std::array<OpenMesh::Vec3d, 3> c;
        int k = 0;
        for (const auto v : mesh.fv_range(f))
            c[static_cast<std::size_t>(k++)] = mesh.point(v);
        area += 0.5 * std::abs((c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]));
    }
    return area;
}

// Uniform samples, with and without a tenfold density gradient, and a jittered grid: no gap.
TEST(CoverageGap, surfaces_without_holes_have_none)
{
    for (std::uint32_t seed = 1; seed <= 5; ++seed) {
        for (std::size_t n : {500u, 4000u, 20000u})
            EXPECT_EQ(coverage_gap(shapes::flat_plate(n, [](double, double) { return true; }, seed).positions, kU, kV), 0.0)
                << n << " points, seed " << seed;
        std::mt19937 rng(seed);
        const PointCloud graded = shapes::flat_plate(20000, [&](double x, double) {
            return static_cast<double>(rng() % 1000) < 1000.0 * (0.1 + 0.9 * x);
        }, seed);
        EXPECT_EQ(coverage_gap(graded.positions, kU, kV), 0.0) << "graded, seed " << seed;
    }
    // A patch sampled twenty times more sparsely than the rest is sparse, not empty.
    std::mt19937 rng(3);
    const PointCloud sparse = shapes::flat_plate(20000, [&](double x, double y) {
        return !(x > 0.3 && x < 0.7 && y > 0.3 && y < 0.7) || rng() % 20 == 0;
    });
    EXPECT_EQ(coverage_gap(sparse.positions, kU, kV), 0.0);
}

// A round hole is measured to within a grid cell of the brute-force largest empty distance; one a few
// spacings wide does not count.
TEST(CoverageGap, a_round_hole_is_measured)
{
    const std::size_t n = 20000;
    const double s = 1.0 / std::sqrt(static_cast<double>(n));
    for (double r : {6 * s, 10 * s, 0.1, 0.2}) {
        const PointCloud c = shapes::flat_plate(n, outside_holes({{0.45, 0.55, r}}));
        const double gap = coverage_gap(c.positions, kU, kV);
        const double truth = largest_empty_distance(c.positions, 0.45, 0.55, r);
        EXPECT_NEAR(gap, truth, 3.0 * s) << "hole radius " << r / s << " spacings";
    }
    const PointCloud small = shapes::flat_plate(n, outside_holes({{0.45, 0.55, 2 * s}}));
    EXPECT_EQ(coverage_gap(small.positions, kU, kV), 0.0);
}

// QA round qa3: a NaN point or option made the gap 0 (no hole) without a word; now refused.
TEST(CoverageGap, non_finite_points_and_options_are_refused)
{
    const PointCloud c = shapes::flat_plate(5000, outside_holes({{0.45, 0.55, 0.1}}));
    std::vector<Vec3> nan_point = c.positions;
    nan_point[7].y = std::nan("");
    EXPECT_THROW(coverage_gap(nan_point, kU, kV), InvalidInput);
    EXPECT_THROW(coverage_gap(c.positions, kU, kV, {}, nan_point), InvalidInput);
    EXPECT_THROW(coverage_gap(c.positions, Vec3{std::nan(""), 0, 0}, kV), InvalidInput);
    CoverageOptions nan_cell;
    nan_cell.points_per_cell = std::nan("");
    CoverageOptions nan_fraction;
    nan_fraction.sample_fraction = std::nan("");
    CoverageOptions negative;
    negative.min_missing_points = -1;
    for (const CoverageOptions& o : {nan_cell, nan_fraction, negative})
        EXPECT_THROW(coverage_gap(c.positions, kU, kV, o), InvalidInput);
    EXPECT_GT(coverage_gap(c.positions, kU, kV), 0.05);
}

// Points of other clusters in the hole fill it; a map locates the hole, and its centre and radius
// from any spot in it (gap_disc: the surface stage judges the hole by the points around that disc).
TEST(CoverageGap, fill_points_close_a_hole_and_a_map_locates_it)
{
    const Hole hole{0.3, 0.6, 0.15};
    const PointCloud c = shapes::flat_plate(20000, outside_holes({hole}));
    const PointCloud inside = shapes::flat_plate(3000, [&](double x, double y) { return !outside_holes({hole})(x, y); });
    EXPECT_GT(coverage_gap(c.positions, kU, kV), 0.1);
    EXPECT_EQ(coverage_gap(c.positions, kU, kV, {}, inside.positions), 0.0);
    const CoverageMap map(c.positions, kU, kV);
    EXPECT_TRUE(map.in_gap({0.3, 0.6, 0.0}));
    EXPECT_TRUE(map.in_gap({0.3, 0.6, 0.0}, 0.1));
    EXPECT_FALSE(map.in_gap({0.3, 0.6, 0.0}, 0.5)); // the hole is narrower than that
    EXPECT_FALSE(map.in_gap({0.8, 0.2, 0.0}));
    Vec3 centre;
    double radius = 0.0;
    ASSERT_TRUE(map.gap_disc({0.4, 0.55, 0.25}, 0.1, centre, radius));
    // Within a grid cell (about 0.014) or so of the hole's centre, at the spot's height above the plane.
    EXPECT_NEAR(centre.x, hole.x, 0.03);
    EXPECT_NEAR(centre.y, hole.y, 0.03);
    EXPECT_DOUBLE_EQ(centre.z, 0.25);
    EXPECT_NEAR(radius, hole.r, 0.03);
    EXPECT_FALSE(map.gap_disc({0.4, 0.55, 0.25}, 0.5, centre, radius));
    EXPECT_FALSE(map.gap_disc({0.8, 0.2, 0.0}, 0.0, centre, radius));
}

// The inside corner of an L-shaped plate is a gap of its hull.
TEST(CoverageGap, a_notch_is_a_gap)
{
    const PointCloud l = shapes::flat_plate(20000, [](double x, double y) { return x < 0.5 || y < 0.5; });
    EXPECT_GT(coverage_gap(l.positions, kU, kV), 0.1);
}

// Two groups apart along a line (two small objects far apart): half the empty stretch between them,
// along either axis, when wider than the caller's minimum; the same stretch filled by another
// cluster's points, or a strip with no break, has none. coverage_gap's grid misses it: the hull is
// narrower than its cells.
TEST(CoverageGap, two_groups_far_apart_are_a_separation)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const double apart : {100.0, 1000.0, 10000.0}) {
        std::vector<Vec3> points, between;
        for (int i = 0; i < 2000; ++i) {
            points.push_back({unit(rng), unit(rng), 0.0});
            points.push_back({apart + unit(rng), unit(rng), 0.0});
        }
        if (apart >= 1000.0) { // the grid sees it only at 100
            EXPECT_EQ(coverage_gap(points, kU, kV), 0.0) << apart;
        }
        EXPECT_NEAR(separation_gap(points, kU, kV, 10.0), 0.5 * (apart - 2.0), 0.01 * apart) << apart;
        EXPECT_NEAR(separation_gap(points, kV, kU, 10.0), 0.5 * (apart - 2.0), 0.01 * apart) << apart; // either axis
        EXPECT_EQ(separation_gap(points, kU, kV, apart), 0.0) << apart; // narrower than the minimum
        for (int i = 0; i < 4000; ++i)
            between.push_back({apart * 0.5 * (1.0 + unit(rng)), unit(rng), 0.0});
        EXPECT_EQ(separation_gap(points, kU, kV, 10.0, {}, between), 0.0) << apart;
        EXPECT_EQ(separation_gap(between, kU, kV, 10.0), 0.0) << apart; // one long strip: no break
    }
}

// Two unit spheres 10,000 apart lie within the default tolerance of one plane: the build splits them
// apart (it had kept the cloud as one leaf, one tile bridging them), and no face joins them.
TEST(CoverageGap, two_small_objects_far_apart_are_not_bridged)
{
    PointCloud two = shapes::sphere(10000, 1.0, 3);
    const PointCloud other = shapes::sphere(10000, 1.0, 4);
    for (const Vec3& p : other.positions)
        two.positions.push_back(p + Vec3{10000.0, 0.0, 0.0});
    const Hierarchy h = build_hierarchy(two);
    ASSERT_GT(h.nodes.size(), 1u);
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.0));
    ASSERT_GT(r.mesh.n_faces(), 0u);
    for (const auto f : r.mesh.faces()) {
        double lo = 1e300, hi = -1e300;
        for (const auto v : r.mesh.fv_range(f)) {
            lo = std::min(lo, r.mesh.point(v)[0] + h.cloud.origin.x);
            hi = std::max(hi, r.mesh.point(v)[0] + h.cloud.origin.x);
        }
        EXPECT_LT(hi - lo, 10.0) << "a face spans the space between the spheres";
    }
    EXPECT_EQ(topology_stats(r.mesh).components, 2u);
}

// A flat plate with a hole: the paper's flatness test alone leaves one tile over it; the build splits
// until no leaf covers it, and every node's gap is at least its children's.
TEST(CoverageGap, the_build_splits_clusters_whose_tiles_cover_a_hole)
{
    const PointCloud c = shapes::flat_plate(20000, outside_holes({{0.5, 0.5, 0.1}}));
    BuildOptions paper;
    paper.split_gaps = false;
    EXPECT_EQ(build_hierarchy(c, paper).nodes.size(), 1u);
    const Hierarchy h = build_hierarchy(c);
    EXPECT_GT(h.nodes.size(), 1u);
    EXPECT_GT(h.nodes[0].coverage_gap, 0.08);
    for (const Node& n : h.nodes) {
        if (n.is_leaf())
            EXPECT_EQ(n.coverage_gap, 0.0) << "a leaf of " << n.count() << " points";
        else
            EXPECT_GE(n.coverage_gap, std::max(h.nodes[static_cast<std::size_t>(n.left)].coverage_gap,
                                               h.nodes[static_cast<std::size_t>(n.right)].coverage_gap));
    }
}

// Without holes the tree is the same whether or not the build looks for them.
TEST(CoverageGap, clouds_without_holes_build_the_same_tree)
{
    for (const PointCloud& c : {shapes::torus(20000), shapes::sphere(10000), shapes::smooth_height_field(10000)}) {
        BuildOptions paper;
        paper.split_gaps = false;
        const Hierarchy a = build_hierarchy(c), b = build_hierarchy(c, paper);
        ASSERT_EQ(a.nodes.size(), b.nodes.size());
        for (std::size_t k = 0; k < a.nodes.size(); ++k) {
            EXPECT_EQ(a.nodes[k].begin, b.nodes[k].begin);
            EXPECT_EQ(a.nodes[k].end, b.nodes[k].end);
        }
        EXPECT_EQ(a.input_index, b.input_index);
    }
}

// Cuts refine flat nodes whose tiles would cover a hole wider than their limit, and only those.
TEST(CoverageGap, cuts_refine_nodes_by_their_gap)
{
    const Hierarchy h = build_hierarchy(shapes::flat_plate(20000, outside_holes({{0.5, 0.5, 0.1}})));
    EXPECT_EQ(cut_by_tolerance(h, 1.0).size(), 1u); // a limit above the gap: the root covers the hole
    const Cut fine = cut_by_tolerance(h, 0.001);
    EXPECT_GT(fine.size(), 1u);
    for (std::int32_t id : fine) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        EXPECT_TRUE(n.is_leaf() || n.coverage_gap <= 0.001 * h.scale);
    }
    // The budget cut weighs the gap like a plane distance: the root, exactly flat, is refined first.
    EXPECT_EQ(cut_by_budget(h, 2).size(), 2u);
    // A camera far enough away sees the hole below its pixel threshold, a near one above.
    Camera camera;
    camera.position = {0.5, 0.5, 100.0};
    EXPECT_LT(screen_space_error(h.nodes[0], camera), camera.max_pixel_error);
    camera.position = {0.5, 0.5, 2.0};
    EXPECT_GT(screen_space_error(h.nodes[0], camera), camera.max_pixel_error);
    EXPECT_GT(cut_for_camera(h, camera).size(), 1u);
}

// Whether p (in the plane z = 0) lies strictly inside the tile's outline.
bool inside_tile(const Hierarchy& h, const Tile& t, double x, double y)
{
    const std::size_t n = t.boundary.size();
    if (n < 3)
        return false;
    int sign = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3& a = h.cloud.positions[t.boundary[i]];
        const Vec3& b = h.cloud.positions[t.boundary[(i + 1) % n]];
        const double c = (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x);
        const int s = c > 0 ? 1 : (c < 0 ? -1 : 0);
        if (s == 0 || (sign != 0 && s != sign))
            return false;
        sign = s;
    }
    return true;
}

// A Voronoi cell can take in points across a hole from a neighbouring node, and its hull then covers
// the hole: such a tile keeps its own node's points. A plate with holes 12, 16 and 20 spacings wide:
// without the gaps measured a tile covers the middle of the widest; with them none does (the narrower
// ones are under what a tile's sample can see).
TEST(CoverageGap, tiles_whose_cells_reach_over_a_hole_keep_their_own_points)
{
    const std::size_t n = 60000;
    const double s = 1.0 / std::sqrt(static_cast<double>(n));
    const std::vector<Hole> holes{{0.5, 0.5, 6 * s}, {0.25, 0.75, 8 * s}, {0.75, 0.75, 10 * s}};
    const Hierarchy h = build_hierarchy(shapes::flat_plate(n, outside_holes(holes), 9));
    const Cut cut = cut_by_tolerance(h, 0.002);
    auto covering_widest = [&](const TileOptions& o) {
        std::size_t count = 0;
        for (const Tile& t : make_tiles(h, cut, o))
            count += inside_tile(h, t, holes[2].x, holes[2].y) ? 1 : 0;
        return count;
    };
    TileOptions unmeasured;
    unmeasured.measure_gaps = false;
    EXPECT_EQ(covering_widest(unmeasured), 1u);
    EXPECT_EQ(covering_widest(TileOptions{}), 0u);
}

// Holes 20 to 50 spacings wide in a flat plate stay open in the mesh, clean or noisy, at the default
// cut, and the rest of the plate is covered.
// widest_gap against sorting and scanning, on values built to tie: equal gaps everywhere (a grid),
// repeated values, two clusters, negative and huge values, and random ones.
TEST(CoverageGap, widest_gap_equals_sorting)
{
    auto sorted_scan = [](std::vector<double> v) {
        WidestGap g;
        if (v.size() < 2)
            return g;
        std::sort(v.begin(), v.end());
        g.extent = v.back() - v.front();
        g.from = v.front();
        for (std::size_t i = 1; i < v.size(); ++i)
            if (v[i] - v[i - 1] > g.width) {
                g.width = v[i] - v[i - 1];
                g.from = v[i - 1];
            }
        return g;
    };
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<std::vector<double>> cases{{}, {3.0}, {2.0, 2.0, 2.0}, {1.0, -1.0}, {0.0, 1.0, 2.0, 3.0, 4.0}};
    for (int n : {7, 100, 1001}) {
        std::vector<double> random, grid, repeated, clusters, huge;
        for (int i = 0; i < n; ++i) {
            random.push_back(u(rng));
            grid.push_back(0.1 * (i % 37)); // equal gaps: the lowest must win
            repeated.push_back(std::round(4.0 * u(rng)));
            clusters.push_back(i % 2 ? 100.0 + u(rng) : u(rng));
            huge.push_back(1e12 * u(rng) - 5e11);
        }
        std::shuffle(grid.begin(), grid.end(), rng);
        cases.insert(cases.end(), {random, grid, repeated, clusters, huge});
    }
    // Past 2^20 values widest_gap sorts (the buckets would take 4x the memory): both ways agree.
    std::vector<double> many(std::size_t{1} << 20 | 1);
    for (std::size_t i = 0; i < many.size(); ++i)
        many[i] = i % 3 ? u(rng) : 0.5 * std::round(8.0 * u(rng));
    cases.push_back(many);
    cases.push_back(std::vector<double>(many.begin(), many.end() - 1));
    for (std::size_t c = 0; c < cases.size(); ++c) {
        const WidestGap expected = sorted_scan(cases[c]), got = widest_gap(cases[c]);
        EXPECT_EQ(got.width, expected.width) << c;
        EXPECT_EQ(got.extent, expected.extent) << c;
        if (expected.width > 0.0) {
            EXPECT_EQ(got.from, expected.from) << c;
        }
    }
}

TEST(CoverageGap, holes_in_a_flat_plate_stay_open)
{
    const std::size_t n = 60000;
    const double s = 1.0 / std::sqrt(static_cast<double>(n));
    const std::vector<Hole> holes{{0.25, 0.25, 10 * s}, {0.75, 0.3, 15 * s}, {0.4, 0.72, 25 * s}};
    for (const bool noisy : {false, true}) {
        PointCloud c = shapes::flat_plate(n, outside_holes(holes), 3);
        if (noisy)
            shapes::add_noise(c, 0.3 * s);
        const Hierarchy h = build_hierarchy(c);
        const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.002));
        const TopologyStats t = topology_stats(r.mesh);
        EXPECT_EQ(t.nonmanifold_edges, 0u);
        EXPECT_EQ(t.nonmanifold_vertices, 0u);
        EXPECT_EQ(t.boundary_loops, 1 + holes.size()) << (noisy ? "noisy" : "clean");
        // Convex tiles larger than a hole can still reach over part of it: most of each hole is open.
        for (const Hole& hole : holes)
            EXPECT_LT(covered_share(r.mesh, hole), 0.5) << (noisy ? "noisy, " : "clean, ") << "hole of radius " << hole.r / s;
        EXPECT_FALSE(covered(r.mesh, holes[2].x, holes[2].y));
        EXPECT_TRUE(covered(r.mesh, 0.6, 0.55));
        double open = 0.0;
        for (const Hole& hole : holes)
            open += kPi * hole.r * hole.r;
        EXPECT_NEAR(projected_area(r.mesh), 1.0 - open, 0.02);
    }
}

// A wall with eight windows (the paper's flatness test makes the whole wall one tile): nine loops.
TEST(CoverageGap, windows_in_a_wall_stay_open)
{
    const auto keep = [](double x, double y) {
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 2; ++j) {
                const double wx = 0.1 + 0.225 * i, wy = 0.15 + 0.45 * j;
                if (x >= wx && x <= wx + 0.075 && y >= wy && y <= wy + 0.2)
                    return false;
            }
        return true;
    };
    const Hierarchy h = build_hierarchy(shapes::flat_plate(80000, keep, 4));
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.002));
    const TopologyStats t = topology_stats(r.mesh);
    EXPECT_EQ(t.boundary_loops, 9u);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_FALSE(covered(r.mesh, 0.1375, 0.25));
    EXPECT_NEAR(projected_area(r.mesh), 1.0 - 8 * 0.075 * 0.2, 0.02);
}

// The inside corner of an L-shaped plate is not filled.
TEST(CoverageGap, an_l_shaped_plate_keeps_its_notch)
{
    const Hierarchy h = build_hierarchy(shapes::flat_plate(45000, [](double x, double y) { return x < 0.5 || y < 0.5; }));
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.002));
    EXPECT_EQ(topology_stats(r.mesh).boundary_loops, 1u);
    EXPECT_FALSE(covered(r.mesh, 0.75, 0.75));
    EXPECT_FALSE(covered(r.mesh, 0.6, 0.6));
    EXPECT_NEAR(projected_area(r.mesh), 0.75, 0.01);
}

// A flat L-shaped sample cut into a few tiles: every tile is meshed. Jittered grids (spacing 0.01)
// are split along a diagonal into two tiles whose hulls can lie a sliver apart; both fans then stood
// alone, and the one drop_islands had not taken for the island was dropped as "covered by the rest",
// half the sample with it (QA round 40: 3,128 of 7,652 points far from the mesh). Seeds 29, 39 and 48
// of these did so (5 of seeds 1-200).
TEST(CoverageGap, every_tile_of_a_coarse_l_shaped_plate_is_meshed)
{
    for (std::uint32_t seed = 21; seed <= 50; ++seed) {
        PointCloud cloud;
        std::mt19937 random(seed);
        std::uniform_real_distribution<double> jitter(-0.0015, 0.0015);
        for (int i = 0; i <= 100; ++i)
            for (int j = 0; j <= 100; ++j) {
                const double x = 0.01 * i + jitter(random), y = 0.01 * j + jitter(random);
                if (x <= 0.5 || y <= 0.5)
                    cloud.positions.push_back({x, y, 0.0});
            }
        const Hierarchy h = build_hierarchy(cloud);
        const Cut cut = cut_by_tolerance(h, 0.005);
        const MeshResult r = mesh_cut(h, cut);
        const QualityReport q = measure_quality(h, r.cut, r.mesh);
        EXPECT_LT(q.point_to_mesh.max, 0.01) << "seed " << seed << ", " << cut.size() << " tiles"; // of the diagonal
        EXPECT_NEAR(projected_area(r.mesh), 0.75, 0.03) << "seed " << seed;
        EXPECT_EQ(q.topology.nonmanifold_edges + q.topology.nonmanifold_vertices, 0u) << "seed " << seed;
    }
}
} // namespace
} // namespace mrt
