// Whether a cloud is one view from its viewpoint (single_view.h): exact answers on analytic scenes where
// every point is seen or the hidden share is known, and the option checks.

#include "libmrtile/errors.h"
#include "libmrtile/shapes.h"
#include "libmrtile/single_view.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

using namespace mrt;

namespace {

std::vector<Vec3> positions_of(const PointCloud& c)
{
    std::vector<Vec3> out;
    for (const Vec3& p : c.positions)
        out.push_back(p + c.origin);
    return out;
}

} // namespace

// A plane seen from above: every point is the first thing on its ray.
TEST(SingleView, a_plane_seen_from_above_hides_nothing)
{
    const std::vector<Vec3> points = positions_of(shapes::plane_grid(300));
    const SingleViewStats s = single_view_stats(points, Vec3{0.5, 0.5, 1.0});
    EXPECT_EQ(s.sampled, points.size());
    EXPECT_EQ(s.hidden, 0u);
    EXPECT_TRUE(s.single_view);
}

// From the centre of a sphere (a room scanned from inside) every direction meets it once.
TEST(SingleView, a_sphere_seen_from_its_centre_hides_nothing)
{
    const std::vector<Vec3> points = positions_of(shapes::sphere(200000, 2.0, 3));
    const SingleViewStats s = single_view_stats(points, Vec3{0, 0, 0});
    EXPECT_EQ(s.hidden, 0u);
    EXPECT_TRUE(s.single_view);
}

// Sampled all round and seen from outside, a sphere hides its far side: of the directions that meet it,
// each meets it twice, so half of the points lie behind the near half (a little less: cells at the
// silhouette hold a near and a far point at almost the same depth).
TEST(SingleView, a_sphere_sampled_all_round_hides_its_far_half)
{
    const std::vector<Vec3> points = positions_of(shapes::sphere(200000, 1.0, 4));
    // Near and far from it: a depth of a fortieth of the distance is still a layer behind another (a
    // ratio of 1.1 between the layers' depths, once asked, hid nothing beyond 20 radii: QA round 39).
    for (const double distance : {4.0, 50.0}) {
        SCOPED_TRACE(distance);
        const SingleViewStats s = single_view_stats(points, Vec3{0, 0, distance});
        EXPECT_GT(s.hidden_share, 0.40);
        EXPECT_LE(s.hidden_share, 0.52); // half, give or take the sample's randomness cell by cell
        EXPECT_FALSE(s.single_view);
    }
}

// Two parallel squares, the lower one seen only through the upper: half of the points are hidden. Moved
// sideways out of the upper one's shadow, the lower square is seen too: a single view again.
TEST(SingleView, a_layer_behind_another_is_hidden_and_seen_beside_it)
{
    PointCloud planes = shapes::parallel_planes(100000, 0.5);
    std::vector<Vec3> points = positions_of(planes); // z = 0 and z = 0.5 over [0, 1]²
    const Vec3 above{0.5, 0.5, 1.0};                 // the upper square's shadow covers the lower one
    const SingleViewStats stacked = single_view_stats(points, above);
    EXPECT_GT(stacked.hidden_share, 0.45);
    EXPECT_LE(stacked.hidden_share, 0.5);
    EXPECT_FALSE(stacked.single_view);
    for (Vec3& p : points)
        if (p.z < 0.25)
            p.x += 3.0;
    const SingleViewStats beside = single_view_stats(points, above);
    EXPECT_EQ(beside.hidden, 0u);
    EXPECT_TRUE(beside.single_view);
}

// A torus seen from one side at a grazing angle spreads its depths within a cell without a gap: no
// layers. The same torus sampled all round (a merge of views saved with one sensor origin, QA round 35)
// hides its far side.
TEST(SingleView, a_depth_image_is_one_view_and_the_whole_torus_is_not)
{
    const Vec3 eye{0.0, -4.0, 1.0};
    const std::vector<Vec3> all = positions_of(shapes::torus(200000));
    // A depth image: per ray of a 400 x 400 grid over the torus, the nearest hit, found by marching the
    // torus' distance function (exact enough: the step ends within 1e-9).
    const auto sdf = [](const Vec3& p) {
        const double q = std::sqrt(p.x * p.x + p.y * p.y) - 1.0;
        return std::sqrt(q * q + p.z * p.z) - 0.35;
    };
    std::vector<Vec3> view;
    const Vec3 forward = Vec3{0.0, 4.0, -1.0} / std::sqrt(17.0);
    const Vec3 right{1, 0, 0};
    const Vec3 up = cross(right, forward);
    for (int i = 0; i < 400; ++i)
        for (int j = 0; j < 400; ++j) {
            const Vec3 d = normalized(forward + right * (0.8 * (i / 399.0 - 0.5)) + up * (0.8 * (j / 399.0 - 0.5)));
            double t = 0.0;
            for (int k = 0; k < 400 && t < 10.0; ++k) {
                const double s = sdf(eye + d * t);
                if (s < 1e-9) {
                    view.push_back(eye + d * t);
                    break;
                }
                t += s;
            }
        }
    ASSERT_GT(view.size(), 20000u);
    const SingleViewStats one = single_view_stats(view, eye);
    EXPECT_LT(one.hidden_share, 0.02); // cells across the inner rim's silhouette only
    EXPECT_TRUE(one.single_view);
    const SingleViewStats merged = single_view_stats(all, eye);
    EXPECT_GT(merged.hidden_share, 0.2);
    EXPECT_FALSE(merged.single_view);
}

TEST(SingleView, points_at_the_viewpoint_are_left_out_and_nothing_is_no_view)
{
    const SingleViewStats none = single_view_stats({}, Vec3{0, 0, 0});
    EXPECT_EQ(none.sampled, 0u);
    EXPECT_FALSE(none.single_view);
    const SingleViewStats at_eye = single_view_stats({Vec3{1, 2, 3}, Vec3{1, 2, 3}}, Vec3{1, 2, 3});
    EXPECT_EQ(at_eye.sampled, 0u);
    EXPECT_FALSE(at_eye.single_view);
}

TEST(SingleView, bad_options_and_values_are_refused)
{
    const std::vector<Vec3> points{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const Vec3 eye{0, 0, 1};
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const auto& change : std::vector<void (*)(SingleViewOptions&)>{
             [](SingleViewOptions& o) { o.points_per_cell = 0.5; },
             [](SingleViewOptions& o) { o.layer_ratio = 0.5; },
             [](SingleViewOptions& o) { o.layer_ratio = std::numeric_limits<double>::quiet_NaN(); },
             [](SingleViewOptions& o) { o.min_gap_cells = -1.0; },
             [](SingleViewOptions& o) { o.max_hidden_share = 1.5; },
             [](SingleViewOptions& o) { o.max_samples = 0; }}) {
        SingleViewOptions o;
        change(o);
        EXPECT_THROW(single_view_stats(points, eye, o), InvalidInput);
    }
    EXPECT_THROW(single_view_stats(points, Vec3{nan, 0, 0}), InvalidInput);
    EXPECT_THROW(single_view_stats({Vec3{0, 0, 0}, Vec3{nan, 0, 0}}, eye), InvalidInput);
}
