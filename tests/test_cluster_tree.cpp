// Tests of cluster_tree.h (paper §4.1): the invariants of the persistent hierarchy on analytic shapes,
// checked against brute-force recomputation.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/errors.h"
#include "libmrtile/model_file.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace mrt {
namespace {

// Nodes of the frontier "depth d": nodes at depth d, plus leaves above it.
std::vector<std::int32_t> cut_at_depth(const Hierarchy& h, std::uint32_t d)
{
    std::vector<std::int32_t> cut;
    for (std::size_t k = 0; k < h.nodes.size(); ++k)
        if (h.nodes[k].depth == d || (h.nodes[k].depth < d && h.nodes[k].is_leaf()))
            cut.push_back(static_cast<std::int32_t>(k));
    return cut;
}

// Every point index in [0, n) is covered by exactly one node of the cut.
void expect_partition(const Hierarchy& h, const std::vector<std::int32_t>& cut)
{
    std::vector<int> covered(h.cloud.size(), 0);
    for (std::int32_t k : cut)
        for (std::uint32_t i = h.nodes[static_cast<std::size_t>(k)].begin; i < h.nodes[static_cast<std::size_t>(k)].end; ++i)
            ++covered[i];
    EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }));
}

void expect_valid_tree(const Hierarchy& h)
{
    ASSERT_FALSE(h.nodes.empty());
    EXPECT_EQ(h.nodes[0].begin, 0u);
    EXPECT_EQ(h.nodes[0].end, h.cloud.size());
    EXPECT_EQ(h.nodes[0].parent, -1);
    for (std::size_t k = 0; k < h.nodes.size(); ++k) {
        const Node& n = h.nodes[k];
        EXPECT_GT(n.count(), 0u);
        EXPECT_EQ(n.moments.count, n.count());
        if (n.is_leaf()) {
            EXPECT_EQ(n.right, -1);
            continue;
        }
        ASSERT_GT(n.left, static_cast<std::int32_t>(k));
        ASSERT_GT(n.right, static_cast<std::int32_t>(k));
        const Node& l = h.nodes[static_cast<std::size_t>(n.left)];
        const Node& r = h.nodes[static_cast<std::size_t>(n.right)];
        EXPECT_EQ(l.parent, static_cast<std::int32_t>(k));
        EXPECT_EQ(r.parent, static_cast<std::int32_t>(k));
        EXPECT_EQ(l.depth, n.depth + 1);
        EXPECT_EQ(l.begin, n.begin);
        EXPECT_EQ(l.end, r.begin);
        EXPECT_EQ(r.end, n.end);
    }
    std::vector<std::uint32_t> sorted = h.input_index;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t i = 0; i < sorted.size(); ++i)
        ASSERT_EQ(sorted[i], i);
}

// Every point lands in exactly one leaf, and every depth-cut partitions the points.
TEST(ClusterTree, leaves_and_depth_cuts_partition_points)
{
    const Hierarchy h = build_hierarchy(shapes::torus(20000), {});
    expect_valid_tree(h);
    std::vector<std::int32_t> leaves;
    for (std::size_t k = 0; k < h.nodes.size(); ++k)
        if (h.nodes[k].is_leaf())
            leaves.push_back(static_cast<std::int32_t>(k));
    EXPECT_GT(leaves.size(), 50u);
    expect_partition(h, leaves);
    for (std::uint32_t d = 0; d <= h.max_depth(); d += 3)
        expect_partition(h, cut_at_depth(h, d));
}

