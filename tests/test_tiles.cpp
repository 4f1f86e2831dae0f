// Tests of tiles.h: the tile outline is the convex hull of the projected cluster (brute-force
// cross-check), counter-clockwise seen from the normal, strictly convex; degenerate clusters.
#include "libmrtile/tiles.h"

#include "cut_fixtures.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>

namespace mrt {
namespace {

// One-node hierarchy over the given points.
Hierarchy single_node(const std::vector<Vec3>& points)
{
    PointCloud c;
    c.positions = points;
    return testing::hierarchy_from_labels(c, std::vector<std::uint32_t>(points.size(), 0)).hierarchy;
}

std::pair<double, double> uv(const Hierarchy& h, const Tile& t, std::uint32_t i)
{
    const Vec3 d = h.cloud.positions[i] - t.centre;
    return {dot(d, t.axis_u), dot(d, t.axis_v)};
}

double turn(std::pair<double, double> o, std::pair<double, double> a, std::pair<double, double> b)
{
    return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
}

// Directed hull edges by brute force: i -> j is an edge when every other point is strictly to its left
// (points in general position: no three collinear).
std::set<std::pair<std::uint32_t, std::uint32_t>> brute_force_hull(const Hierarchy& h, const Tile& t)
{
    std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
    const std::uint32_t n = static_cast<std::uint32_t>(h.cloud.size());
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t j = 0; j < n; ++j) {
            if (i == j)
                continue;
            bool all_left = true;
            for (std::uint32_t k = 0; k < n && all_left; ++k)
                if (k != i && k != j)
                    all_left = turn(uv(h, t, i), uv(h, t, j), uv(h, t, k)) > 0;
            if (all_left)
                edges.insert({i, j});
        }
    return edges;
}

TEST(Tiles, hull_matches_brute_force_on_random_tilted_clusters)
{
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
        const Vec3 n = normalized(Vec3{u(rng), u(rng), u(rng)});
        const Vec3 a = normalized(cross(n, Vec3{0.3, 0.5, 0.8}));
        const Vec3 b = cross(n, a);
        std::vector<Vec3> pts;
        const int count = 10 + trial * 3;
        for (int i = 0; i < count; ++i)
            pts.push_back(Vec3{2, -1, 5} + a * u(rng) + b * (0.5 * u(rng)) + n * (0.01 * u(rng)));
        const Hierarchy h = single_node(pts);
        const Tile t = make_tile(h, 0);
        ASSERT_TRUE(t.has_fan());
        EXPECT_NEAR(dot(cross(t.axis_u, t.axis_v), t.normal), 1.0, 1e-12);
        EXPECT_NEAR(std::abs(dot(t.normal, n)), 1.0, 1e-3);
        std::set<std::pair<std::uint32_t, std::uint32_t>> got;
        const std::size_t m = t.boundary.size();
        double twice_area = 0.0;
        for (std::size_t i = 0; i < m; ++i) {
            const std::uint32_t p = t.boundary[i], q = t.boundary[(i + 1) % m], r = t.boundary[(i + 2) % m];
            got.insert({p, q});
            EXPECT_GT(turn(uv(h, t, p), uv(h, t, q), uv(h, t, r)), 0.0) << "not strictly convex / CCW";
            twice_area += uv(h, t, p).first * uv(h, t, q).second - uv(h, t, p).second * uv(h, t, q).first;
        }
        EXPECT_EQ(got, brute_force_hull(h, t)) << "trial " << trial;
        EXPECT_NEAR(t.area, 0.5 * twice_area, 1e-12);
        EXPECT_GT(t.area, 0.0);
        EXPECT_EQ(t.points, static_cast<std::uint32_t>(count));
    }
}

