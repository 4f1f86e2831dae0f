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

namespace {

double median(std::vector<double> v)
{
    const auto middle = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), middle, v.end());
    return *middle;
}

// See Hierarchy::noise_floor. Medians, so that the nodes on sharp edges and at the sample's borders
// (rough for other reasons) do not decide.
double noise_floor(const Hierarchy& h)
{
    constexpr double kSmooth = 0.2, kRough = 0.4; // leaf roughness: no floor .. full floor
    constexpr double kCurved = 1.0, kNoisy = 0.6; // roughness 16-32x larger / at the leaves: no .. full
    constexpr double kFactor = 3.0;
    constexpr std::size_t kMinNodes = 8;
    const std::size_t min_cluster = h.info.min_cluster > 0 ? h.info.min_cluster : 16;
    auto roughness = [](const Node& n) {
        return n.rms_plane_distance / std::sqrt(n.frame.values[1] / static_cast<double>(n.count()));
    };
    std::vector<double> leaf_rms, leaf_roughness, coarse_roughness;
    for (const Node& n : h.nodes) {
        if (n.count() < 3 || !(n.frame.values[1] > 0))
            continue;
        if (n.is_leaf()) {
            leaf_rms.push_back(n.rms_plane_distance);
            leaf_roughness.push_back(roughness(n));
        } else if (n.count() >= 16 * min_cluster && n.count() < 32 * min_cluster) {
            coarse_roughness.push_back(roughness(n));
        }
    }
    if (leaf_rms.size() < kMinNodes || coarse_roughness.size() < kMinNodes)
        return 0.0;
    const double rough = median(leaf_roughness);
    const double ratio = median(coarse_roughness) / rough;
    const double weight = std::clamp((rough - kSmooth) / (kRough - kSmooth), 0.0, 1.0) *
                          std::clamp((kCurved - ratio) / (kCurved - kNoisy), 0.0, 1.0);
    return weight * kFactor * median(leaf_rms);
}

} // namespace

void update_derived(Hierarchy& h)
{
    for (Node& n : h.nodes) {
        n.frame = eigen_decomposition(n.moments);
        n.rms_plane_distance = n.moments.count ? std::sqrt(n.frame.values[0] / static_cast<double>(n.moments.count)) : 0.0;
    }
    h.scale = tolerance_scale(h.cloud.positions);
    h.noise_floor = noise_floor(h);
}

} // namespace mrt