// Stored statistics equal a brute-force recomputation over each node's points.
TEST(ClusterTree, node_statistics_match_brute_force)
{
    PointCloud cloud = shapes::sphere(8000, 2.0);
    shapes::add_noise(cloud, 0.002);
    const Hierarchy h = build_hierarchy(cloud, {});
    for (const Node& n : h.nodes) {
        std::vector<Vec3> pts(h.cloud.positions.begin() + n.begin, h.cloud.positions.begin() + n.end);
        Vec3 sum{0, 0, 0};
        for (const Vec3& p : pts)
            sum += p;
        const Vec3 mean = sum / static_cast<double>(pts.size());
        double m2[6] = {0, 0, 0, 0, 0, 0}, eq1 = 0;
        for (const Vec3& p : pts) {
            const Vec3 d = p - mean;
            m2[0] += d.x * d.x, m2[1] += d.x * d.y, m2[2] += d.x * d.z;
            m2[3] += d.y * d.y, m2[4] += d.y * d.z, m2[5] += d.z * d.z;
            eq1 += norm(d);
        }
        const double scale = m2[0] + m2[3] + m2[5] + 1e-300;
        for (int i = 0; i < 3; ++i)
            EXPECT_NEAR(n.moments.mean[i], mean[i], 1e-12);
        for (std::size_t i = 0; i < 6; ++i)
            EXPECT_NEAR(n.moments.m2[i], m2[i], 1e-10 * scale);
        EXPECT_NEAR(n.internal_error, eq1, 1e-9 * (eq1 + 1e-300));
        double max_plane = 0;
        for (const Vec3& p : pts)
            max_plane = std::max(max_plane, std::abs(dot(p - n.centre(), n.frame.vectors[0])));
        EXPECT_NEAR(n.max_plane_distance, max_plane, 1e-12);
        const BoundingBox box = bounding_box(pts);
        EXPECT_EQ(n.box.min, box.min);
        EXPECT_EQ(n.box.max, box.max);
    }
}

// Splitting never increases the global error: the children's summed squared distances to their own
// centres never exceed the parent's (the centroid minimises it). The paper's eq. 1 (unsquared) is the
// split order; its monotonicity is not guaranteed for arbitrary sets, the squared form is.
TEST(ClusterTree, global_error_never_increases_with_a_split)
{
    PointCloud cloud = shapes::three_holes(6000);
    const Hierarchy h = build_hierarchy(cloud, {});
    for (const Node& n : h.nodes) {
        if (n.is_leaf())
            continue;
        const double children = h.nodes[static_cast<std::size_t>(n.left)].moments.sum_squared_distances() +
                                h.nodes[static_cast<std::size_t>(n.right)].moments.sum_squared_distances();
        EXPECT_LE(children, n.moments.sum_squared_distances() * (1 + 1e-12));
    }
}

// Every leaf meets the stop criterion (scale-free tolerance) or is at most min_cluster points.
TEST(ClusterTree, leaves_meet_tolerance_or_min_size)
{
    PointCloud cloud = shapes::sphere(15000);
    shapes::add_noise(cloud, 0.001);
    BuildOptions o;
    o.tolerance = 2e-3;
    o.min_cluster = 12;
    const Hierarchy h = build_hierarchy(cloud, o);
    const double side = h.scale;
    std::size_t leaves = 0;
    for (const Node& n : h.nodes)
        if (n.is_leaf()) {
            ++leaves;
            EXPECT_TRUE(n.count() <= o.min_cluster || n.rms_plane_distance <= o.tolerance * side * (1 + 1e-9))
                << "leaf with " << n.count() << " points, rms " << n.rms_plane_distance;
        }
    EXPECT_GT(leaves, 10u);
    EXPECT_EQ(h.info.criterion, Criterion::Tolerance);
}

// The paper's τ criterion: every leaf's smallest eigenvalue of ΔᵀΔ is at most τ (or it is tiny).
TEST(ClusterTree, leaves_meet_tau)
{
    const Hierarchy h = build_hierarchy(shapes::torus(10000), [] {
        BuildOptions o;
        o.tau = 1e-3;
        return o;
    }());
    EXPECT_EQ(h.info.criterion, Criterion::Tau);
    for (const Node& n : h.nodes) {
        if (n.is_leaf()) {
            EXPECT_TRUE(n.count() <= BuildOptions{}.min_cluster || n.frame.values[0] <= 1e-3 * (1 + 1e-9));
        }
    }
    // A larger τ gives a coarser hierarchy.
    BuildOptions coarse;
    coarse.tau = 1e-1;
    EXPECT_LT(build_hierarchy(shapes::torus(10000), coarse).leaf_count(), h.leaf_count());
}

