// The persistent hierarchy of paper §4.1 as a data structure: derived per-node values and queries.
// Derived values (PCA frames) are recomputed from the stored moments instead of being stored, so the
// model file holds only exact, mergeable statistics.
#include "libmrtile/hierarchy.h"

#include <algorithm>
#include <cmath>

namespace mrt {

std::size_t Hierarchy::leaf_count() const
{
    return static_cast<std::size_t>(std::count_if(nodes.begin(), nodes.end(), [](const Node& n) { return n.is_leaf(); }));
}

std::uint32_t Hierarchy::max_depth() const
{
    std::uint32_t d = 0;
    for (const Node& n : nodes)
        d = std::max(d, n.depth);
    return d;
}

double Hierarchy::flatness(const Node& node, double largest_side) const
{
    if (info.criterion == Criterion::Tau)
        return node.frame.values[0];
    return largest_side > 0 ? node.rms_plane_distance / largest_side : 0.0;
}

void update_derived(Hierarchy& h)
{
    for (Node& n : h.nodes) {
        n.frame = eigen_decomposition(n.moments);
        n.rms_plane_distance = n.moments.count ? std::sqrt(n.frame.values[0] / static_cast<double>(n.moments.count)) : 0.0;
    }
    h.scale = tolerance_scale(h.cloud.positions);
}

} // namespace mrt
