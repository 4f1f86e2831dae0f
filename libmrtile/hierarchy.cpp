// The persistent hierarchy of paper §4.1 as a data structure: derived per-node values and queries.
// Derived values (PCA frames, the tolerance scale, the noise floors) are recomputed when a model is
// built or loaded instead of being stored, so the model file holds only exact, mergeable statistics.
// The noise floor goes beyond the paper, which assumes that its smallest clusters are pieces of surface:
// under noise of about a point spacing they are blobs, and the floor keeps cuts above them.
#include "libmrtile/hierarchy.h"
#include "libmrtile/errors.h"
#include "libmrtile/median.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

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

double node_spacing(const Node& n)
{
    const double count = static_cast<double>(n.count());
    if (!(count > 0.0))
        return 0.0;
    const double area = 12.0 * std::sqrt(std::max(0.0, n.frame.values[1]) * std::max(0.0, n.frame.values[2])) / count;
    return std::sqrt(area / count);
}

LineSpread line_spread(const Node& n)
{
    const double count = static_cast<double>(n.count());
    if (!(count > 0.0))
        return {};
    // frame.values are of the scatter matrix (sums over the points): a variance is value / count.
    const double length = std::sqrt(12.0 * n.frame.values[2] / count);
    return {std::sqrt(n.frame.values[1] / count), length / count};
}

double Hierarchy::flatness(const Node& node, double largest_side) const
{
    if (info.criterion == Criterion::Tau)
        return node.frame.values[0];
    return largest_side > 0 ? node.rms_plane_distance / largest_side : 0.0;
}

