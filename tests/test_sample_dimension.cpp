// Whether a cloud samples a surface (sample_dimension.h): analytic clouds of known dimension (a plane
// and a sphere 2, a line 1, random points in a cube 3, a noisy sphere still a surface), real scans,
// and the option checks.

#include "formats/read_points.h"
#include "libmrtile/errors.h"
#include "libmrtile/sample_dimension.h"
#include "libmrtile/shapes.h"
#include "obj_fixture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

using namespace mrt;

namespace {

std::vector<Vec3> cube_points(std::size_t count, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Vec3> out(count);
    for (Vec3& p : out)
        p = Vec3{u(rng), u(rng), u(rng)};
    return out;
}

} // namespace

TEST(SampleDimension, surfaces_measure_two_and_do_not_fill_a_volume)
{
    const SampleDimension plane = sample_dimension(shapes::plane_grid(200).positions);
    EXPECT_EQ(plane.sampled, DimensionOptions{}.samples);
    EXPECT_NEAR(plane.mean_dimension, 2.0, 0.1);
    EXPECT_FALSE(plane.fills_volume);
    const SampleDimension sphere = sample_dimension(shapes::sphere(100000).positions);
    EXPECT_NEAR(sphere.mean_dimension, 2.0, 0.1);
    EXPECT_FALSE(sphere.fills_volume);
    // Noise of four point spacings (which breaks a mesh: README, Known limits) is still a surface at
    // the scale measured.
    PointCloud noisy = shapes::sphere(100000);
    shapes::add_noise(noisy, 4.0 * std::sqrt(4.0 * M_PI / 100000.0));
    const SampleDimension rough = sample_dimension(noisy.positions);
    EXPECT_LT(rough.mean_dimension, 2.5);
    EXPECT_FALSE(rough.fills_volume);
}

TEST(SampleDimension, random_points_in_a_cube_fill_a_volume)
{
    for (const std::size_t count : {20000u, 300000u}) {
        const SampleDimension cube = sample_dimension(cube_points(count, 7));
        EXPECT_GT(cube.sampled, 400u) << count;
        EXPECT_GT(cube.mean_dimension, 2.7) << count;
        EXPECT_TRUE(cube.fills_volume) << count;
    }
}

TEST(SampleDimension, points_along_a_line_measure_one)
{
    std::vector<Vec3> line(30000);
    for (std::size_t i = 0; i < line.size(); ++i)
        line[i] = Vec3{static_cast<double>(i) * 1e-3, 0.0, 0.0};
    const SampleDimension d = sample_dimension(line);
    EXPECT_NEAR(d.mean_dimension, 1.0, 0.05);
    EXPECT_FALSE(d.fills_volume);
}

TEST(SampleDimension, real_scans_are_surfaces)
{
    for (const char* name : {"/bun_zipper.ply", "/bun000.ply", "/igea.ply", "/fandisk.obj", "/rocker-arm.obj"}) {
        const SampleDimension d = sample_dimension(read_points(std::string(MRTILE_SHARED_DATA) + name).positions);
        EXPECT_GT(d.sampled, 0u) << name;
        EXPECT_LT(d.mean_dimension, 2.3) << name;
        EXPECT_FALSE(d.fills_volume) << name;
    }
    // A CAD part's surface (sharp edges, thin parts) sampled uniformly, not by its mesh's vertices.
    const SampleDimension part = sample_dimension(mrt::testing::sampled_obj_surface(MRTILE_SHARED_DATA "/rocker-arm.obj", 100000, 1).positions);
    EXPECT_GT(part.sampled, 0u);
    EXPECT_LT(part.mean_dimension, 2.3);
    EXPECT_FALSE(part.fills_volume);
}

// Too few points to measure at the scale asked (8 × far after thinning), or a clump of equal points:
// nothing measured, nothing refused.
TEST(SampleDimension, too_few_points_or_a_clump_tell_nothing)
{
    const SampleDimension few = sample_dimension(cube_points(8 * DimensionOptions{}.far - 1, 3));
    EXPECT_EQ(few.sampled, 0u);
    EXPECT_FALSE(few.fills_volume);
    const SampleDimension clump = sample_dimension(std::vector<Vec3>(50000, Vec3{1, 2, 3}));
    EXPECT_EQ(clump.sampled, 0u);
    EXPECT_FALSE(clump.fills_volume);
    EXPECT_EQ(sample_dimension({}).sampled, 0u);
}

TEST(SampleDimension, options_and_positions_are_checked)
{
    const std::vector<Vec3> points = cube_points(100, 1);
    DimensionOptions o;
    o.near = 1;
    EXPECT_THROW(sample_dimension(points, o), InvalidInput);
    o = {};
    o.far = o.near;
    EXPECT_THROW(sample_dimension(points, o), InvalidInput);
    o = {};
    o.samples = 0;
    EXPECT_THROW(sample_dimension(points, o), InvalidInput);
    o = {};
    o.max_points = 0;
    EXPECT_THROW(sample_dimension(points, o), InvalidInput);
    o = {};
    o.volume_dimension = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(sample_dimension(points, o), InvalidInput);
    std::vector<Vec3> bad = points;
    bad[5].y = std::numeric_limits<double>::infinity();
    EXPECT_THROW(sample_dimension(bad), InvalidInput);
}
