// The persistent hierarchy of paper §4.1 as a data structure: derived per-node values and queries.
// Derived values (PCA frames, the tolerance scale, the noise floors) are recomputed when a model is
// built or loaded instead of being stored, so the model file holds only exact, mergeable statistics.
// The noise floor goes beyond the paper, which assumes that its smallest clusters are pieces of surface:
// under noise of about a point spacing they are blobs, and the floor keeps cuts above them.
#include "libmrtile/hierarchy.h"
#include "libmrtile/parallel.h"

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

struct Roughness
{
    std::vector<double> rms;       // RMS plane distances of leaves
    std::vector<double> roughness; // RMS plane distance / RMS extent along the second axis
    void add(const Node& n)
    {
        if (n.count() < 3 || !(n.frame.values[1] > 0))
            return;
        rms.push_back(n.rms_plane_distance);
        roughness.push_back(node_roughness(n));
    }
    static double node_roughness(const Node& n)
    {
        return n.rms_plane_distance / std::sqrt(n.frame.values[1] / static_cast<double>(n.count()));
    }
};

constexpr std::size_t kMinLeaves = 8;

// The floor of a region whose leaves are `leaves` and whose own roughness is `region` (see
// derive_noise_floor in hierarchy.h).
double floor_of(const Roughness& leaves, double region)
{
    constexpr double kSmooth = 0.2, kRough = 0.4; // leaf roughness: no floor .. full floor
    constexpr double kCurved = 1.0, kNoisy = 0.7; // region roughness / leaf roughness: no .. full
    constexpr double kFactor = 3.0;
    if (leaves.rms.size() < kMinLeaves)
        return 0.0;
    const double rough = median(leaves.roughness);
    if (!(rough > 0))
        return 0.0;
    const double weight = std::clamp((rough - kSmooth) / (kRough - kSmooth), 0.0, 1.0) *
                          std::clamp((kCurved - region / rough) / (kCurved - kNoisy), 0.0, 1.0);
    return weight > 0 ? weight * kFactor * median(leaves.rms) : 0.0;
}

} // namespace

std::vector<std::uint32_t> points_in_box(const Hierarchy& h, const BoundingBox& box, std::size_t stride)
{
    std::vector<std::uint32_t> out;
    if (h.nodes.empty())
        return out;
    const auto step = static_cast<std::uint32_t>(std::max<std::size_t>(1, stride));
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
        const Node& n = h.nodes[static_cast<std::size_t>(stack.back())];
        stack.pop_back();
        if (!n.box.meets(box))
            continue;
        const bool inside = box.contains(n.box.min) && box.contains(n.box.max);
        if (!n.is_leaf() && !inside) {
            stack.push_back(n.right); // left first: ascending indices
            stack.push_back(n.left);
            continue;
        }
        // A leaf, or a node wholly inside: its range at once (every step-th point of the cloud).
        for (std::uint32_t i = (n.begin + step - 1) / step * step; i < n.end; i += step)
            if (inside || box.contains(h.cloud.positions[i]))
                out.push_back(i);
    }
    return out;
}

void update_derived(Hierarchy& h)
{
    // Each node on its own (a loaded 1M-point model has 170k of them): in chunks, on every thread.
    run_parallel_ranges(h.nodes.size(), 4096, 0, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            Node& n = h.nodes[k];
            n.frame = eigen_decomposition(n.moments);
            n.rms_plane_distance = n.moments.count ? std::sqrt(n.frame.values[0] / static_cast<double>(n.moments.count)) : 0.0;
        }
    });
    h.scale = tolerance_scale(h.cloud.positions);
    derive_noise_floor(h);
}

void derive_noise_floor(Hierarchy& h)
{
    const std::size_t count = h.nodes.size();
    if (count == 0)
        return;
    const std::size_t min_cluster = h.info.min_cluster > 0 ? h.info.min_cluster : 16;
    const std::size_t region_max = 32 * min_cluster, region_min = 8 * min_cluster;
    auto is_region = [&](const Node& n) {
        return n.count() < region_max && (n.parent < 0 || h.nodes[static_cast<std::size_t>(n.parent)].count() >= region_max);
    };
    // The whole sample's measure, for regions too small to judge alone: all its leaves, and the median
    // roughness of all its nodes of 16-31 x min_cluster points.
    Roughness all;
    std::vector<double> region_roughness;
    for (const Node& n : h.nodes) {
        if (n.is_leaf())
            all.add(n);
        if (n.count() >= 16 * min_cluster && n.count() < region_max && n.frame.values[1] > 0)
            region_roughness.push_back(Roughness::node_roughness(n));
    }
    const double global = region_roughness.size() >= kMinLeaves ? floor_of(all, median(region_roughness)) : 0.0;

    // Parents come before children: a region computes its floor, its descendants copy it.
    std::vector<std::int32_t> stack;
    for (std::size_t k = 0; k < count; ++k) {
        Node& n = h.nodes[k];
        n.noise_floor = 0.0;
        if (n.parent >= 0 && h.nodes[static_cast<std::size_t>(n.parent)].count() < region_max) {
            n.noise_floor = h.nodes[static_cast<std::size_t>(n.parent)].noise_floor;
        } else if (is_region(n)) {
            if (n.count() < region_min || !(n.frame.values[1] > 0)) {
                n.noise_floor = global;
                continue;
            }
            Roughness leaves;
            stack.assign(1, static_cast<std::int32_t>(k));
            while (!stack.empty()) {
                const Node& m = h.nodes[static_cast<std::size_t>(stack.back())];
                stack.pop_back();
                if (m.is_leaf()) {
                    leaves.add(m);
                } else {
                    stack.push_back(m.left);
                    stack.push_back(m.right);
                }
            }
            // A small region (under half the largest) is judged at its parent's scale too, whichever
            // is smoother: under heavy noise a region of 250 points is itself still blob-like.
            double region_roughness = Roughness::node_roughness(n);
            if (n.parent >= 0 && 2 * n.count() < region_max) {
                const Node& parent = h.nodes[static_cast<std::size_t>(n.parent)];
                if (parent.frame.values[1] > 0)
                    region_roughness = std::min(region_roughness, Roughness::node_roughness(parent));
            }
            n.noise_floor = leaves.rms.size() >= kMinLeaves ? floor_of(leaves, region_roughness) : global;
        }
    }
    // Above the regions: the smallest floor below, so that a node is refined wherever a part needs it.
    for (std::size_t k = count; k-- > 0;) {
        Node& n = h.nodes[k];
        if (!n.is_leaf() && n.count() >= region_max)
            n.noise_floor = std::min(h.nodes[static_cast<std::size_t>(n.left)].noise_floor,
                                     h.nodes[static_cast<std::size_t>(n.right)].noise_floor);
    }
}

void clear_noise_floor(Hierarchy& h)
{
    for (Node& n : h.nodes)
        n.noise_floor = 0.0;
}

double max_noise_floor(const Hierarchy& h)
{
    double m = 0.0;
    for (const Node& n : h.nodes)
        m = std::max(m, n.noise_floor);
    return m;
}

} // namespace mrt