namespace {

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
// Median leaf roughness at which a region's leaves are blobs: floor_of's full floor, and where the
// rules for noise its measures cannot see start.
constexpr double kNoisyLeaves = 0.4;
// How far up the tree those rules look: ancestors of up to kReach × the largest region's points.
constexpr std::size_t kReach = 64;

// The regions derive_noise_floor judges: the highest nodes under 32 × min_cluster points.
std::size_t min_cluster_of(const Hierarchy& h) { return h.info.min_cluster > 0 ? h.info.min_cluster : 16; }
bool is_region(const Hierarchy& h, const Node& n, std::size_t region_max)
{
    return n.count() < region_max && (n.parent < 0 || h.nodes[static_cast<std::size_t>(n.parent)].count() >= region_max);
}

// The floor of a region whose leaves are `leaves` and whose own roughness is `region` (see
// derive_noise_floor in hierarchy.h).
double floor_of(const Roughness& leaves, double region)
{
    constexpr double kSmooth = 0.2; // leaf roughness: no floor (full floor at kNoisyLeaves)
    constexpr double kCurved = 1.0, kNoisy = 0.7; // region roughness / leaf roughness: no .. full
    constexpr double kFactor = 3.0;
    if (leaves.rms.size() < kMinLeaves)
        return 0.0;
    const double rough = upper_median(leaves.roughness);
    if (!(rough > 0))
        return 0.0;
    const double weight = std::clamp((rough - kSmooth) / (kNoisyLeaves - kSmooth), 0.0, 1.0) *
                          std::clamp((kCurved - region / rough) / (kCurved - kNoisy), 0.0, 1.0);
    return weight > 0 ? weight * kFactor * upper_median(leaves.rms) : 0.0;
}

// Kurtosis of the distances of a node's points to its plane, E[d⁴] / E[d²]²: about 3 for noise (a
// Gaussian; 2.6-3.6 measured on noisy spheres), 1 for two sheets (a thin plate sampled on both sides:
// 1.3 on the three-holes solid at 4,000 points), 1.8 for a uniform spread.
double plane_kurtosis(const Hierarchy& h, const Node& n)
{
    const Vec3 normal = n.frame.vectors[0];
    double m2 = 0.0, m4 = 0.0;
    for (std::uint32_t i = n.begin; i < n.end; ++i) {
        const double d = dot(h.cloud.positions[i] - n.centre(), normal);
        const double d2 = d * d;
        m2 += d2;
        m4 += d2 * d2;
    }
    return m2 > 0.0 ? m4 * static_cast<double>(n.count()) / (m2 * m2) : 0.0;
}

// Noise wider than a region: under noise of two point spacings or more, a region's leaves and the
// region itself are blobs (roughness 0.6-0.8 at every size up to 512 points), so its roughness does
// not fall below its leaves' and floor_of sees no noise. Its ancestors show it: the roughness falls
// once a node is several σ wide, while its RMS plane distance stays at σ (saturated). The floor of
// such a region is kPlateauFactor × the RMS plane distance of its first ancestor that is a slab
// (roughness under kSlab), provided that RMS is within kSaturated of the region's own (else the
// thickness grows with the scale: a rod, a corner, shape and not noise) and the points spread about
// that plane as noise does, unimodally (kurtosis over kMinKurtosis; a thin plate sampled on both
// sides spreads as two sheets and keeps its detail). 0 when it does not apply. `leaf_roughness` is
// the median of the region's leaves; `kurtosis` caches plane_kurtosis per node (NaN = not computed).
double plateau_floor(const Hierarchy& h, const Node& region, double leaf_roughness, std::size_t region_max,
                     std::vector<double>& kurtosis)
{
    constexpr double kBlob = 0.4;    // region roughness: still a blob
    constexpr double kSlab = 0.35;   // an ancestor this smooth is a piece of noisy surface
    constexpr double kSaturated = 1.5;
    constexpr double kMinKurtosis = 2.2;
    constexpr double kPlateauFactor = 2.0;
    if (!(region.frame.values[1] > 0) || leaf_roughness < kNoisyLeaves || Roughness::node_roughness(region) < kBlob)
        return 0.0;
    for (std::int32_t a = region.parent; a >= 0; a = h.nodes[static_cast<std::size_t>(a)].parent) {
        const Node& up = h.nodes[static_cast<std::size_t>(a)];
        if (up.count() > kReach * region_max || !(up.frame.values[1] > 0))
            return 0.0;
        if (Roughness::node_roughness(up) >= kSlab)
            continue;
        if (!(up.rms_plane_distance <= kSaturated * region.rms_plane_distance))
            return 0.0;
        double& k = kurtosis[static_cast<std::size_t>(a)];
        if (std::isnan(k))
            k = plane_kurtosis(h, up);
        return k > kMinKurtosis ? kPlateauFactor * up.rms_plane_distance : 0.0;
    }
    return 0.0;
}

// A region judged by derive_noise_floor: its node, its leaves' median RMS plane distance and
// roughness, and the floor its own measures gave it.
struct JudgedRegion
{
    std::int32_t node = -1;
    double leaf_rms = 0.0;
    double leaf_roughness = 0.0;
    double floor = 0.0;
};

// Noise hidden by shape: a region across a sharp edge (a noisy box's), or one on a surface curved too
// much for a slab of several σ, has leaves as noisy as the regions beside it, but its own roughness
// rises with the scale like a curved surface's, and its measures give it no floor: a cut then refines
// it down to blobs, and the mesh along the edge breaks up (a box with noise of one spacing: 4 loops
// and 315 crossing faces at tolerance 0.002). Noise comes from the sensor and is the same nearby, and
// the leaves show it: a region with noisy leaves (roughness over kNoisyLeaves) takes the median floor
// of the regions near it in the tree (under its lowest ancestor with kNeighbours regions or more, of at most
// kReach × region_max points) whose leaves look alike (median RMS within kAlike of its own) and that
// have a floor, when they are at least half of the regions there. A floor only rises; the floors of
// the regions' own measures are the ones taken (no chains).
void take_neighbours_floors(Hierarchy& h, const std::vector<JudgedRegion>& judged, std::size_t region_max)
{
    constexpr double kAlike = 1.5;
    constexpr std::size_t kNeighbours = 8;
    const std::size_t count = h.nodes.size();
    std::vector<std::int32_t> judged_at(count, -1);  // node -> index in `judged`
    std::vector<std::uint32_t> regions_under(count, 0); // judged regions at or under a node
    for (std::size_t r = 0; r < judged.size(); ++r)
        judged_at[static_cast<std::size_t>(judged[r].node)] = static_cast<std::int32_t>(r);
    for (std::size_t k = count; k-- > 0;) { // children come after their parents
        const Node& n = h.nodes[k];
        if (judged_at[k] >= 0)
            regions_under[k] = 1;
        else if (!n.is_leaf() && n.count() >= region_max)
            regions_under[k] = regions_under[static_cast<std::size_t>(n.left)] + regions_under[static_cast<std::size_t>(n.right)];
    }
    // Where the regions near it do not tell (the box's edges are long, and some of their neighbourhoods
    // in the tree hold edge regions mostly): the whole sample's, when at least half of its regions with
    // noisy leaves have a floor and its leaves look like theirs.
    std::vector<double> floored_rms, floored_floor;
    std::size_t noisy_leaves = 0;
    for (const JudgedRegion& j : judged)
        if (j.leaf_roughness >= kNoisyLeaves) {
            ++noisy_leaves;
            if (j.floor > 0.0) {
                floored_rms.push_back(j.leaf_rms);
                floored_floor.push_back(j.floor);
            }
        }
    const bool sample_noisy = !floored_rms.empty() && 2 * floored_rms.size() >= noisy_leaves;
    const double sample_rms = sample_noisy ? upper_median(floored_rms) : 0.0;
    const double sample_floor = sample_noisy ? upper_median(floored_floor) : 0.0;
    auto whole_sample = [&](const JudgedRegion& me) {
        return sample_noisy && me.leaf_rms <= kAlike * sample_rms && sample_rms <= kAlike * me.leaf_rms ? sample_floor : 0.0;
    };
    std::vector<double> raised(judged.size(), 0.0), floors;
    std::vector<std::int32_t> stack;
    for (std::size_t r = 0; r < judged.size(); ++r) {
        const JudgedRegion& me = judged[r];
        if (me.leaf_roughness < kNoisyLeaves)
            continue;
        std::int32_t around = h.nodes[static_cast<std::size_t>(me.node)].parent;
        while (around >= 0 && regions_under[static_cast<std::size_t>(around)] < kNeighbours &&
               h.nodes[static_cast<std::size_t>(around)].count() <= kReach * region_max)
            around = h.nodes[static_cast<std::size_t>(around)].parent;
        if (around < 0 || h.nodes[static_cast<std::size_t>(around)].count() > kReach * region_max) {
            raised[r] = whole_sample(me);
            continue;
        }
        std::size_t others = 0;
        floors.clear();
        stack.assign(1, around);
        while (!stack.empty()) {
            const auto k = static_cast<std::size_t>(stack.back());
            stack.pop_back();
            const Node& n = h.nodes[k];
            if (judged_at[k] >= 0) {
                const JudgedRegion& other = judged[static_cast<std::size_t>(judged_at[k])];
                if (other.node == me.node)
                    continue;
                ++others;
                if (other.floor > 0.0 && other.leaf_roughness >= kNoisyLeaves && other.leaf_rms <= kAlike * me.leaf_rms &&
                    me.leaf_rms <= kAlike * other.leaf_rms)
                    floors.push_back(other.floor);
            } else if (!n.is_leaf() && n.count() >= region_max) {
                stack.push_back(n.left);
                stack.push_back(n.right);
            }
        }
        raised[r] = !floors.empty() && 2 * floors.size() >= others ? upper_median(floors) : whole_sample(me);
    }
    for (std::size_t r = 0; r < judged.size(); ++r) {
        Node& n = h.nodes[static_cast<std::size_t>(judged[r].node)];
        n.noise_floor = std::max(n.noise_floor, raised[r]);
    }
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

std::vector<char> has_point_within(const Hierarchy& h, const std::vector<Vec3>& queries, const std::vector<double>& radii,
                                   const std::vector<std::int32_t>* first_nodes, std::size_t threads)
{
    if (radii.size() != queries.size())
        throw InvalidInput("has_point_within: " + std::to_string(radii.size()) + " radii for " + std::to_string(queries.size()) + " queries");
    if (first_nodes && first_nodes->size() != queries.size())
        throw InvalidInput("has_point_within: " + std::to_string(first_nodes->size()) + " first nodes for " +
                           std::to_string(queries.size()) + " queries");
    if (first_nodes)
        for (const std::int32_t id : *first_nodes)
            if (id < -1 || (id >= 0 && static_cast<std::size_t>(id) >= h.nodes.size()))
                throw InvalidInput("has_point_within: first node " + std::to_string(id) + " is no node of the " +
                                   std::to_string(h.nodes.size()) + " of the hierarchy");
    std::vector<char> within(queries.size(), 0);
    if (h.nodes.empty())
        return within;
    run_parallel_ranges(queries.size(), 256, threads, [&](std::size_t begin, std::size_t end) {
        std::vector<std::int32_t> stack;
        for (std::size_t k = begin; k < end; ++k) {
            const Vec3& q = queries[k];
            if (!(radii[k] >= 0.0))
                continue;
            const double reach2 = radii[k] * radii[k];
            const std::int32_t first = first_nodes ? (*first_nodes)[k] : -1;
            // Depth first from `start`, skipping `done` (a subtree searched already); a box's distance is
            // never more than that of a point in it, so no point within reach is passed over.
            const auto search = [&](std::int32_t start, std::int32_t done) {
                stack.assign(1, start);
                while (!stack.empty()) {
                    const std::int32_t id = stack.back();
                    stack.pop_back();
                    const Node& n = h.nodes[static_cast<std::size_t>(id)];
                    if (id == done || n.box.squared_distance_to(q) > reach2)
                        continue;
                    if (!n.is_leaf()) {
                        stack.push_back(n.right);
                        stack.push_back(n.left);
                        continue;
                    }
                    for (std::uint32_t i = n.begin; i < n.end; ++i)
                        if (squared_norm(h.cloud.positions[i] - q) <= reach2)
                            return true;
                }
                return false;
            };
            within[k] = (first > 0 && search(first, -1)) || search(0, first > 0 ? first : -1) ? 1 : 0;
        }
    });
    return within;
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
    h.view.reset();
    if (h.cloud.viewpoint)
        h.view = single_view_stats(h.cloud.positions, *h.cloud.viewpoint);
    derive_noise_floor(h);
}

void derive_noise_floor(Hierarchy& h)
{
    const std::size_t count = h.nodes.size();
    if (count == 0)
        return;
    const std::size_t min_cluster = min_cluster_of(h);
    const std::size_t region_max = 32 * min_cluster, region_min = 8 * min_cluster;
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
    const double global = region_roughness.size() >= kMinLeaves ? floor_of(all, upper_median(region_roughness)) : 0.0;

    // Each region computes its floor (parents come before children, so regions come before what is
    // under them).
    std::vector<std::int32_t> stack;
    std::vector<double> kurtosis(count, std::numeric_limits<double>::quiet_NaN());
    std::vector<JudgedRegion> judged;
    for (std::size_t k = 0; k < count; ++k) {
        Node& n = h.nodes[k];
        n.noise_floor = 0.0;
        if (!is_region(h, n, region_max))
            continue;
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
        if (leaves.rms.size() < kMinLeaves) {
            n.noise_floor = global;
            continue;
        }
        // A small region (under half the largest) is judged at its parent's scale too, whichever
        // is smoother: under heavy noise a region of 250 points is itself still blob-like.
        double region_roughness = Roughness::node_roughness(n);
        if (n.parent >= 0 && 2 * n.count() < region_max) {
            const Node& parent = h.nodes[static_cast<std::size_t>(n.parent)];
            if (parent.frame.values[1] > 0)
                region_roughness = std::min(region_roughness, Roughness::node_roughness(parent));
        }
        const double leaf_roughness = upper_median(leaves.roughness);
        n.noise_floor = std::max(floor_of(leaves, region_roughness), plateau_floor(h, n, leaf_roughness, region_max, kurtosis));
        judged.push_back({static_cast<std::int32_t>(k), upper_median(leaves.rms), leaf_roughness, n.noise_floor});
    }
    take_neighbours_floors(h, judged, region_max);
    // A denoised sample's regions: at least their residual noise, which their leaves no longer show.
    if (h.denoise_moves.size() == h.cloud.size() && !h.denoise_moves.empty())
        for (Node& n : h.nodes)
            if (is_region(h, n, region_max))
                n.noise_floor = std::max(n.noise_floor, denoised_noise_floor(h, n));
    // Nodes under a region take its floor.
    for (std::size_t k = 0; k < count; ++k) {
        Node& n = h.nodes[k];
        if (n.parent >= 0 && h.nodes[static_cast<std::size_t>(n.parent)].count() < region_max)
            n.noise_floor = h.nodes[static_cast<std::size_t>(n.parent)].noise_floor;
    }
    // Above the regions: the smallest floor below, so that a node is refined wherever a part needs it.
    for (std::size_t k = count; k-- > 0;) {
        Node& n = h.nodes[k];
        if (!n.is_leaf() && n.count() >= region_max)
            n.noise_floor = std::min(h.nodes[static_cast<std::size_t>(n.left)].noise_floor,
                                     h.nodes[static_cast<std::size_t>(n.right)].noise_floor);
    }
}

double typical_move(const Hierarchy& h, std::size_t begin, std::size_t count)
{
    // Compared without the sum, which a count of SIZE_MAX wrapped round (QA round 51).
    if (count == 0 || begin > h.denoise_moves.size() || count > h.denoise_moves.size() - begin)
        return 0.0;
    std::vector<float> moves(h.denoise_moves.begin() + static_cast<std::ptrdiff_t>(begin),
                             h.denoise_moves.begin() + static_cast<std::ptrdiff_t>(begin + count));
    // |x| of a Gaussian x has its lower quartile at 0.3186 σ. The median (0.6745 σ) was thrown off
    // where a region spans a sharp edge: the noisy rocker arm's edge regions took floors that cost its
    // finest cut 13% of its accuracy (against 2% with the quartile); on smooth shapes the two agree
    // within 1%.
    const auto quartile = moves.begin() + static_cast<std::ptrdiff_t>(count / 4);
    std::nth_element(moves.begin(), quartile, moves.end());
    return 3.138 * static_cast<double>(*quartile); // 1 / 0.3186
}

double denoised_noise_floor(const Hierarchy& h, const Node& region)
{
    // kDenoisedFloorShare (0.7): the moved points keep about a third of the noise (each is the value
    // at its own spot of a quadric fitted to 48 points: README "Choices"), smooth over a few spacings,
    // so that nodes of a few dozen points cannot tell it from the surface. The share is where the finest cut came
    // nearest the true surface (face centroids): a torus and a bumpy ellipsoid, 1M points, noise of
    // 0.6 and 1.2 spacings, and a sphere, 40k points, noise of one spacing; floors of 0.3-1.0 × the
    // move (0.3 gave 3-6 times the tiles and was the farthest but for every leaf; 1.0 was farther
    // again on the ellipsoid's bumps; on the sphere 0.5 and 0.7 were within 1%). Per region (a few
    // hundred points), not per sample: a clean scan merged with a noisy one moves little where it is
    // clean, and one floor for all cut it as coarsely as the noisy part (QA round 33).
    return kDenoisedFloorShare * typical_move(h, region.begin, region.count());
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

NoiseFloorStops noise_floor_stops(const Hierarchy& h)
{
    NoiseFloorStops stops;
    if (h.nodes.empty())
        return stops;
    // The finest cut's walk (cut.cpp: rougher_than at limit 0), down to the first node the floor
    // holds: rough enough to split by its plane distance, not by a hole its tile would cover.
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
        const Node& n = h.nodes[static_cast<std::size_t>(stack.back())];
        stack.pop_back();
        if (n.is_leaf())
            continue;
        const bool holds_hole = n.coverage_gap > 0.0 && gap_dominates(n);
        if (n.rms_plane_distance > 0.0 && n.rms_plane_distance <= n.noise_floor && !holds_hole) {
            stops.points += n.count();
            stops.floor_max = std::max(stops.floor_max, n.noise_floor);
            continue;
        }
        stack.push_back(n.left);
        stack.push_back(n.right);
    }
    return stops;
}

bool sample_is_noisy(const Hierarchy& h)
{
    const std::size_t region_max = 32 * min_cluster_of(h);
    std::size_t regions = 0;
    Roughness leaves;
    for (const Node& n : h.nodes) {
        if (is_region(h, n, region_max))
            ++regions;
        if (n.is_leaf())
            leaves.add(n);
    }
    // The leaves, not the floors: floors come from noise of a fifth of a spacing on (meshes that the
    // floor alone keeps whole), and noise that breaks meshes (a spacing or more) makes blobs of leaves
    // also where the floor's rules miss it (3-4 spacings on a tube, one at a CAD part's sharp edges).
    return regions >= kMinLeaves && !leaves.roughness.empty() && upper_median(leaves.roughness) >= kNoisyLeaves;
}

} // namespace mrt