// node_hull (read from the model or computed with its octagon and 16-gon filters) against a gift
// wrapping of all of the node's points in the same plane coordinates, on every node of more than
// kHullStoredAbove points of a noisy torus and of a sphere: the same points.
TEST(Tiles, node_hull_matches_gift_wrapping)
{
    for (int shape = 0; shape < 2; ++shape) {
        PointCloud cloud = shape == 0 ? shapes::torus(6000) : shapes::sphere(5000);
        shapes::add_noise(cloud, 0.002);
        Hierarchy h = build_hierarchy(cloud);
        Hierarchy stored = h;
        set_node_hulls(stored);
        std::size_t checked = 0;
        for (std::size_t k = 0; k < h.nodes.size(); ++k) {
            const Node& n = h.nodes[k];
            if (n.count() <= kHullStoredAbove)
                continue;
            const Vec3 u = n.frame.vectors[2], v = cross(n.frame.vectors[0], u);
            std::vector<std::pair<double, double>> p;
            for (std::uint32_t i = n.begin; i < n.end; ++i)
                p.push_back({dot(h.cloud.positions[i] - n.moments.mean, u), dot(h.cloud.positions[i] - n.moments.mean, v)});
            // Gift wrapping from the leftmost point: the next corner has every other point to its left.
            std::size_t first = 0;
            for (std::size_t j = 1; j < p.size(); ++j)
                if (p[j] < p[first])
                    first = j;
            std::vector<std::uint32_t> expected;
            std::size_t at = first;
            do {
                expected.push_back(n.begin + static_cast<std::uint32_t>(at));
                std::size_t next = at == 0 ? 1 : 0;
                for (std::size_t j = 0; j < p.size(); ++j)
                    if (j != at && turn(p[at], p[next], p[j]) < 0.0)
                        next = j;
                at = next;
            } while (at != first && expected.size() <= p.size());
            std::sort(expected.begin(), expected.end());
            EXPECT_EQ(node_hull(h, static_cast<std::int32_t>(k)), expected) << "shape " << shape << " node " << k;
            EXPECT_EQ(node_hull(stored, static_cast<std::int32_t>(k)), expected) << "shape " << shape << " node " << k;
            ++checked;
        }
        EXPECT_GT(checked, 10u);
    }
}

TEST(Tiles, collinear_hull_points_are_dropped)
{
    // A 5 x 5 grid: the hull is the 4 corners, the 12 other border points are collinear.
    std::vector<Vec3> pts;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j)
            pts.push_back({double(i), double(j), 0.0});
    const Hierarchy h = single_node(pts);
    const Tile t = make_tile(h, 0);
    ASSERT_EQ(t.boundary.size(), 4u);
    for (std::uint32_t i : t.boundary) {
        const Vec3& p = h.cloud.positions[i];
        EXPECT_TRUE((p.x == 0 || p.x == 4) && (p.y == 0 || p.y == 4));
    }
    EXPECT_NEAR(t.area, 16.0, 1e-9);
}

TEST(Tiles, hull_of_points_on_a_convex_curve_is_thinned)
{
    // Every point of a circle is a hull point: a tile of 1,000 of them had a fan of 1,000 faces, all
    // sharing the apex, whose self-intersection tests cost the square of that (QA round qa-adv: a
    // 40,000-point circle took 96 s to mesh). The outline keeps at most 128 of them, strictly convex and
    // counter-clockwise, and loses a sliver of the disc only.
    const int n = 1000;
    const double pi = std::acos(-1.0);
    std::vector<Vec3> pts;
    for (int i = 0; i < n; ++i)
        pts.push_back({std::cos(2.0 * pi * i / n), std::sin(2.0 * pi * i / n), 0.0});
    const Hierarchy h = single_node(pts);
    const Tile t = make_tile(h, 0);
    ASSERT_TRUE(t.has_fan());
    ASSERT_LE(t.boundary.size(), 128u);
    ASSERT_GE(t.boundary.size(), 100u);
    const std::size_t m = t.boundary.size();
    double largest_gap = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
        const std::uint32_t p = t.boundary[i], q = t.boundary[(i + 1) % m], r = t.boundary[(i + 2) % m];
        EXPECT_GT(turn(uv(h, t, p), uv(h, t, q), uv(h, t, r)), 0.0) << "not strictly convex / CCW";
        largest_gap = std::max(largest_gap, norm(h.cloud.positions[q] - h.cloud.positions[p]));
    }
    // Evenly thinned: no chord much longer than the regular 128-gon's (2 sin(pi / 128)), so every
    // dropped point lies within the chord's sagitta (about 3e-4 here) of the outline.
    EXPECT_LT(largest_gap, 2.0 * 2.0 * std::sin(pi / 128));
    EXPECT_GT(t.area, pi * (1.0 - 2e-3));
    EXPECT_LT(t.area, pi);
}

