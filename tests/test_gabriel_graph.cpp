// Tests of gabriel_graph.h against the O(n³) definition on seeded random point sets.
#include "libmrtile/gabriel_graph.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <random>

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

} // namespace
} // namespace mrt
