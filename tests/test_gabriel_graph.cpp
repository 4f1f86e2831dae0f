// Tests of gabriel_graph.h against the O(n³) definition on seeded random point sets.
#include "libmrtile/errors.h"
#include "libmrtile/gabriel_graph.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>

namespace mrt {
namespace {

std::vector<std::vector<std::uint32_t>> brute_force(const std::vector<Vec3>& pts)
{
    std::vector<std::vector<std::uint32_t>> adj(pts.size());
    for (std::uint32_t i = 0; i < pts.size(); ++i)
        for (std::uint32_t j = i + 1; j < pts.size(); ++j) {
            bool empty = true;
            for (std::uint32_t k = 0; k < pts.size() && empty; ++k)
                if (k != i && k != j && !is_gabriel_edge(pts[i], pts[j], pts[k]))
                    empty = false;
            if (empty) {
                adj[i].push_back(j);
                adj[j].push_back(i);
            }
        }
    return adj;
}

std::vector<Vec3> random_points(std::size_t n, std::uint32_t seed, bool planar)
{
    std::mt19937 rng(seed);
    auto u = [&] { return static_cast<double>(rng()) / 4294967296.0; };
    std::vector<Vec3> pts;
    for (std::size_t i = 0; i < n; ++i)
        pts.push_back({u(), u(), planar ? 0.0 : u()});
    return pts;
}

// The Delaunay-filtered construction equals the definition on random 3D sets of several sizes.
TEST(GabrielGraph, equals_brute_force_in_3d)
{
    for (std::size_t n : {2u, 3u, 5u, 40u, 300u})
        for (std::uint32_t seed : {1u, 2u, 3u}) {
            const auto pts = random_points(n, seed, false);
            EXPECT_EQ(gabriel_graph(pts), brute_force(pts)) << "n=" << n << " seed=" << seed;
        }
}

// Coplanar centres (a triangulation of dimension 2) and samples of a surface work too.
TEST(GabrielGraph, equals_brute_force_on_planar_and_surface_sets)
{
    const auto planar = random_points(200, 9, true);
    EXPECT_EQ(gabriel_graph(planar), brute_force(planar));
    const auto sphere = shapes::sphere(250, 1.0, 4).positions;
    EXPECT_EQ(gabriel_graph(sphere), brute_force(sphere));
}

// CGAL's exact arithmetic died in GMP (SIGFPE) on a NaN, and squares of 1e300 overflowed so that every
// Delaunay edge was kept (QA round 59): such points are refused with the point's index.
TEST(GabrielGraph, points_it_cannot_take_are_refused)
{
    std::vector<Vec3> points = shapes::sphere(50).positions;
    for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e300}) {
        std::vector<Vec3> p = points;
        p[17].z = bad;
        for (auto graph : {gabriel_graph, delaunay_graph}) {
            try {
                graph(p);
                ADD_FAILURE() << bad;
            } catch (const InvalidInput& e) {
                EXPECT_NE(std::string(e.what()).find("point 17"), std::string::npos) << e.what();
            }
        }
    }
    EXPECT_EQ(gabriel_graph(points).size(), points.size());
}

} // namespace
} // namespace mrt