// The paper's literal order (split the highest-error cluster while any fails) refines flat regions
// too: more leaves than the adaptive default, and still every leaf meets τ or the minimum size.
TEST(ClusterTree, paper_split_order_gives_more_uniform_tiles)
{
    PointCloud c = shapes::three_holes(8000);
    BuildOptions o;
    o.tau = 50.0;
    const Hierarchy adaptive = build_hierarchy(c, o);
    o.paper_split_order = true;
    const Hierarchy literal = build_hierarchy(c, o);
    expect_valid_tree(literal);
    EXPECT_GT(literal.leaf_count(), adaptive.leaf_count());
    for (const Node& n : literal.nodes) {
        if (n.is_leaf()) {
            EXPECT_TRUE(n.count() <= o.min_cluster || n.frame.values[0] <= o.tau * (1 + 1e-9));
        }
    }
}

// A flat grid is one cluster: nothing to split.
TEST(ClusterTree, flat_grid_is_one_leaf)
{
    const Hierarchy h = build_hierarchy(shapes::plane_grid(100), {});
    EXPECT_EQ(h.nodes.size(), 1u);
    EXPECT_EQ(h.leaf_count(), 1u);
    EXPECT_EQ(h.nodes[0].count(), 10000u);
}

// Two parallel planes 0.05 apart never share a leaf at a tight tolerance (min_cluster 3: any three
// points are coplanar, so only the flatness test decides).
TEST(ClusterTree, parallel_planes_never_share_a_leaf)
{
    const Hierarchy h = build_hierarchy(shapes::parallel_planes(10000, 0.05), [] {
        BuildOptions o;
        o.tolerance = 1e-3;
        o.min_cluster = 3;
        return o;
    }());
    for (const Node& n : h.nodes) {
        if (!n.is_leaf())
            continue;
        const double z = h.cloud.positions[n.begin].z;
        for (std::uint32_t i = n.begin; i < n.end; ++i)
            ASSERT_EQ(h.cloud.positions[i].z, z) << "leaf mixes both planes";
    }
}

// Reclassification off still gives a valid tree; on, it never breaks the invariants either.
TEST(ClusterTree, without_reclassification_tree_is_valid)
{
    BuildOptions o;
    o.reclassify = false;
    const Hierarchy h = build_hierarchy(shapes::sphere(5000), o);
    expect_valid_tree(h);
    EXPECT_FALSE(h.info.reclassify);
}

// PCA splitting only (pca_limit above n) and highest-deviation splitting only (pca_limit 0) both work.
TEST(ClusterTree, both_split_directions_give_valid_trees)
{
    for (std::size_t limit : {std::size_t{0}, std::size_t{1000000}}) {
        BuildOptions o;
        o.pca_limit = limit;
        const Hierarchy h = build_hierarchy(shapes::torus(6000), o);
        expect_valid_tree(h);
        EXPECT_GT(h.leaf_count(), 20u);
    }
}

// Degenerate clouds give a valid trivial hierarchy; unusable ones a clear error.
TEST(ClusterTree, degenerate_inputs)
{
    PointCloud one;
    one.positions = {{1, 2, 3}};
    EXPECT_EQ(build_hierarchy(one).nodes.size(), 1u);

    PointCloud dup;
    dup.positions.assign(1000, Vec3{0.5, 0.5, 0.5});
    EXPECT_EQ(build_hierarchy(dup).nodes.size(), 1u);

    PointCloud line;
    for (int i = 0; i < 1000; ++i)
        line.positions.push_back({i * 0.001, i * 0.002, 0.0});
    EXPECT_EQ(build_hierarchy(line).leaf_count(), 1u);

    PointCloud two;
    two.positions = {{0, 0, 0}, {1, 1, 1}};
    expect_valid_tree(build_hierarchy(two));

    EXPECT_THROW(build_hierarchy(PointCloud{}), InvalidInput);
    PointCloud nan = shapes::sphere(100);
    nan.positions[42].y = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(build_hierarchy(nan), InvalidInput);
    BuildOptions bad;
    bad.tolerance = -1;
    EXPECT_THROW(build_hierarchy(shapes::sphere(100), bad), InvalidInput);
    bad = {};
    bad.min_cluster = 0;
    EXPECT_THROW(build_hierarchy(shapes::sphere(100), bad), InvalidInput);
}

