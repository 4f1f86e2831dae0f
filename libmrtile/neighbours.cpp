// Neighbourhoods for the point-wise stages that run before the hierarchy exists (beyond the paper:
// outliers.cpp and denoise.cpp). The hierarchy's own neighbourhoods (leaves, Gabriel graph) are not
// there yet, and both stages need each point's k nearest neighbours exactly: CGAL's kd-tree, built
// once, queried from every thread (nanoflann's, tried for the denoising's 48 neighbours per query,
// was 1.6x slower).
#include "libmrtile/neighbours.h"

#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/property_map.h>

#include <boost/tuple/tuple.hpp>

#include <cmath>

namespace mrt {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Entry = boost::tuple<Point, std::uint32_t>;
using Traits = CGAL::Search_traits_adapter<Entry, CGAL::Nth_of_tuple_property_map<0, Entry>, CGAL::Search_traits_3<Kernel>>;
using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;

} // namespace

struct NearestNeighbours::Tree
{
    std::vector<Entry> entries;
    Search::Tree tree;
};

NearestNeighbours::NearestNeighbours(const std::vector<Vec3>& positions) : tree_(std::make_unique<Tree>())
{
    tree_->entries.reserve(positions.size());
    for (std::uint32_t i = 0; i < positions.size(); ++i)
        tree_->entries.emplace_back(Point(positions[i].x, positions[i].y, positions[i].z), i);
    tree_->tree.insert(tree_->entries.begin(), tree_->entries.end());
    tree_->tree.build(); // built before threads query it (CGAL builds lazily otherwise)
}

NearestNeighbours::~NearestNeighbours() = default;

void NearestNeighbours::query(std::uint32_t i, std::size_t k, std::vector<std::uint32_t>& index, std::vector<double>& distance) const
{
    index.clear();
    distance.clear();
    // k + 1: the query finds the point itself too (or a duplicate of it first: whichever, the point's
    // own index is skipped).
    const Search search(tree_->tree, boost::get<0>(tree_->entries[i]), static_cast<unsigned>(k + 1));
    for (auto it = search.begin(); it != search.end() && index.size() < k; ++it) {
        const std::uint32_t j = boost::get<1>(it->first);
        if (j == i)
            continue;
        index.push_back(j);
        distance.push_back(std::sqrt(it->second));
    }
}

} // namespace mrt
