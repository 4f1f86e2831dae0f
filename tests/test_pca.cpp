// Tests of pca.h: mergeable moments against brute force, eigen-decomposition on analytic inputs.
#include "libmrtile/pca.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

namespace mrt {
namespace {

// Merging the moments of two halves equals computing them over the whole (Chan's update is exact).
TEST(Moments, merge_equals_whole)
{
    PointCloud c = shapes::sphere(1000, 2.0, 11);
    const Moments whole = compute_moments(c.positions.data(), c.size());
    Moments a = compute_moments(c.positions.data(), 300);
    const Moments b = compute_moments(c.positions.data() + 300, 700);
    a.merge(b);
    EXPECT_EQ(a.count, whole.count);
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(a.mean[i], whole.mean[i], 1e-12);
    for (std::size_t i = 0; i < 6; ++i)
        EXPECT_NEAR(a.m2[i], whole.m2[i], 1e-9 * whole.sum_squared_distances());
}

// Adding points one by one (Welford) and removing them again agrees with the two-pass computation.
TEST(Moments, add_and_remove_match_two_pass)
{
    PointCloud c = shapes::torus(500);
    Moments m;
    for (const Vec3& p : c.positions)
        m.add(p);
    const Moments ref = compute_moments(c.positions.data(), c.size());
    for (std::size_t i = 0; i < 6; ++i)
        EXPECT_NEAR(m.m2[i], ref.m2[i], 1e-9 * ref.sum_squared_distances());
    for (std::size_t i = 250; i < 500; ++i)
        m.remove(c.positions[i]);
    const Moments half = compute_moments(c.positions.data(), 250);
    EXPECT_EQ(m.count, 250u);
    for (std::size_t i = 0; i < 6; ++i)
        EXPECT_NEAR(m.m2[i], half.m2[i], 1e-8 * half.sum_squared_distances());
}

// A planar grid has a zero smallest eigenvalue and the plane's normal as its eigenvector.
TEST(Eigen, plane_normal_is_smallest_eigenvector)
{
    PointCloud c = shapes::plane_grid(20);
    const Eigen3x3 e = eigen_decomposition(compute_moments(c.positions.data(), c.size()));
    EXPECT_NEAR(e.values[0], 0.0, 1e-12);
    EXPECT_NEAR(std::abs(e.vectors[0].z), 1.0, 1e-12);
    EXPECT_GT(e.values[1], 1.0);
    EXPECT_NEAR(e.values[1], e.values[2], 1e-9);
}

// Points on a segment along (1,2,2)/3 have that direction as principal axis and two zero eigenvalues.
TEST(Eigen, collinear_points_principal_axis)
{
    std::vector<Vec3> pts;
    for (int i = 0; i < 50; ++i)
        pts.push_back(Vec3{1, 2, 2} * (i / 3.0));
    const Eigen3x3 e = eigen_decomposition(compute_moments(pts.data(), pts.size()));
    EXPECT_NEAR(e.values[0], 0.0, 1e-9);
    EXPECT_NEAR(e.values[1], 0.0, 1e-9);
    EXPECT_NEAR(std::abs(dot(e.vectors[2], Vec3{1, 2, 2} / 3.0)), 1.0, 1e-12);
}

} // namespace
} // namespace mrt