// Finite coordinates that no scene has (a stray point at 1e200: its squared distances overflow) are
// refused with the span named; a stray at 1e20 is not: the origin stays among the real points (the
// median, not the box centre), so the sphere keeps its digits.
TEST(ClusterTree, absurd_extents_are_refused_and_far_strays_keep_the_rest_exact)
{
    PointCloud absurd = shapes::sphere(2000);
    absurd.positions.push_back({1e200, 0, 0});
    try {
        build_hierarchy(absurd);
        ADD_FAILURE() << "a cloud spanning 1e200 was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("span x from"), std::string::npos) << e.what();
    }
    PointCloud stray = shapes::sphere(2000);
    const std::vector<Vec3> sphere = stray.positions;
    stray.positions.push_back({1e20, 0, 0});
    recenter(stray);
    EXPECT_EQ(stray.origin, Vec3(0, 0, 0)); // the points straddle 0: nothing to shift
    shapes::translate(stray, {512345.0, 5412345.0, 250.0}); // far from 0: shifted, by the median
    recenter(stray);
    EXPECT_LT(std::abs(stray.origin.x - 512345.0), 2.0); // a box centre would be 5e19
    for (std::size_t i = 0; i < sphere.size(); ++i)
        EXPECT_NEAR(stray.positions[i].x + (stray.origin.x - 512345.0), sphere[i].x, 1e-9) << i;
    const Hierarchy h = build_hierarchy(stray);
    EXPECT_NEAR(h.scale, bounding_box(sphere).largest_side(), 1e-6); // the stray does not set the scale
}

// QA round qa-left: a cloud under 1e-30 across was refused as "collinear or coincident" (1e-200), left
// "no surface" (1e-100) or gave NaN distances (1e-160): the scale is named now. 1e-30 itself builds.
TEST(ClusterTree, clouds_too_small_to_mesh_are_refused_as_such)
{
    for (const double radius : {1e-100, 1e-200, 1e-31}) {
        PointCloud tiny = shapes::sphere(500, radius);
        try {
            build_hierarchy(tiny);
            ADD_FAILURE() << radius << " was accepted";
        } catch (const InvalidInput& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("less than the 1e-30 a mesh can have"), std::string::npos) << what;
            EXPECT_EQ(what.find("collinear"), std::string::npos) << what;
        }
    }
    EXPECT_EQ(build_hierarchy(shapes::sphere(500, 1e-30)).cloud.size(), 500u);
    PointCloud one_point;
    one_point.positions = {{1e-200, 0, 0}, {1e-200, 0, 0}};
    EXPECT_NO_THROW(build_hierarchy(one_point)); // coincident points span 0: not a matter of scale
}

// Far from the origin (UTM-like coordinates, recentred), the hierarchy is the one built near the origin.
TEST(ClusterTree, far_from_origin_matches_near_origin)
{
    PointCloud near = shapes::sphere(6000, 50.0);
    shapes::add_noise(near, 0.05);
    PointCloud far = near;
    shapes::translate(far, {512345.0, 5412345.0, 250.0});
    recenter(far);
    recenter(near);
    const Hierarchy a = build_hierarchy(near), b = build_hierarchy(far);
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    EXPECT_EQ(a.input_index, b.input_index);
    for (std::size_t k = 0; k < a.nodes.size(); ++k) {
        EXPECT_EQ(a.nodes[k].count(), b.nodes[k].count());
        // The input itself is only exact to ~1e-9 at 5e6 (double spacing), so that is all we can ask.
        EXPECT_NEAR(a.nodes[k].rms_plane_distance, b.nodes[k].rms_plane_distance, 1e-7);
    }
}

