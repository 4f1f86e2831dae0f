// Beyond the paper: whether a cloud with a viewpoint is one view from there. build_surface refuses
// handles in a single view (a depth image is a disc with holes), which is right only when the viewpoint
// really is where every point was seen from; occlusion along the rays tells (see single_view.h).

#include "libmrtile/single_view.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

namespace mrt {

namespace {

// A direction on the cube map: the face (major axis and its sign) and the coordinates in it, in [-1, 1].
struct CubeDirection
{
    int face = 0;
    double u = 0.0, v = 0.0;
};

CubeDirection cube_direction(const Vec3& d)
{
    const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
    if (ax >= ay && ax >= az)
        return {d.x >= 0 ? 0 : 1, d.y / ax, d.z / ax};
    if (ay >= az)
        return {d.y >= 0 ? 2 : 3, d.z / ay, d.x / ay};
    return {d.z >= 0 ? 4 : 5, d.x / az, d.y / az};
}

struct Sample
{
    CubeDirection direction;
    double depth = 0.0;
};

// Cells of width `cell` (in cube-map units) on each face; the last one on a side may be narrower.
struct CellGrid
{
    double cell = 2.0;
    std::uint64_t per_side = 1;

    explicit CellGrid(double width) : cell(width), per_side(static_cast<std::uint64_t>(std::ceil(2.0 / width))) {}

    std::uint64_t index(double t) const
    {
        const auto i = static_cast<std::uint64_t>(std::max(0.0, std::floor((t + 1.0) / cell)));
        return std::min(i, per_side - 1);
    }
    std::uint64_t key(const CubeDirection& d) const
    {
        return (static_cast<std::uint64_t>(d.face) * per_side + index(d.u)) * per_side + index(d.v);
    }
};

std::size_t occupied_cells(const std::vector<Sample>& samples, const CellGrid& grid)
{
    std::vector<std::uint64_t> keys;
    keys.reserve(samples.size());
    for (const Sample& s : samples)
        keys.push_back(grid.key(s.direction));
    std::sort(keys.begin(), keys.end());
    return static_cast<std::size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

void check_options(const SingleViewOptions& o)
{
    const auto bad = [](const std::string& what) { throw InvalidInput("single_view_stats: " + what); };
    if (!(o.points_per_cell >= 1.0) || !std::isfinite(o.points_per_cell))
        bad("points_per_cell must be at least 1");
    if (!(o.layer_ratio >= 1.0) || !std::isfinite(o.layer_ratio))
        bad("layer_ratio must be 1 or more");
    if (!(o.min_gap_cells >= 0.0) || !std::isfinite(o.min_gap_cells))
        bad("min_gap_cells must be 0 or more");
    if (!(o.max_hidden_share >= 0.0) || !(o.max_hidden_share <= 1.0))
        bad("max_hidden_share must lie in [0, 1]");
    if (o.max_samples == 0)
        bad("max_samples must be at least 1");
}

} // namespace

SingleViewStats single_view_stats(const std::vector<Vec3>& points, const Vec3& viewpoint, const SingleViewOptions& options)
{
    check_options(options);
    if (!is_finite(viewpoint))
        throw InvalidInput("single_view_stats: the viewpoint is not finite");
    const std::size_t stride = std::max<std::size_t>(1, (points.size() + options.max_samples - 1) / options.max_samples);
    std::vector<Sample> samples;
    samples.reserve(points.size() / stride + 1);
    for (std::size_t i = 0; i < points.size(); i += stride) {
        if (!is_finite(points[i]))
            throw InvalidInput("single_view_stats: point " + std::to_string(i) + " is not finite");
        const Vec3 d = points[i] - viewpoint;
        const double depth = norm(d);
        if (depth > 0.0)
            samples.push_back({cube_direction(d), depth});
    }
    SingleViewStats stats;
    stats.sampled = samples.size();
    if (samples.empty())
        return stats;

    // Cells for about points_per_cell samples each: start as if the samples covered one face evenly,
    // then scale by how full the occupied cells are (a view covers some part of the sphere, unevenly).
    const double n = static_cast<double>(samples.size());
    double width = std::min(2.0, 2.0 / std::sqrt(std::max(1.0, n / options.points_per_cell)));
    for (int round = 0; round < 4; ++round) {
        const double per_cell = n / static_cast<double>(occupied_cells(samples, CellGrid(width)));
        width = std::clamp(width * std::sqrt(options.points_per_cell / per_cell), 1e-7, 2.0);
    }
    const CellGrid grid(width);

    std::vector<std::pair<std::uint64_t, double>> keyed; // (cell, depth)
    keyed.reserve(samples.size());
    for (const Sample& s : samples)
        keyed.push_back({grid.key(s.direction), s.depth});
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t i = 0; i < keyed.size();) {
        std::size_t j = i;
        while (j < keyed.size() && keyed[j].first == keyed[i].first)
            ++j;
        // The cell's angle is about width / (1 + u² + v²) at its centre (the cube map's stretch).
        const std::uint64_t key = keyed[i].first;
        const double cu = (static_cast<double>(key / grid.per_side % grid.per_side) + 0.5) * width - 1.0;
        const double cv = (static_cast<double>(key % grid.per_side) + 0.5) * width - 1.0;
        const double angle = width / (1.0 + cu * cu + cv * cv);
        for (std::size_t k = i + 1; k < j; ++k) {
            const double near = keyed[k - 1].second, far = keyed[k].second;
            if (far >= options.layer_ratio * near && far - near >= options.min_gap_cells * angle * near) {
                stats.hidden += j - k; // this one and every farther one lie behind the nearer layer
                break;
            }
        }
        i = j;
    }
    stats.hidden_share = static_cast<double>(stats.hidden) / n;
    stats.single_view = stats.hidden_share <= options.max_hidden_share;
    return stats;
}

} // namespace mrt
