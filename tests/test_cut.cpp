// Tests of cut.h: every kind of cut is a partition of the points, errors fall monotonically with
// refinement, budgets are exact, and local cuts refine where asked and nowhere else.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"
#include "formats/read_points.h"
#include "tests/error_message.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

namespace mrt {
namespace {

const Hierarchy& torus()
{
    static const Hierarchy h = [] {
        PointCloud c = shapes::torus(30000);
        shapes::add_noise(c, 0.0005);
        return build_hierarchy(c);
    }();
    return h;
}

// Tolerance and τ cuts partition the points, and a finer tolerance never raises the plane error.
TEST(Cut, tolerance_cuts_partition_and_error_is_monotone)
{
    const Hierarchy& h = torus();
    double previous = std::numeric_limits<double>::infinity();
    std::size_t previous_size = 0;
    for (double tol : {0.05, 0.02, 0.01, 0.005, 0.002, 0.001, 0.0}) {
        const Cut cut = cut_by_tolerance(h, tol);
        EXPECT_TRUE(is_partition(h, cut)) << tol;
        const double error = cut_plane_error(h, cut);
        EXPECT_LE(error, previous * (1 + 1e-12));
        EXPECT_GE(cut.size(), previous_size);
        previous = error;
        previous_size = cut.size();
        const double limit = tol * h.scale;
        for (std::int32_t id : cut)
            EXPECT_TRUE(h.nodes[static_cast<std::size_t>(id)].is_leaf() ||
                        h.nodes[static_cast<std::size_t>(id)].rms_plane_distance <= limit);
    }
    EXPECT_EQ(cut_by_tolerance(h, 0.0).size(), h.leaf_count());
    const Cut tau = cut_by_tau(h, 1e-3);
    EXPECT_TRUE(is_partition(h, tau));
    for (std::int32_t id : tau)
        EXPECT_TRUE(h.nodes[static_cast<std::size_t>(id)].is_leaf() || h.nodes[static_cast<std::size_t>(id)].frame.values[0] <= 1e-3);
    EXPECT_THROW(cut_by_tolerance(h, -1), InvalidInput);
}

// A budget of N tiles gives exactly N tiles (or all leaves), and more tiles never more error.
TEST(Cut, budget_is_exact_and_error_falls)
{
    const Hierarchy& h = torus();
    double previous = std::numeric_limits<double>::infinity();
    for (std::size_t n : {1u, 2u, 3u, 10u, 100u, 1000u, 1001u}) {
        const Cut cut = cut_by_budget(h, n);
        EXPECT_EQ(cut.size(), std::min(n, h.leaf_count()));
        EXPECT_TRUE(is_partition(h, cut));
        const double error = cut_plane_error(h, cut);
        EXPECT_LE(error, previous * (1 + 1e-12));
        previous = error;
    }
    EXPECT_EQ(cut_by_budget(h, 100000000).size(), h.leaf_count());
    EXPECT_THROW(cut_by_budget(h, 0), InvalidInput);
}

// A focus sphere: more tiles meet it than in the coarse cut, and the coarse cut's tiles away from it
// are kept unchanged.
TEST(Cut, focus_region_refines_inside_only)
{
    const Hierarchy& h = torus();
    const double coarse_tol = 0.01;
    FocusRegion region;
    region.centre = h.cloud.positions[h.nodes[0].begin + 7];
    region.radius = 0.3;
    region.tolerance = 0.0001;
    const Cut coarse = cut_by_tolerance(h, coarse_tol);
    const Cut focus = cut_by_regions(h, coarse_tol, {region});
    EXPECT_TRUE(is_partition(h, focus));
    auto meeting = [&](const Cut& cut) {
        return std::count_if(cut.begin(), cut.end(), [&](std::int32_t id) { return intersects(h.nodes[static_cast<std::size_t>(id)], region); });
    };
    EXPECT_GT(meeting(focus), 3 * meeting(coarse));
    // Denser inside than outside: tiles meeting the region hold far fewer points each.
    double inside_points = 0, outside_points = 0;
    for (std::int32_t id : focus)
        (intersects(h.nodes[static_cast<std::size_t>(id)], region) ? inside_points : outside_points) +=
            h.nodes[static_cast<std::size_t>(id)].count();
    const double inside_tiles = static_cast<double>(meeting(focus));
    EXPECT_LT(inside_points / inside_tiles, 0.25 * outside_points / (static_cast<double>(focus.size()) - inside_tiles));
    const std::set<std::int32_t> in_focus(focus.begin(), focus.end());
    std::size_t away = 0;
    for (std::int32_t id : coarse)
        if (!intersects(h.nodes[static_cast<std::size_t>(id)], region)) {
            ++away;
            EXPECT_TRUE(in_focus.count(id)) << "coarse tile away from the region was changed";
        }
    EXPECT_GT(away, 10u);

    // A box region and two regions at once.
    FocusRegion box;
    box.shape = FocusRegion::Shape::Box;
    box.box = {{-1.5, -1.5, -0.5}, {-0.8, 1.5, 0.5}};
    box.tolerance = 0.001;
    const Cut both = cut_by_regions(h, coarse_tol, {region, box});
    EXPECT_TRUE(is_partition(h, both));
    EXPECT_GT(both.size(), focus.size());
}

// Incremental refinement gives exactly the fresh focus cut; coarsening inside a region changes only
// nodes inside it and gives back a cut no finer than before.
TEST(Cut, incremental_refine_equals_fresh_extraction_and_coarsen_is_local)
{
    const Hierarchy& h = torus();
    const double base = 0.01;
    FocusRegion region;
    region.centre = {1.3, 0.2, 0.0};
    region.radius = 0.35;
    region.tolerance = 0.0005;
    FocusRegion box;
    box.shape = FocusRegion::Shape::Box;
    box.box = {{-1.4, -0.5, -0.4}, {-0.9, 0.5, 0.4}};
    box.tolerance = 0.001;
    const Cut coarse = cut_by_tolerance(h, base);
    const Cut refined = refine_cut(h, coarse, base, {region, box});
    EXPECT_EQ(refined, cut_by_regions(h, base, {region, box}));
    EXPECT_GT(refined.size(), coarse.size());

    FocusRegion back = region;
    const Cut coarsened = coarsen_cut(h, refined, back, base);
    EXPECT_TRUE(is_partition(h, coarsened));
    EXPECT_LT(coarsened.size(), refined.size());
    const std::set<std::int32_t> before(refined.begin(), refined.end()), after(coarsened.begin(), coarsened.end());
    for (std::int32_t id : refined)
        if (!after.count(id)) { // removed: it must lie inside the region
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            EXPECT_LE(distance(n.box.min, region.centre), region.radius + 1e-12);
            EXPECT_LE(distance(n.box.max, region.centre), region.radius + 1e-12);
        }
    for (std::int32_t id : coarsened) {
        if (!before.count(id)) {
            EXPECT_LE(h.nodes[static_cast<std::size_t>(id)].rms_plane_distance, base * h.scale);
        }
    }
}

// A camera close to one side of the torus refines tiles near it more than far ones.
TEST(Cut, camera_refines_near_the_camera)
{
    const Hierarchy& h = torus();
    Camera cam;
    cam.position = {2.0, 0.0, 0.2};
    cam.viewport_height = 1080;
    const Cut cut = cut_for_camera(h, cam);
    EXPECT_TRUE(is_partition(h, cut));
    double near_points = 0, far_points = 0;
    std::size_t near_tiles = 0, far_tiles = 0;
    for (std::int32_t id : cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        if (n.centre().x > 0.5) {
            near_points += n.count();
            ++near_tiles;
        } else if (n.centre().x < -0.5) {
            far_points += n.count();
            ++far_tiles;
        }
    }
    ASSERT_GT(near_tiles, 0u);
    ASSERT_GT(far_tiles, 0u);
    EXPECT_LT(near_points / near_tiles, 0.5 * far_points / far_tiles); // smaller tiles near the camera
    for (std::int32_t id : cut)
        EXPECT_TRUE(h.nodes[static_cast<std::size_t>(id)].is_leaf() ||
                    screen_space_error(h.nodes[static_cast<std::size_t>(id)], cam) <= cam.max_pixel_error);
    Camera bad = cam;
    bad.fov_y_degrees = 0;
    EXPECT_THROW(cut_for_camera(h, bad), InvalidInput);
}

// A camera that looks somewhere refines only what is in its view cone: beside the torus looking along
// +y at its near side, the tiles there are those of the camera that looks all around, while the half
// behind it (x < 0) stays coarse; looking straight away from the torus, nothing is refined.
TEST(Cut, camera_refines_only_what_is_in_view)
{
    const Hierarchy& h = torus();
    Camera around;
    around.position = {1.0, -1.5, 0.0};
    around.fov_y_degrees = 20.0;
    Camera looking = around;
    looking.direction = {0.0, 1.0, 0.0};
    const Cut all = cut_for_camera(h, around), seen = cut_for_camera(h, looking);
    ASSERT_TRUE(is_partition(h, seen));
    std::size_t tiles_all = 0, tiles_seen = 0;
    auto in_view_half = [&](const Node& n) { return n.centre().x > 0.9 && n.centre().y < 0.0; };
    for (std::int32_t id : all)
        tiles_all += in_view_half(h.nodes[static_cast<std::size_t>(id)]) ? 1 : 0;
    for (std::int32_t id : seen) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        tiles_seen += in_view_half(n) ? 1 : 0;
    }
    EXPECT_EQ(tiles_seen, tiles_all); // refined as by the camera that looks all around
    std::size_t behind_all = 0, behind_seen = 0;
    for (std::int32_t id : all)
        behind_all += h.nodes[static_cast<std::size_t>(id)].centre().x < 0 ? 1 : 0;
    for (std::int32_t id : seen)
        behind_seen += h.nodes[static_cast<std::size_t>(id)].centre().x < 0 ? 1 : 0;
    EXPECT_LT(2 * behind_seen, behind_all); // out of view: 4x the pixel error
    EXPECT_LT(seen.size(), all.size());
    for (std::int32_t id : seen) { // a node out of view is there because its parent was in view or too coarse for out of view
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        if (!in_view(n, looking) && n.parent >= 0) {
            const Node& parent = h.nodes[static_cast<std::size_t>(n.parent)];
            EXPECT_TRUE(in_view(parent, looking) ||
                        screen_space_error(parent, looking) > looking.max_pixel_error * looking.out_of_view_factor);
        }
    }
    // Looking away: the torus behind the camera is refined 4x coarser than in view, not left as the
    // root's tile (an open disc), and meshes closed with its hole.
    Camera away = around;
    away.position = {0.0, -5.0, 0.0};
    away.direction = {0.0, -1.0, 0.0};
    Camera facing = away;
    facing.direction = {0.0, 1.0, 0.0};
    const Cut behind = cut_for_camera(h, away);
    EXPECT_GT(behind.size(), 16u);
    EXPECT_LT(behind.size(), cut_for_camera(h, facing).size());
    const MeshResult behind_mesh = mesh_cut(h, behind);
    const TopologyStats topology = topology_stats(behind_mesh.mesh);
    EXPECT_EQ(topology.boundary_loops, 0u);
    EXPECT_EQ(topology.components, 1u);
    EXPECT_EQ(topology.genus, 1);
    away.out_of_view_factor = std::numeric_limits<double>::infinity(); // never refined out of view
    EXPECT_EQ(cut_for_camera(h, away).size(), 1u);
    away.out_of_view_factor = 0.5;
    EXPECT_THROW(cut_for_camera(h, away), InvalidInput);
    Camera bad = looking;
    bad.aspect = 0.0;
    EXPECT_THROW(cut_for_camera(h, bad), InvalidInput);
    // The per-node functions check the camera too (QA round 51: a NaN field of view gave NaN errors,
    // which refine nothing, without a word).
    const Node& root = h.nodes[0];
    Camera nan_fov = looking;
    nan_fov.fov_y_degrees = std::nan("");
    EXPECT_THROW(screen_space_error(root, nan_fov), InvalidInput);
    EXPECT_THROW(in_view(root, bad), InvalidInput);
    EXPECT_THROW(camera_asks_finer(root, nan_fov), InvalidInput);
    EXPECT_THROW(check_camera(nan_fov), InvalidInput);
    EXPECT_NO_THROW(check_camera(looking));
    EXPECT_TRUE(std::isfinite(screen_space_error(root, facing)));
}

// The general predicate form: refine exactly the nodes above depth 4.
// Cuts and regions from the caller are checked: node ids out of range, non-finite or inverted regions
// are refused (QA, session 19: e_rms, measure_quality, cut_plane_error and coarsen_cut read out of
// bounds; a NaN focus centre refined the whole model).
TEST(Cut, bad_node_ids_and_regions_are_refused)
{
    const Hierarchy& h = torus();
    const Cut bad{-3, 1000000};
    FocusRegion inside;
    inside.radius = 0.5;
    inside.tolerance = 0.001;
    EXPECT_THROW(cut_plane_error(h, bad), InvalidInput);
    // Nodes that are no frontier (the root beside its child) counted points twice.
    EXPECT_THROW(cut_plane_error(h, Cut{0, h.nodes[0].left}), InvalidInput);
    EXPECT_NO_THROW(cut_plane_error(h, cut_by_tolerance(h, 0.01)));
    EXPECT_THROW(coarsen_cut(h, bad, inside, 0.01), InvalidInput);
    EXPECT_THROW(refine_cut(h, bad, 0.01, {inside}), InvalidInput);
    EXPECT_THROW(check_node_ids(h, Cut{static_cast<std::int32_t>(h.nodes.size())}), InvalidInput);
    EXPECT_NO_THROW(check_node_ids(h, cut_by_tolerance(h, 0.01)));
    FocusRegion nan_centre = inside;
    nan_centre.centre = {std::nan(""), 0, 0};
    EXPECT_THROW(cut_by_regions(h, 0.01, {nan_centre}), InvalidInput);
    FocusRegion inverted;
    inverted.shape = FocusRegion::Shape::Box;
    inverted.box = BoundingBox{{1, 1, 1}, {0, 0, 0}};
    EXPECT_THROW(cut_by_regions(h, 0.01, {inverted}), InvalidInput);
    inverted.box = BoundingBox{{0, 0, 0}, {1, std::nan(""), 1}};
    EXPECT_THROW(refine_cut(h, cut_by_tolerance(h, 0.01), 0.01, {inverted}), InvalidInput);
    EXPECT_THROW(coarsen_cut(h, cut_by_tolerance(h, 0.01), nan_centre, 0.01), InvalidInput);
}

// QA round qa-left: a focus region's shape cast from an integer (static_cast<Shape>(42)) was met as a
// sphere, its radius unchecked.
TEST(Cut, unknown_region_shape_is_refused)
{
    const Hierarchy& h = torus();
    FocusRegion odd;
    odd.shape = static_cast<FocusRegion::Shape>(42);
    odd.radius = -1.0;
    const std::string message = "cut: a focus region's shape 42 is neither Sphere nor Box";
    EXPECT_EQ(testing::error_message([&] { check_region(odd); }), message);
    EXPECT_EQ(testing::error_message([&] { cut_by_regions(h, 0.01, {odd}); }), message);
    EXPECT_EQ(testing::error_message([&] { refine_cut(h, cut_by_tolerance(h, 0.01), 0.01, {odd}); }), message);
}

TEST(Cut, predicate_cut)
{
    const Hierarchy& h = torus();
    const Cut cut = cut_by_predicate(h, [](const Hierarchy& hh, std::int32_t id) { return hh.nodes[static_cast<std::size_t>(id)].depth < 4; });
    EXPECT_TRUE(is_partition(h, cut));
    for (std::int32_t id : cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        EXPECT_TRUE(n.depth == 4 || (n.depth < 4 && n.is_leaf()));
    }
    EXPECT_EQ(cut_by_predicate(h, [](const Hierarchy&, std::int32_t) { return false; }), Cut{0});
}

// QA round qa3: a default-constructed Hierarchy (no nodes) read the root out of bounds in the budget
// cut; now every cut gives the empty cut for it. An empty predicate was a std::bad_function_call.
TEST(Cut, empty_hierarchy_and_empty_predicate)
{
    const Hierarchy none;
    EXPECT_TRUE(cut_by_budget(none, 10).empty());
    EXPECT_TRUE(cut_by_tolerance(none, 0.01).empty());
    EXPECT_THROW(cut_by_predicate(torus(), RefinePredicate{}), InvalidInput);
}

// QA round qa3: the camera's direction may have any length. One of 1e300 overflowed its norm and made
// every node out of view (a coarser cut); one of 1e-300 underflowed to 0 and looked all around.
TEST(Cut, camera_direction_of_any_length)
{
    const Hierarchy& h = torus();
    Camera camera;
    camera.position = {3, 0, 1};
    camera.direction = {-3, 0.5, -1};
    const Cut unit = cut_for_camera(h, camera);
    for (const double scale : {1e300, 1e-300, 1e-160, 1e160}) {
        Camera scaled = camera;
        scaled.direction = camera.direction * scale;
        EXPECT_EQ(cut_for_camera(h, scaled), unit) << scale;
    }
}

// A sphere whose noise is one point spacing (30,000 points, σ = 0.02).
const Hierarchy& noisy_sphere()
{
    static const Hierarchy h = [] {
        PointCloud c = shapes::sphere(30000);
        shapes::add_noise(c, 0.02);
        BuildOptions raw; // the noise kept: these tests are about the floor
        raw.denoise = BuildOptions::Denoise::Off;
        return build_hierarchy(c, raw);
    }();
    return h;
}

// Clean samples, analytic and scanned, cut as if there were no noise floor (the analytic ones have none;
// a region of a CAD part whose leaves straddle sharp edges may get a small one, below its nodes' errors).
TEST(Cut, clean_samples_are_cut_as_without_a_noise_floor)
{
    EXPECT_EQ(max_noise_floor(torus()), 0.0);
    EXPECT_EQ(max_noise_floor(build_hierarchy(shapes::sphere(20000))), 0.0);
    EXPECT_EQ(max_noise_floor(build_hierarchy(shapes::three_holes(10000))), 0.0);
    // At 4,000 points the solid's rims are a few spacings thick, and its leaves and regions there are
    // as blob-like as noise: the points spread about their plane as two sheets, not as noise does.
    EXPECT_EQ(max_noise_floor(build_hierarchy(shapes::three_holes(4000))), 0.0);
    for (const char* name : {"bun_zipper.ply", "bun000.ply", "igea.ply", "rocker-arm.obj", "fandisk.obj"}) {
        const Hierarchy h = build_hierarchy(read_points(std::string(MRTILE_SHARED_DATA "/") + name));
        Hierarchy unfloored = h;
        clear_noise_floor(unfloored);
        for (double tol : {0.01, 0.005, 0.002, 0.001, 0.0005})
            EXPECT_EQ(cut_by_tolerance(h, tol), cut_by_tolerance(unfloored, tol)) << name << " " << tol;
    }
}

// A noisy sample's floor is of the order of its noise, and the cuts by tolerance, region and camera
// never refine a node at or under it (budget cuts still may: they do what they are asked).
TEST(Cut, tolerance_region_and_camera_cuts_stop_at_the_noise_floor)
{
    const Hierarchy& h = noisy_sphere();
    EXPECT_GT(max_noise_floor(h), 0.5 * 0.02);
    EXPECT_LT(max_noise_floor(h), 3.0 * 0.02);
    auto parents_above_floor = [&](const Cut& cut) {
        for (std::int32_t id : cut) {
            const std::int32_t parent = h.nodes[static_cast<std::size_t>(id)].parent;
            const Node* p = parent >= 0 ? &h.nodes[static_cast<std::size_t>(parent)] : nullptr;
            if (p && !(p->rms_plane_distance > p->noise_floor))
                return false;
        }
        return true;
    };
    const Cut finest = cut_by_tolerance(h, 0.0);
    EXPECT_TRUE(is_partition(h, finest));
    EXPECT_TRUE(parents_above_floor(finest));
    EXPECT_LT(finest.size(), h.leaf_count() / 10);
    EXPECT_EQ(cut_by_tolerance(h, 0.001), finest);
    FocusRegion focus;
    focus.centre = {1, 0, 0};
    focus.radius = 0.5;
    const Cut regions = cut_by_regions(h, 0.01, {focus});
    EXPECT_TRUE(parents_above_floor(regions));
    EXPECT_EQ(refine_cut(h, cut_by_tolerance(h, 0.01), 0.01, {focus}), regions);
    Camera camera;
    camera.position = {1.2, 0, 0};
    const Cut near = cut_for_camera(h, camera);
    EXPECT_TRUE(parents_above_floor(near));
    EXPECT_FALSE(parents_above_floor(cut_by_budget(h, h.leaf_count())));
    Hierarchy unfloored = h;
    clear_noise_floor(unfloored);
    EXPECT_EQ(cut_by_tolerance(unfloored, 0.0).size(), h.leaf_count());
}

// QA round qa-left: refine_cut and coarsen_cut checked only that the node ids exist. A node listed twice
// came out twice, a node beside its own ancestor was kept, and the result was no cut. A cut that is no
// frontier is refused now, naming the node or the points that are wrong.
TEST(Cut, refine_and_coarsen_refuse_a_cut_that_is_no_frontier)
{
    const Hierarchy& h = torus();
    const Cut base = cut_by_tolerance(h, 0.01);
    ASSERT_GT(base.size(), 3u);
    FocusRegion everywhere;
    everywhere.radius = 100.0;
    everywhere.tolerance = 0.005;
    const auto node = [&](std::int32_t id) { return h.nodes[static_cast<std::size_t>(id)]; };
    const auto points = [](std::uint32_t first, std::uint32_t last) {
        return "points " + std::to_string(first) + " to " + std::to_string(last) +
               " are in no node of the cut (a subtree is missing)";
    };
    Cut twice = base;
    twice.push_back(base[3]);
    const std::int32_t parent = node(base[0]).parent;
    ASSERT_GE(parent, 0);
    Cut nested = base;
    nested.push_back(parent);
    Cut missing = base;
    missing.erase(missing.begin() + 2);
    // The node holding the last point: its range ends the cut.
    const auto last = std::find_if(base.begin(), base.end(), [&](std::int32_t id) { return node(id).end == h.cloud.size(); });
    ASSERT_NE(last, base.end());
    Cut no_end = base;
    no_end.erase(no_end.begin() + (last - base.begin()));
    const std::vector<std::pair<Cut, std::string>> cases = {
        {twice, "node " + std::to_string(base[3]) + " is listed twice in the cut"},
        {nested, "node " + std::to_string(base[0]) + " of the cut lies inside node " + std::to_string(parent) +
                     " of it (a cut holds each point once)"},
        {missing, points(node(base[2]).begin, node(base[2]).end - 1)},
        {no_end, points(node(*last).begin, static_cast<std::uint32_t>(h.cloud.size() - 1))},
        {Cut{}, points(0, static_cast<std::uint32_t>(h.cloud.size() - 1))},
        {Cut{0, -1}, "node id -1 of the cut is not in the hierarchy"},
    };
    for (const auto& [cut, expected] : cases) {
        SCOPED_TRACE(expected);
        EXPECT_FALSE(is_partition(h, cut));
        EXPECT_EQ(testing::error_message([&] { refine_cut(h, cut, 0.01, {everywhere}); }), "refine_cut: " + expected);
        EXPECT_EQ(testing::error_message([&] { coarsen_cut(h, cut, everywhere, 0.05); }), "coarsen_cut: " + expected);
    }
    // Any order of a frontier is one.
    Cut reversed = base;
    std::reverse(reversed.begin(), reversed.end());
    EXPECT_NO_THROW(check_cut(h, reversed, "x"));
    EXPECT_TRUE(is_partition(h, refine_cut(h, reversed, 0.01, {everywhere})));
    EXPECT_TRUE(is_partition(h, coarsen_cut(h, reversed, everywhere, 0.05)));
}

// A terrain scanned in lines 30 times farther apart than the points along them (QA round qa-scan): a
// 16-point leaf is a stretch of one line, which fits every plane through it. The cuts by tolerance
// took such slivers wherever their parent was rougher than asked, and the mesh fell apart (143 pieces,
// 6,218 crossing pairs at 0.002); they now stop at the parent, whose points span two lines or more.
TEST(Cut, scan_lines_far_apart_are_not_cut_into_single_lines)
{
    PointCloud c;
    const double across = 0.04, along = across / 30.0;
    for (int j = 0; j < 25; ++j)
        for (int i = 0; i * along <= 1.0; ++i) {
            const double x = i * along, y = j * across;
            c.positions.push_back({x, y, 0.1 * std::sin(3 * x) * std::sin(2 * y)});
        }
    const Hierarchy h = build_hierarchy(c);
    auto spans_a_surface = [&](std::int32_t id) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        return n.frame.values[1] > n.frame.values[2] / 900.0;
    };
    for (double tol : {0.005, 0.002, 0.0}) {
        const Cut cut = cut_by_tolerance(h, tol);
        EXPECT_TRUE(is_partition(h, cut));
        EXPECT_TRUE(std::all_of(cut.begin(), cut.end(), spans_a_surface)) << tol;
    }
    Camera camera;
    camera.position = {0.5, 0.5, 0.3};
    camera.direction = {0, 0, -1};
    const Cut near = cut_for_camera(h, camera);
    EXPECT_TRUE(std::all_of(near.begin(), near.end(), spans_a_surface));
    // The slivers' fans crossed each other by the thousand. (The mesh is still in pieces: the surface
    // stage measures gaps by the spacing along the lines, 30 times finer than across: README, Known
    // limits.)
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.002));
    EXPECT_TRUE(self_intersecting_faces(r.mesh).empty());
}