// The same input and options give the same hierarchy, bit for bit.
TEST(ClusterTree, deterministic)
{
    PointCloud c = shapes::three_holes(5000);
    const Hierarchy a = build_hierarchy(c), b = build_hierarchy(c);
    ASSERT_EQ(a.nodes.size(), b.nodes.size());
    EXPECT_EQ(a.input_index, b.input_index);
    for (std::size_t k = 0; k < a.nodes.size(); ++k) {
        EXPECT_EQ(a.nodes[k].moments.m2, b.nodes[k].moments.m2);
        EXPECT_EQ(a.nodes[k].internal_error, b.nodes[k].internal_error);
    }
}

// first_occurrences against a brute-force scan, with many repeats and a -0 beside a +0.
TEST(ClusterTree, first_occurrences_match_brute_force)
{
    std::vector<Vec3> points;
    std::uint32_t state = 12345;
    auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 28; }; // 0..15
    for (int i = 0; i < 3000; ++i)
        points.push_back({static_cast<double>(next() % 4), static_cast<double>(next() % 5), static_cast<double>(next() % 6) * 0.5});
    points.push_back({-0.0, 0.0, 0.0});
    points.push_back({0.0, -0.0, 0.0});
    std::vector<std::uint32_t> expected;
    for (std::uint32_t i = 0; i < points.size(); ++i) {
        bool earlier = false;
        for (std::uint32_t j = 0; j < i && !earlier; ++j)
            earlier = points[j] == points[i];
        if (!earlier)
            expected.push_back(i);
    }
    EXPECT_EQ(first_occurrences(points), expected);
    EXPECT_LT(expected.size(), 121u); // 4 × 5 × 6 positions at most
}

// Points at the same position are merged before the build: the tree holds each position once (the
// first occurrence, with its colour), input_index points back to it, and the rest of the contract holds.
TEST(ClusterTree, duplicates_are_merged)
{
    PointCloud input = shapes::torus(2000);
    for (std::size_t i = 0; i < input.size(); ++i)
        input.colors.push_back({static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i >> 8), 7, 255});
    const std::size_t distinct = input.size();
    // Every third point twice more, interleaved: a repeat's colour differs from its first occurrence's.
    for (int copy = 0; copy < 2; ++copy)
        for (std::size_t i = copy; i < distinct; i += 3) {
            input.positions.push_back(input.positions[i]);
            input.colors.push_back({1, 2, 3, 4});
        }
    const std::size_t repeats = input.size() - distinct;
    const Hierarchy h = build_hierarchy(input);
    expect_valid_tree(h);
    EXPECT_EQ(h.info.duplicates_merged, repeats);
    ASSERT_EQ(h.cloud.size(), distinct);
    ASSERT_EQ(h.input_index.size(), distinct);
    std::vector<std::uint32_t> sorted = h.input_index;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t i = 0; i < distinct; ++i)
        ASSERT_EQ(sorted[i], i); // the first occurrences are the original points
    for (std::size_t i = 0; i < distinct; ++i) {
        EXPECT_EQ(h.cloud.positions[i], input.positions[h.input_index[i]]);
        EXPECT_EQ(h.cloud.colors[i], input.colors[h.input_index[i]]);
    }

    BuildOptions keep;
    keep.merge_duplicates = false;
    const Hierarchy all = build_hierarchy(input, keep);
    EXPECT_EQ(all.cloud.size(), input.size());
    EXPECT_EQ(all.info.duplicates_merged, 0u);
}

// The tolerance's scale leaves out a few far stray points, and only those: the full box for clean
// shapes, for a cloud whose far part holds more than 1% of the points, and for small clouds.
TEST(ClusterTree, tolerance_scale_leaves_out_far_strays)
{
    const PointCloud sphere = shapes::sphere(20000);
    const double side = bounding_box(sphere.positions).largest_side();
    EXPECT_EQ(tolerance_scale(sphere.positions), side);
    PointCloud strays = sphere;
    strays.positions.push_back({100, 0, 0});
    strays.positions.push_back({-3, 40, 7});
    strays.positions.push_back({0, 0, -250});
    EXPECT_EQ(tolerance_scale(strays.positions), side);
    // Order does not matter (the sample is chosen by position).
    std::reverse(strays.positions.begin(), strays.positions.end());
    EXPECT_EQ(tolerance_scale(strays.positions), side);
    const Hierarchy h = build_hierarchy(strays);
    EXPECT_EQ(h.scale, side);

    PointCloud two = sphere; // a second object with 3% of the points: it counts
    for (std::size_t i = 0; i < 600; ++i)
        two.positions.push_back(sphere.positions[i] + Vec3{100, 0, 0});
    EXPECT_EQ(tolerance_scale(two.positions), bounding_box(two.positions).largest_side());
    PointCloud small = shapes::sphere(100);
    small.positions.push_back({100, 0, 0});
    EXPECT_EQ(tolerance_scale(small.positions), bounding_box(small.positions).largest_side());
    EXPECT_EQ(tolerance_scale({}), 0.0);
}