TEST(Tiles, degenerate_clusters_have_no_fan)
{
    EXPECT_EQ(make_tile(single_node({{1, 2, 3}}), 0).boundary.size(), 1u);
    const Tile two = make_tile(single_node({{0, 0, 0}, {1, 1, 0}}), 0);
    EXPECT_EQ(two.boundary.size(), 2u);
    EXPECT_FALSE(two.has_fan());
    std::vector<Vec3> line;
    for (int i = 0; i < 9; ++i)
        line.push_back(Vec3{1, 2, 2} * (i * 0.25));
    const Hierarchy hl = single_node(line);
    const Tile t = make_tile(hl, 0);
    ASSERT_EQ(t.boundary.size(), 2u);
    EXPECT_FALSE(t.has_fan());
    std::set<double> ends{hl.cloud.positions[t.boundary[0]].x, hl.cloud.positions[t.boundary[1]].x};
    EXPECT_EQ(ends, (std::set<double>{0.0, 2.0}));
    EXPECT_EQ(make_tile(single_node({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}), 0).boundary.size(), 1u);
}

// Without the Voronoi partition a tile is exactly its node (the paper's literal tile).
TEST(Tiles, untrimmed_tiles_use_their_own_points)
{
    const testing::FlatCut fc = testing::kmeans_cut(shapes::sphere(3000), 40);
    TileOptions literal;
    literal.voronoi_trim = false;
    const std::vector<Tile> tiles = make_tiles(fc.hierarchy, fc.cut, literal);
    ASSERT_EQ(tiles.size(), fc.cut.size());
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const Node& n = fc.hierarchy.nodes[static_cast<std::size_t>(fc.cut[k])];
        EXPECT_EQ(tiles[k].node, fc.cut[k]);
        EXPECT_EQ(tiles[k].centre, n.moments.mean);
        EXPECT_EQ(tiles[k].points, n.count());
        EXPECT_TRUE(tiles[k].neighbours.empty());
        ASSERT_TRUE(tiles[k].has_fan());
        for (std::uint32_t i : tiles[k].boundary) {
            EXPECT_GE(i, n.begin);
            EXPECT_LT(i, n.end);
        }
    }
    EXPECT_THROW(make_tiles(fc.hierarchy, {static_cast<std::int32_t>(fc.hierarchy.nodes.size())}), InvalidInput);
    EXPECT_THROW(make_tiles(fc.hierarchy, {-1}), InvalidInput);
}

// Default tiles are the Voronoi cells of the cut's centres (brute-force nearest centre), they
// partition the points, and neighbours are symmetric.
TEST(Tiles, trimmed_tiles_are_voronoi_cells)
{
    // A few Lloyd steps only: the node means are not the centres the labels came from, so many points
    // are nearer to another node's mean than to their own.
    const testing::FlatCut fc = testing::kmeans_cut(shapes::torus(4000), 60, 1);
    const Hierarchy& h = fc.hierarchy;
    TileOptions every_point;
    every_point.max_points = 0;
    const std::vector<Tile> tiles = make_tiles(h, fc.cut, every_point);
    ASSERT_EQ(tiles.size(), fc.cut.size());
    auto nearest = [&](const Vec3& p) {
        std::size_t best = 0;
        for (std::size_t k = 1; k < tiles.size(); ++k)
            if (squared_distance(p, tiles[k].centre) < squared_distance(p, tiles[best].centre))
                best = k;
        return best;
    };
    std::size_t total = 0, moved = 0;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const Node& n = h.nodes[static_cast<std::size_t>(fc.cut[k])];
        EXPECT_EQ(tiles[k].centre, n.moments.mean);
        total += tiles[k].points;
        for (std::uint32_t i : tiles[k].boundary) {
            EXPECT_EQ(nearest(h.cloud.positions[i]), k);
            moved += (i < n.begin || i >= n.end) ? 1 : 0;
        }
        for (std::uint32_t j : tiles[k].neighbours) {
            EXPECT_NE(j, k);
            EXPECT_TRUE(std::binary_search(tiles[j].neighbours.begin(), tiles[j].neighbours.end(), static_cast<std::uint32_t>(k)));
        }
        EXPECT_TRUE(std::is_sorted(tiles[k].neighbours.begin(), tiles[k].neighbours.end()));
    }
    EXPECT_EQ(total, h.cloud.size());
    EXPECT_GT(moved, 0u) << "the fixture should have points outside their node's cell";
    // On a closed surface every tile is surrounded: at least three neighbours each, about six on average.
    std::size_t degree = 0;
    for (const Tile& t : tiles) {
        EXPECT_GE(t.neighbours.size(), 3u);
        degree += t.neighbours.size();
    }
    EXPECT_NEAR(static_cast<double>(degree) / static_cast<double>(tiles.size()), 6.0, 1.0);
}