// Profiles 15 times farther apart than their points, with range noise of a quarter spacing (a laser
// line scanner: each profile lies exactly in its laser plane), and a cylinder scanned in rings 19:1
// (QA round 54). A stretch of one profile has no normal of its own, yet two neighbouring stretches
// were taken for the two sides of a thin part facing each other across the strip between them, a hole
// of 4 spacings: every cut refined to pairs of stretches and the surface came out in pieces with
// holes (the terrain: 717 tiles, 2 pieces, 29 loops at 0.002; the cylinder: 58 loops).
TEST(Cut, neighbouring_scan_lines_are_no_hole)
{
    std::mt19937 rng(54); // raw output only: the same everywhere (its distributions are not)
    auto uniform = [&] { return (static_cast<double>(rng()) + 0.5) / 4294967296.0; };
    auto gauss = [&] { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2.0 * M_PI * uniform()); };
    PointCloud terrain;
    const int lines = 40, per_line = 600;
    const double along = 1.0 / per_line;
    for (int j = 0; j < lines; ++j)
        for (int i = 0; i < per_line; ++i) {
            const double x = (i + 0.3 * uniform()) * along, y = (j + 0.5) / lines;
            const double z = 0.08 * std::sin(3 * x + 1) * std::cos(4 * y) + 0.03 * std::sin(9 * x * y);
            terrain.positions.push_back({x, y, z + 0.24 * along * gauss()});
        }
    const Hierarchy h = build_hierarchy(terrain);
    for (double tol : {0.005, 0.002, 0.001}) {
        const Cut cut = cut_by_tolerance(h, tol);
        EXPECT_LT(cut.size(), 200u) << tol;
        const Mesh mesh = mesh_cut(h, cut).mesh;
        const TopologyStats t = topology_stats(mesh);
        EXPECT_EQ(t.components, 1u) << tol;
        EXPECT_EQ(t.boundary_loops, 1u) << tol;
        // Nor is the last line cut off the border (4% of the diagonal at 0.005 before; see the rings below).
        EXPECT_LT(point_to_mesh_distance(h.cloud.positions, mesh).max, 0.02) << tol;
    }
    PointCloud rings;
    const int ring_count = 53, per_ring = 1880; // 1 mm along a ring of radius 0.3, rings 19 mm apart
    for (int j = 0; j < ring_count; ++j)
        for (int i = 0; i < per_ring; ++i) {
            const double a = 2.0 * M_PI * i / per_ring;
            rings.positions.push_back({0.3 * std::cos(a), 0.3 * std::sin(a), (j + 0.5) / ring_count});
        }
    const Hierarchy cylinder = build_hierarchy(rings);
    for (double tol : {0.01, 0.005, 0.002}) {
        const Mesh mesh = mesh_cut(cylinder, cut_by_tolerance(cylinder, tol)).mesh;
        const TopologyStats t = topology_stats(mesh);
        EXPECT_EQ(t.components, 1u) << tol;
        EXPECT_EQ(t.boundary_loops, 2u) << tol; // its open ends
        EXPECT_EQ(t.genus, 0) << tol;
        // The last ring stays on the border: a rim point collapsed across a strip into a point well inside
        // cut a corner off it (5% of the diagonal at 0.01; QA round 54).
        EXPECT_LT(point_to_mesh_distance(cylinder.cloud.positions, mesh).max, 0.02) << tol;
    }
}

