// Outlier removal before the hierarchy (beyond the paper, which assumes a clean sample): a stray point
// makes its cluster unflat, is split off again and again, and ends up as the tip of a spike in the mesh.
// The test is the classic statistical one (mean distance to the k nearest neighbours) made relative
// twice, so that it needs no scale: against the point's own neighbours (density may vary across a scan)
// and against the whole cloud (stray points among stray points). See outliers.h.
// Neighbours come from CGAL's kd-tree (mesh_stats.cpp uses it too, for nearest distances only: here each
// point's neighbour indices are needed, so the tree stores them).
#include "libmrtile/outliers.h"

#include "libmrtile/errors.h"
#include "libmrtile/parallel.h"

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <boost/tuple/tuple.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace mrt {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Entry = boost::tuple<Point, std::uint32_t>;
using Traits = CGAL::Search_traits_adapter<Entry, CGAL::Nth_of_tuple_property_map<0, Entry>, CGAL::Search_traits_3<Kernel>>;
using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
using Tree = Search::Tree;

double median_of(std::vector<double>& values)
{
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

} // namespace

std::vector<std::uint32_t> find_outliers(const std::vector<Vec3>& positions, const OutlierOptions& o)
{
    if (o.neighbours == 0 || !(o.local_ratio >= 0.0) || !(o.global_ratio >= 0.0))
        throw InvalidInput("OutlierOptions: neighbours must be > 0 and local_ratio, global_ratio >= 0");
    const std::size_t n = positions.size(), k = o.neighbours;
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(positions[i].x) || !std::isfinite(positions[i].y) || !std::isfinite(positions[i].z))
            throw InvalidInput("find_outliers: position " + std::to_string(i) + " is not finite");
    if (n <= k || (o.local_ratio == 0.0 && o.global_ratio == 0.0))
        return {};
    std::vector<Entry> entries;
    entries.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i)
        entries.emplace_back(Point(positions[i].x, positions[i].y, positions[i].z), i);
    Tree tree(entries.begin(), entries.end());
    tree.build(); // built before the threads query it (CGAL builds lazily otherwise)

    // The k nearest other points of every point (the query finds the point itself too, or a duplicate
    // of it first: whichever, the point's own index is skipped) and their mean distance.
    std::vector<std::uint32_t> near(n * k);
    std::vector<double> spread(n);
    run_parallel_ranges(n, 4096, o.threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const Search search(tree, boost::get<0>(entries[i]), static_cast<unsigned>(k + 1));
            double sum = 0.0;
            std::size_t found = 0;
            for (auto it = search.begin(); it != search.end() && found < k; ++it) {
                const std::uint32_t j = boost::get<1>(it->first);
                if (j == i)
                    continue;
                near[i * k + found++] = j;
                sum += std::sqrt(it->second);
            }
            assert(found == k);
            spread[i] = sum / static_cast<double>(k);
        }
    });

    std::vector<double> all = spread;
    const double global = median_of(all);
    std::vector<std::uint32_t> out;
    std::vector<double> local(k);
    for (std::uint32_t i = 0; i < n; ++i) {
        bool outlier = o.global_ratio > 0.0 && global > 0.0 && spread[i] > o.global_ratio * global;
        if (!outlier && o.local_ratio > 0.0) {
            for (std::size_t m = 0; m < k; ++m)
                local[m] = spread[near[i * k + m]];
            const double around = median_of(local);
            outlier = around > 0.0 && spread[i] > o.local_ratio * around;
        }
        if (outlier)
            out.push_back(i);
    }
    return out;
}

std::size_t remove_outliers(PointCloud& cloud, const OutlierOptions& options)
{
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