// With TileOptions::meet_factor (thin walls), the two sides of a wall (two planes 5 point spacings apart)
// are no surface neighbours: the bisector of a tile above and one below, set apart along the planes,
// crosses both planes, so both cells have points at it (by default 556 such pairs of 2,608), but the
// points of one never come near the other's. A tile whose node holds points of both planes is left out.
TEST(Tiles, the_sides_of_a_thin_wall_are_no_neighbours)
{
    const std::size_t per_plane = 8000;
    const double gap = 5.0 / std::sqrt(static_cast<double>(per_plane)); // 5 spacings of a unit square
    const Hierarchy h = build_hierarchy(shapes::parallel_planes(per_plane, gap));
    const Cut cut = cut_by_tolerance(h, 0.002);
    const auto side = [&](std::size_t k) { // 0 or 1 (the plane), 2: both
        const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
        bool low = false, high = false;
        for (std::uint32_t i = n.begin; i < n.end; ++i)
            (h.cloud.positions[i].z + h.cloud.origin.z < 0.5 * gap ? low : high) = true;
        return low && high ? 2 : high ? 1 : 0;
    };
    const auto across = [&](const TileOptions& options, std::size_t& pairs) {
        const std::vector<Tile> tiles = make_tiles(h, cut, options);
        std::size_t count = 0;
        pairs = 0;
        for (std::size_t k = 0; k < tiles.size(); ++k)
            for (std::uint32_t j : tiles[k].neighbours) {
                ++pairs;
                count += side(k) != 2 && side(j) != 2 && side(k) != side(j) ? 1 : 0;
            }
        return count;
    };
    TileOptions thin_walls;
    thin_walls.meet_factor = kThinWallMeetFactor;
    std::size_t pairs = 0, pairs_before = 0;
    EXPECT_GT(across(TileOptions{}, pairs_before), 100u) << "the fixture should have tiles witnessed across the wall";
    EXPECT_EQ(across(thin_walls, pairs), 0u);
    // Neighbours along each plane stay: about six per tile.
    EXPECT_GT(pairs, 5 * cut.size());
    TileOptions negative;
    negative.meet_factor = -1.0;
    EXPECT_THROW(make_tiles(h, cut, negative), InvalidInput);
}

// Without fitting, the apex (the fan's centre vertex) lies on the surface: on a unit sphere it is much
// nearer to the sphere than the patch's mean, which sits below the cap.
TEST(Tiles, apex_lies_on_a_curved_surface)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(20000));
    TileOptions on_surface;
    on_surface.fit_apex = false;
    const std::vector<Tile> tiles = make_tiles(h, cut_by_budget(h, 60), on_surface);
    double apex_error = 0.0, mean_error = 0.0;
    for (const Tile& t : tiles) {
        apex_error += std::abs(norm(t.apex) - 1.0);
        mean_error += std::abs(norm(t.centre) - 1.0);
        EXPECT_LE(norm(cross(t.apex - t.centre, t.normal)), 1e-12);
    }
    EXPECT_LT(apex_error, 0.25 * mean_error);
}

// The fitted apex of a cap lies above the sphere: for a cap of sag s the least-squares cone puts it
// 0.4 s above the surface, and the mean lies about 2/3 s below it, so the ratio of the two heights is
// about 0.6 for a round cap (0.85 measured on these polygonal Voronoi cells: a loose band).
TEST(Tiles, fitted_apex_lies_above_a_cap)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(20000));
    const std::vector<Tile> tiles = make_tiles(h, cut_by_budget(h, 60));
    double ratio = 0.0;
    for (const Tile& t : tiles) {
        EXPECT_GT(norm(t.apex), 1.0);
        EXPECT_LE(norm(cross(t.apex - t.centre, t.normal)), 1e-12);
        ratio += (norm(t.apex) - 1.0) / (1.0 - norm(t.centre));
    }
    ratio /= static_cast<double>(tiles.size());
    EXPECT_GT(ratio, 0.4);
    EXPECT_LT(ratio, 1.3);
}

} // namespace
} // namespace mrt

