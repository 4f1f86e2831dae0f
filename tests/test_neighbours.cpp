// Tests of neighbours.h: the kd-tree's k nearest neighbours against brute force on clouds built to
// tie (integer grids, duplicates, a line, a single repeated point), with and without the radius hint,
// including hints that are too small; and a point repeated many times stays cheap.
#include "libmrtile/neighbours.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

namespace mrt {
namespace {

// The k nearest other points of point i by (squared distance, index): every distance, sorted.
std::vector<std::pair<double, std::uint32_t>> brute_force(const std::vector<Vec3>& p, std::uint32_t i, std::size_t k)
{
    std::vector<std::pair<double, std::uint32_t>> all;
    for (std::uint32_t j = 0; j < p.size(); ++j)
        if (j != i) {
            const Vec3 d = p[j] - p[i];
            all.emplace_back(d.x * d.x + d.y * d.y + d.z * d.z, j);
        }
    std::sort(all.begin(), all.end());
    all.resize(std::min(k, all.size()));
    return all;
}

// Whether `index` / `distance` are a right answer for point i: the brute-force distances in order,
// and distinct other points, each at the distance given (ties at the k-th may be any of the tied).
bool right_answer(const std::vector<Vec3>& p, std::uint32_t i, std::size_t k, const std::vector<std::uint32_t>& index,
                  const std::vector<double>& distance)
{
    const auto expected = brute_force(p, i, k);
    if (index.size() != expected.size() || distance.size() != expected.size())
        return false;
    std::vector<std::uint32_t> seen = index;
    std::sort(seen.begin(), seen.end());
    if (std::adjacent_find(seen.begin(), seen.end()) != seen.end())
        return false;
    for (std::size_t m = 0; m < expected.size(); ++m) {
        const Vec3 d = p[index[m]] - p[i];
        if (index[m] == i || distance[m] != std::sqrt(expected[m].first) ||
            distance[m] != std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z))
            return false;
    }
    return true;
}

// Every point through for_each_point (each queried with the radius of the one before, as denoise and
// outliers do), and every 7th point also alone with no radius, half the true one and zero.
void expect_brute_force(const std::vector<Vec3>& p, std::size_t k, const std::string& what)
{
    SCOPED_TRACE(what);
    const NearestNeighbours search(p);
    ASSERT_EQ(search.order().size(), p.size());
    std::vector<std::uint32_t> sorted = search.order();
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t i = 0; i < p.size(); ++i)
        ASSERT_EQ(sorted[i], i) << "order() is not a permutation";
    std::vector<std::uint32_t> index;
    std::vector<double> distance;
    std::size_t mismatches = 0;
    auto check = [&](std::uint32_t i, double within) {
        search.query(i, k, index, distance, within);
        const bool same = right_answer(p, i, k, index, distance);
        mismatches += same ? 0 : 1;
    };
    std::vector<std::vector<std::uint32_t>> visited(p.size());
    std::vector<std::vector<double>> visited_distance(p.size());
    search.for_each_point(k, 2, [&](std::uint32_t i, const std::vector<std::uint32_t>& found, const std::vector<double>& d) {
        visited[i] = found;
        visited_distance[i] = d;
    });
    for (std::uint32_t i = 0; i < p.size(); ++i) {
        const bool same = right_answer(p, i, k, visited[i], visited_distance[i]);
        mismatches += same ? 0 : 1;
    }
    for (std::uint32_t i = 0; i < p.size(); i += 7) {
        check(i, std::numeric_limits<double>::infinity());
        const double radius = distance.empty() ? 0.0 : distance.back();
        check(i, 0.5 * radius);
        check(i, 0.0);
    }
    EXPECT_EQ(mismatches, 0u);
}

TEST(NearestNeighbours, equals_brute_force_on_a_noisy_sphere)
{
    std::vector<Vec3> p = shapes::sphere(3000, 1.0, 5).positions;
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 0.01);
    for (Vec3& q : p)
        q += Vec3{noise(rng), noise(rng), noise(rng)};
    for (const std::size_t k : {1, 6, 47})
        expect_brute_force(p, k, "sphere, k = " + std::to_string(k));
}

TEST(NearestNeighbours, equals_brute_force_where_distances_tie)
{
    // An integer grid (every point has 6 neighbours at distance 1, 12 at sqrt 2, ...), shuffled, with
    // a tenth of its points repeated: ties are the rule, and only the index decides them.
    std::vector<Vec3> p;
    for (int x = 0; x < 14; ++x)
        for (int y = 0; y < 14; ++y)
            for (int z = 0; z < 6; ++z)
                p.push_back({double(x), double(y), double(z)});
    std::mt19937 rng(3);
    std::shuffle(p.begin(), p.end(), rng);
    for (std::size_t i = 0; i < p.size(); i += 10)
        p.push_back(p[i]);
    for (const std::size_t k : {1, 6, 26, 47})
        expect_brute_force(p, k, "grid, k = " + std::to_string(k));
    // Points on a line, and one point repeated: the boxes are flat or empty.
    std::vector<Vec3> line;
    for (int i = 0; i < 500; ++i)
        line.push_back({double(i % 37), 0.0, 0.0});
    expect_brute_force(line, 20, "line");
    expect_brute_force(std::vector<Vec3>(100, Vec3{1, 2, 3}), 10, "one point repeated");
}

TEST(NearestNeighbours, fewer_points_than_asked_gives_them_all)
{
    const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}};
    expect_brute_force(p, 5, "three points");
    const std::vector<Vec3> one{{0, 0, 0}};
    const NearestNeighbours search(one);
    std::vector<std::uint32_t> index{7};
    std::vector<double> distance{7.0};
    search.query(0, 3, index, distance);
    EXPECT_TRUE(index.empty());
    EXPECT_TRUE(distance.empty());
}

} // namespace
} // namespace mrt