// A bent thin pipe (QA round 48): each straight arm, as a whole, is as long and thin as a stretch of a
// scan line, and the line rule stopped every tolerance cut at the root, one flat tile over the empty
// space between the arms (mesh to points: 0.29 of the diagonal), even at tolerance 0. Its points go
// round the pipe, far denser than a line of that length: the cut refines, and the mesh is a tube.
TEST(Cut, a_bent_thin_pipe_is_no_line)
{
    PointCloud c;
    const double radius = 0.025, length = 5.0;
    std::mt19937 rng(48); // its raw output is the same everywhere (its distributions are not)
    auto uniform = [&] { return static_cast<double>(rng()) / 4294967296.0; };
    for (int i = 0; i < 40000; ++i) {
        const double along = length * uniform(), angle = 2 * M_PI * uniform();
        const double u = radius * std::cos(angle), w = radius * std::sin(angle);
        c.positions.push_back(i % 2 ? Vec3{along, u, w} : Vec3{u, along, w}); // arms along x and y
    }
    const Hierarchy h = build_hierarchy(c);
    const Node& root = h.nodes[0];
    EXPECT_FALSE(splits_into_lines(h, root));
    for (double tol : {0.002, 0.0}) {
        const Cut cut = cut_by_tolerance(h, tol);
        EXPECT_GT(cut.size(), 100u) << tol;
        const MeshResult r = mesh_cut(h, cut);
        EXPECT_LT(mesh_to_point_distance(r.mesh, h.cloud.positions).max, 0.01) << tol;
    }
}