namespace mrt {
namespace {

// Sampled tiles (TileOptions::max_points): every k-th point of each cut node, k = ceil(count / max), and
// the node's own hull points. Brute force: each hull point of a tile is such a point and its nearest cut
// centre is its tile's, the tiles hold about the whole sample, and a tile's hull is inside the hull of
// the same cell with every point (the sample of a cell is a subset of the cell).
TEST(Tiles, sampled_tiles_are_voronoi_cells_of_the_sample)
{
    const testing::FlatCut fc = testing::kmeans_cut(shapes::torus(20000), 40, 1);
    const Hierarchy& h = fc.hierarchy;
    TileOptions sampled, every_point;
    sampled.max_points = 64;
    every_point.max_points = 0;
    const std::vector<Tile> tiles = make_tiles(h, fc.cut, sampled);
    const std::vector<Tile> full = make_tiles(h, fc.cut, every_point);
    ASSERT_EQ(tiles.size(), fc.cut.size());
    std::vector<bool> in_sample(h.cloud.size(), false);
    std::size_t sample = 0;
    for (const std::int32_t id : fc.cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        const std::uint32_t stride = (n.count() + 63) / 64;
        ASSERT_GT(stride, 1u) << "the fixture's nodes should be larger than the sample";
        for (std::uint32_t i = n.begin; i < n.end; i += stride)
            in_sample[i] = true;
        for (std::uint32_t i : make_tile(h, id, every_point).boundary) // the node's hull
            in_sample[i] = true;
    }
    for (bool b : in_sample)
        sample += b ? 1 : 0;
    std::size_t total = 0;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        total += tiles[k].points;
        EXPECT_LT(tiles[k].points, full[k].points);
        for (std::uint32_t i : tiles[k].boundary) {
            EXPECT_TRUE(in_sample[i]) << "hull point " << i << " is not in the sample";
            std::size_t best = 0;
            for (std::size_t j = 1; j < tiles.size(); ++j)
                if (squared_distance(h.cloud.positions[i], tiles[j].centre) < squared_distance(h.cloud.positions[i], tiles[best].centre))
                    best = j;
            EXPECT_EQ(best, k);
        }
        EXPECT_LE(tiles[k].area, full[k].area * (1 + 1e-12));
        EXPECT_GT(tiles[k].area, 0.5 * full[k].area);
    }
    // The node hulls found by the octagon filter may keep a nearly collinear point that the tiles' hull
    // tolerance drops: the tiles hold the sample, give or take such points.
    EXPECT_GE(total, sample);
    EXPECT_LE(total, sample + sample / 100);
}

// A sampled tile at an open border still reaches it: one tile over a flat square has the square's
// corners whatever the sample, so the sample does not shrink the surface.
TEST(Tiles, sampled_tile_keeps_the_border_of_its_node)
{
    const Hierarchy h = build_hierarchy(shapes::plane_grid(60));
    TileOptions sampled, every_point;
    sampled.max_points = 32;
    every_point.max_points = 0;
    const Tile a = make_tiles(h, {0}, sampled).front();
    const Tile b = make_tiles(h, {0}, every_point).front();
    EXPECT_LT(a.points, b.points / 10);
    EXPECT_EQ(a.boundary.size(), 4u);
    EXPECT_NEAR(a.area, b.area, 1e-12);
    EXPECT_NEAR(a.area, 1.0, 1e-12);
}

// A stray far off a tile's plane (a bird over a terrain) does not shape its outline: the pseudo tile
// maps hull points back to where they were sampled, so a stray on the hull was a fan corner far off the
// surface (QA round 60: spikes and tents up to 46 m over a 100 m terrain at tolerance 0.02). Points
// whose heights run on from the rest (a ridge) or too many to be strays (two ledges) keep their place.
TEST(Tiles, a_stray_far_off_the_plane_does_not_shape_the_outline)
{
    std::vector<Vec3> plane;
    for (int i = 0; i <= 30; ++i)
        for (int j = 0; j <= 30; ++j)
            plane.push_back({i / 30.0, j / 30.0, 0.0});
    const auto highest_hull_point = [](const std::vector<Vec3>& points) {
        const Hierarchy h = single_node(points);
        TileOptions every_point;
        every_point.max_points = 0;
        const Tile t = make_tiles(h, {0}, every_point).front();
        double highest = -std::numeric_limits<double>::infinity(), farthest = 0.0;
        for (const std::uint32_t i : t.boundary) {
            highest = std::max(highest, h.cloud.positions[i].z + h.cloud.origin.z);
            farthest = std::max(farthest, h.cloud.positions[i].x + h.cloud.origin.x);
        }
        return std::tuple{highest, t, farthest};
    };
    // The stray lies outside the plane's square, so that it is on the hull of the projected points.
    std::vector<Vec3> with_stray = plane;
    with_stray.push_back({1.3, 0.5, 0.6});
    const auto [stray_height, stray_tile, stray_x] = highest_hull_point(with_stray);
    EXPECT_LT(stray_height, 0.05);
    EXPECT_EQ(stray_x, 1.0);
    EXPECT_EQ(stray_tile.boundary.size(), 4u);
    EXPECT_GT(stray_tile.area, 0.99);
    EXPECT_LT(std::abs(dot(stray_tile.apex - stray_tile.centre, stray_tile.normal)), 0.01);
    // A small tile (a 4 x 3 patch) that took in a bird: one point in 13 is too many for the height test,
    // but the bird stands apart from every other point (a small tile leans to it, QA round 60 at 0.005).
    std::vector<Vec3> patch;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 3; ++j)
            patch.push_back({0.5 * i, 0.5 * j, 0.0});
    patch.push_back({2.5, 0.5, 3.0});
    const auto [patch_height, patch_tile, patch_x] = highest_hull_point(patch);
    EXPECT_EQ(patch_height, 0.0);
    EXPECT_EQ(patch_tile.boundary.size(), 4u);
    EXPECT_EQ(patch_x, 1.5);
    // The same patch with a point as far out on its plane: a sparse sample of the surface, kept (QA
    // round 63).
    std::vector<Vec3> far_on_the_plane = patch;
    far_on_the_plane.back() = {4.5, 0.5, 0.0};
    EXPECT_EQ(std::get<2>(highest_hull_point(far_on_the_plane)), 4.5);
    // A ridge of 15 points (1.5%) running on from the plane up to the same height: no gap in the heights.
    std::vector<Vec3> ridge = plane;
    for (int i = 1; i <= 15; ++i)
        ridge.push_back({1.0 + i / 50.0, 0.5, 0.6 * i / 15.0});
    EXPECT_GT(std::get<0>(highest_hull_point(ridge)), 0.5);
    // Two ledges of 20 points each (4% in all), 0.6 up on either side: too many to be strays.
    std::vector<Vec3> ledges = plane;
    for (int i = 1; i <= 4; ++i)
        for (int j = 0; j < 5; ++j) {
            ledges.push_back({-i / 30.0, 0.4 + j / 30.0, 0.6});
            ledges.push_back({1.0 + i / 30.0, 0.4 + j / 30.0, 0.6});
        }
    EXPECT_GT(std::get<0>(highest_hull_point(ledges)), 0.5);
}

