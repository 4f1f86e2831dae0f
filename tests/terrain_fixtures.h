#pragma once
// A rolling terrain 100 x 100 m (about 10 m of relief) sampled with 3 cm noise, and the same with birds
// 5-50 m over it: the stray-point tests of reconstruct and lod_set share it. Seeded through `rng`, which
// the caller may draw on afterwards.
#include "libmrtile/point_cloud.h"

#include <cmath>
#include <random>

namespace mrt::test {

inline double rolling_ground(double x, double y)
{
    return 3.0 * std::sin(x / 15.0) + 2.0 * std::cos(y / 11.0) + 0.5 * std::sin((x + y) / 5.0);
}

struct TerrainWithBirds
{
    PointCloud clean; //!< `points` samples of the ground
    PointCloud birds; //!< the same and `bird_count` points 5-50 m over the ground
};

inline TerrainWithBirds terrain_with_birds(std::mt19937& rng, int points = 40000, int bird_count = 100)
{
    std::uniform_real_distribution<double> u(0.0, 100.0), up(5.0, 50.0);
    std::normal_distribution<double> noise(0.0, 0.03);
    TerrainWithBirds t;
    for (int i = 0; i < points; ++i) {
        const double x = u(rng), y = u(rng);
        t.clean.positions.push_back({x, y, rolling_ground(x, y) + noise(rng)});
    }
    t.birds = t.clean;
    for (int i = 0; i < bird_count; ++i) {
        const double x = u(rng), y = u(rng);
        t.birds.positions.push_back({x, y, rolling_ground(x, y) + up(rng)});
    }
    return t;
}

} // namespace mrt::test