// A torus with three strays 10⁶ away (QA round 60): the node holding the torus and one stray spread
// along the stray like a line (eigenvalues 10⁸ apart, its spacing along inflated by the stray's
// distance), the line rule stopped every tolerance cut at its parent, and the mesh was 4 faces, at
// tolerance 0 too. Its points bunch and leave the stray's length empty: the cut refines, and the mesh
// is the torus.
TEST(Cut, a_blob_with_a_far_stray_is_no_line)
{
    PointCloud c = shapes::torus(40000);
    for (const Vec3& stray : {Vec3{1e6, 0, 0}, Vec3{0, -1e6, 3e5}, Vec3{-5e5, 5e5, -1e6}})
        c.positions.push_back(stray);
    const Hierarchy h = build_hierarchy(c);
    for (const Node& n : h.nodes)
        EXPECT_FALSE(splits_into_lines(h, n) && n.count() > 1000) << n.count();
    for (double tol : {0.01, 0.0}) {
        const Cut cut = cut_by_tolerance(h, tol);
        EXPECT_GT(cut.size(), 100u) << tol;
        const MeshResult r = mesh_cut(h, cut);
        const TopologyStats t = topology_stats(r.mesh);
        EXPECT_EQ(t.genus, 1) << tol;
        EXPECT_EQ(t.boundary_loops, 0u) << tol;
        EXPECT_GT(r.mesh.n_faces(), 1000u) << tol;
    }
}