// QA round qa3: TileOptions::plane_axis of any non-zero length is the axis. One of 1e-300 (its squared
// norm underflows) was taken for none, one of 1e300 (its norm overflows) made NaN planes and mesh_cut
// blamed the cut; an infinite collinear_tolerance dropped every hull point the same way.
TEST(Tiles, plane_axis_of_any_length_and_finite_collinear_tolerance)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(3000));
    const Cut cut = cut_by_tolerance(h, 0.02);
    TileOptions unit;
    unit.plane_axis = {0, 0, 1};
    const std::vector<Tile> expected = make_tiles(h, cut, unit);
    for (const double scale : {1e-300, 1e-160, 1e160, 1e300}) {
        TileOptions scaled;
        scaled.plane_axis = unit.plane_axis * scale;
        const std::vector<Tile> tiles = make_tiles(h, cut, scaled);
        ASSERT_EQ(tiles.size(), expected.size());
        for (std::size_t k = 0; k < tiles.size(); ++k) {
            EXPECT_EQ(tiles[k].normal.z, expected[k].normal.z) << scale;
            EXPECT_EQ(tiles[k].boundary, expected[k].boundary) << scale;
        }
    }
    TileOptions infinite;
    infinite.collinear_tolerance = std::numeric_limits<double>::infinity();
    EXPECT_THROW(make_tiles(h, cut, infinite), InvalidInput);
}

} // namespace
} // namespace mrt