// QA round qa-left: BuildOptions::denoise cast from an integer (static_cast<Denoise>(42)) was taken for
// Auto.
TEST(ClusterTree, unknown_denoise_is_refused)
{
    BuildOptions options;
    options.denoise = static_cast<BuildOptions::Denoise>(42);
    try {
        build_hierarchy(shapes::sphere(500), options);
        ADD_FAILURE() << "denoise 42 was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), "build_hierarchy: BuildOptions::denoise 42 is none of Auto, Off, On");
    }
}

// assemble_hierarchy takes a caller's partition, so it checks it (QA round 59): a cluster split in three
// hung it (its third child's points had no leaf, and the permutation never ended), too few colours
// were copied past their end, NaN points were taken; a valid partition's hierarchy can be saved.
TEST(ClusterTree, assemble_hierarchy_checks_what_it_is_given)
{
    PointCloud cloud = shapes::sphere(30);
    std::vector<std::uint32_t> three(30), two(30);
    for (std::uint32_t i = 0; i < 30; ++i) {
        three[i] = 1 + i % 3;
        two[i] = 1 + i % 2;
    }
    EXPECT_THROW(assemble_hierarchy(cloud, {-1, 0, 0, 0}, three), InvalidInput);
    PointCloud few_colours = cloud;
    few_colours.colors.assign(3, {0, 0, 0, 255});
    EXPECT_THROW(assemble_hierarchy(few_colours, {-1, 0, 0}, two), InvalidInput);
    PointCloud nan = cloud;
    nan.positions[7].y = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(assemble_hierarchy(nan, {-1, 0, 0}, two), InvalidInput);

    const Hierarchy h = assemble_hierarchy(cloud, {-1, 0, 0}, two);
    ASSERT_EQ(h.nodes.size(), 3u);
    EXPECT_EQ(h.nodes[0].count(), 30u);
    EXPECT_EQ(h.nodes[1].count() + h.nodes[2].count(), 30u);
    EXPECT_EQ(h.info.min_cluster, 1u);
    EXPECT_EQ(deserialize_model(serialize_model(h), "assembled").nodes.size(), 3u);
}

// A cloud placed at ordinary UTM-like coordinates without recenter() (QA round 59: the bunny at
// (5e5, 5e6), 2e7 times its extent from its origin, built 953 nodes instead of 5,819, its moments
// cancelling as points moved between clusters; a torus at 3e7 1,345 instead of 3,409) is recentred by
// the build and gives the tree of the same cloud near its origin; its positions are the same points
// relative to the new origin.
TEST(ClusterTree, a_cloud_far_from_its_origin_is_recentred)
{
    const PointCloud near = shapes::torus(20000);
    PointCloud far = near;
    const Vec3 offset{3e7, 3e7, 100};
    for (Vec3& p : far.positions)
        p = p + offset;
    const Hierarchy a = build_hierarchy(near), b = build_hierarchy(far);
    EXPECT_GT(norm(b.cloud.origin - near.origin), 1e5);
    EXPECT_NEAR(static_cast<double>(b.nodes.size()), static_cast<double>(a.nodes.size()), 0.03 * static_cast<double>(a.nodes.size()));
    EXPECT_NEAR(norm(b.cloud.origin + b.cloud.positions[0] - (near.origin + offset + near.positions[b.input_index[0]])), 0.0, 1e-9);
}

} // namespace
} // namespace mrt