// Scan lines with a dwell clump each (a scanner that paused: three times a line's points within a few
// spacings) bunch as a blob with a stray does, but leave no empty stretch: they are lines still (QA
// round 61: taken for no lines, a 20:1 terrain at tolerance 0 lost a piece). Cross-checked node by node
// against the line test without the blob rule (line_spread), through splits_into_lines of the parents.
TEST(Cut, scan_lines_with_dwell_clumps_are_lines)
{
    PointCloud c;
    std::mt19937 rng(61);
    auto uniform = [&] { return static_cast<double>(rng()) / 4294967296.0; };
    const double length = 50.0, line_gap = 2.0;
    const int along = 500;
    for (int line = 0; line * line_gap <= length; ++line) {
        const double y = line * line_gap, clump = length * uniform();
        for (int k = 0; k < along; ++k)
            c.positions.push_back({length * k / along, y, 0.3 * std::sin(0.2 * y + 0.1 * length * k / along)});
        for (int k = 0; k < 3 * along; ++k) {
            const double x = clump + 0.15 * (uniform() + uniform() + uniform() - 1.5);
            if (x >= 0.0 && x <= length)
                c.positions.push_back({x, y, 0.3 * std::sin(0.2 * y + 0.1 * x)});
        }
    }
    const Hierarchy h = build_hierarchy(c);
    std::size_t bunched = 0;
    for (const Node& parent : h.nodes) {
        if (parent.is_leaf())
            continue;
        for (const std::int32_t child : {parent.left, parent.right}) {
            const Node& n = h.nodes[static_cast<std::size_t>(child)];
            if (n.count() < 8 || !(n.frame.values[1] <= n.frame.values[2] / 900.0))
                continue;
            const LineSpread spread = line_spread(n);
            if (!(spread.across <= 2.0 * spread.spacing_along))
                continue;
            const LineSpread parent_spread = line_spread(parent);
            const bool parent_line = parent.count() >= 8 && parent.frame.values[1] <= parent.frame.values[2] / 900.0 &&
                                     parent_spread.across <= 2.0 * parent_spread.spacing_along;
            bunched += spread.spacing_along * static_cast<double>(n.count()) < 0.5 * n.box.diagonal() ? 1 : 0;
            if (!parent_line) {
                EXPECT_TRUE(splits_into_lines(h, parent)) << n.count();
            }
        }
    }
    EXPECT_GT(bunched, 5u); // the case is exercised
}

// refine_cut returns its cut in point order, as every cut is, whatever the order it was given in (QA
// round 59: a shuffled cut came back shuffled).
TEST(Cut, refine_cut_returns_point_order_from_any_order)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(5000));
    Cut cut = cut_by_tolerance(h, 0.02);
    std::reverse(cut.begin(), cut.end());
    FocusRegion region;
    region.centre = Vec3{1, 0, 0} - h.cloud.origin;
    region.radius = 0.5;
    region.tolerance = 0.002;
    const Cut refined = refine_cut(h, cut, 0.02, {region});
    ASSERT_GT(refined.size(), cut.size());
    for (std::size_t k = 1; k < refined.size(); ++k)
        EXPECT_EQ(h.nodes[static_cast<std::size_t>(refined[k])].begin, h.nodes[static_cast<std::size_t>(refined[k - 1])].end) << k;
}

} // namespace
} // namespace mrt
