// Outlier removal before the hierarchy (beyond the paper, which assumes a clean sample): a stray point
// makes its cluster unflat, is split off again and again, and ends up as the tip of a spike in the mesh.
// The test is the classic statistical one (mean distance to the k nearest neighbours) made relative
// twice, so that it needs no scale: against the point's own neighbours (density may vary across a scan)
// and against the whole cloud (stray points among stray points). See outliers.h.
// Neighbours come from neighbours.h (denoise.cpp uses them too).
#include "libmrtile/outliers.h"

#include "libmrtile/errors.h"
#include "libmrtile/median.h"
#include "libmrtile/neighbours.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace mrt {
namespace {


} // namespace

std::vector<std::uint32_t> find_outliers(const std::vector<Vec3>& positions, const OutlierOptions& o)
{
    if (o.neighbours == 0 || !(o.local_ratio >= 0.0) || !(o.global_ratio >= 0.0))
        throw InvalidInput("OutlierOptions: neighbours must be > 0 and local_ratio, global_ratio >= 0");
    const std::size_t n = positions.size(), k = o.neighbours;
    for (std::size_t i = 0; i < n; ++i)
        if (!is_finite(positions[i]))
            throw InvalidInput("find_outliers: position " + std::to_string(i) + " is not finite");
    if (n <= k || (o.local_ratio == 0.0 && o.global_ratio == 0.0))
        return {};
    // The k nearest other points of every point and their mean distance.
    const NearestNeighbours search(positions);
    std::vector<std::uint32_t> near(n * k);
    std::vector<double> spread(n);
    search.for_each_point(k, o.threads, [&](std::uint32_t i, const std::vector<std::uint32_t>& index, const std::vector<double>& distance) {
        assert(index.size() == k);
        double sum = 0.0;
        for (std::size_t m = 0; m < k; ++m) {
            near[i * k + m] = index[m];
            sum += distance[m];
        }
        spread[i] = sum / static_cast<double>(k);
    });

    std::vector<double> all = spread;
    const double global = upper_median_in_place(all);
    std::vector<std::uint32_t> out;
    std::vector<double> local(k);
    for (std::uint32_t i = 0; i < n; ++i) {
        bool outlier = o.global_ratio > 0.0 && global > 0.0 && spread[i] > o.global_ratio * global;
        if (!outlier && o.local_ratio > 0.0) {
            for (std::size_t m = 0; m < k; ++m)
                local[m] = spread[near[i * k + m]];
            const double around = upper_median_in_place(local);
            outlier = around > 0.0 && spread[i] > o.local_ratio * around;
        }
        if (outlier)
            out.push_back(i);
    }
    return out;
}

std::size_t remove_outliers(PointCloud& cloud, const OutlierOptions& options)
{
    check_colors(cloud, "remove_outliers");
    const std::vector<std::uint32_t> outliers = find_outliers(cloud.positions, options);
    if (outliers.empty())
        return 0;
    std::size_t kept = 0, next = 0;
    for (std::size_t i = 0; i < cloud.positions.size(); ++i) {
        if (next < outliers.size() && outliers[next] == i) {
            ++next;
            continue;
        }
        cloud.positions[kept] = cloud.positions[i];
        if (cloud.has_colors())
            cloud.colors[kept] = cloud.colors[i];
        ++kept;
    }
    cloud.positions.resize(kept);
    if (cloud.has_colors())
        cloud.colors.resize(kept);
    return outliers.size();
}

} // namespace mrt
