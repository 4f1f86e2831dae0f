// Implements: Heckel, Uva, Hamann, "Clustering-based generation of hierarchical surface models",
// 1998, §4.1 (Algorithm 1): divisive clustering with local reclassification over Gabriel neighbours.
// Why it is built this way:
//  - clusters keep explicit member lists while building, because reclassification moves points
//    between clusters that are not siblings; the exact, contiguous tree is assembled once at the end
//    from the final assignment (assemble_hierarchy), which is what makes every cut a partition;
//  - the Gabriel graph is updated locally after each split (paper: "updated locally"): the new
//    clusters look for neighbours only among the split cluster's old neighbours, tested against
//    nearby centres. It only decides which points are reclassified, so locality is enough.
#include "libmrtile/cluster_tree.h"

#include "libmrtile/coverage_gap.h"
#include "libmrtile/errors.h"
#include "libmrtile/gabriel_graph.h"
#include "libmrtile/huge_pages.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <deque>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <queue>
#include <string>
#include <tuple>

namespace mrt {
namespace {

constexpr const char* kBuildStage = "building hierarchy"; // BuildOptions::progress

// A point as the builder holds it: its position is copied next to its index so that scanning a
// cluster reads memory sequentially (the scans over clusters and their neighbours are the whole cost
// of the build; gathering positions through indices made it memory-bound).
struct Member
{
    Vec3 p;
    std::uint32_t index;
};
// A cluster's member list. Every split writes its cluster's members into two fresh lists, so the build
// touches new memory all the time: large lists ask for huge pages (huge_pages.h).
using Members = std::vector<Member, HugePageAllocator<Member>>;

struct Cluster
{
    Members members;
    Moments moments;
    double internal_error = 0.0;            // eq. 1: sum of distances to the centre
    double radius = 0.0;                    // largest distance of a member to the centre
    std::vector<std::uint32_t> neighbours;  // Gabriel neighbours (cluster ids, sorted)
    std::uint32_t version = 0;              // bumped on every change; stale queue entries are skipped
    std::uint64_t counted = 0;              // points counted as "still to split" for progress
    bool failing = false;                   // fails the flatness test (and may be split)
    bool queued = false;                    // has an entry in the queue (possibly with an older error)
    bool alive = true;
};

struct QueueEntry
{
    double error;
    std::uint32_t id;
    std::uint32_t version;
    bool operator<(const QueueEntry& o) const
    {
        // Max-heap on error; among equal errors the smaller id comes first (determinism).
        return std::tie(error, o.id) < std::tie(o.error, id);
    }
};

void insert_sorted(std::vector<std::uint32_t>& list, std::uint32_t value)
{
    auto it = std::lower_bound(list.begin(), list.end(), value);
    if (it == list.end() || *it != value)
        list.insert(it, value);
}

void erase_sorted(std::vector<std::uint32_t>& list, std::uint32_t value)
{
    auto it = std::lower_bound(list.begin(), list.end(), value);
    if (it != list.end() && *it == value)
        list.erase(it);
}

class Builder
{
public:
    Builder(const std::vector<Vec3>& positions, const BuildOptions& options, double threshold, double scale)
        : pos_(positions), options_(options), threshold_(threshold),
          min_separation_(std::max(kSeparationShare * scale,
                                   8.0 * scale / std::sqrt(static_cast<double>(std::max<std::size_t>(1, positions.size())))))
    {
    }

    void run();
    void split_failing();
    bool mark_gaps();
    double gap_of(std::uint32_t id) const;

    std::vector<std::int32_t> parent_of;
    std::vector<std::uint32_t> leaf_of_point;

private:
    bool is_flat(const Moments& m) const;
    void refresh(std::uint32_t id);
    void refresh_incremental(std::uint32_t id, const Members& left, const Members& arrived);
    void requeue(std::uint32_t id);
    void set_failing(std::uint32_t id, bool failing);
    void split(std::uint32_t id);
    void connect_new(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& old_neighbours);
    const Vec3& centre(std::uint32_t id) const { return centres_[id]; }
    void add_cluster();

    const std::vector<Vec3>& pos_;
    const BuildOptions& options_;
    const double threshold_; // on λ_min (Tau) or on the RMS plane distance in model units (Tolerance)
    // Two groups of a flat cluster this far apart are two objects (separation_gap): a tenth of the
    // cloud's size, and 8 of its spacings at the least (size / sqrt(points): an upper bound). Far
    // apart in the cloud's terms, since a cluster's own density cannot tell two far spheres from two
    // clumps of near-equal points a spacing apart (ten copies of a sphere with noise of 1e-6).
    static constexpr double kSeparationShare = 0.1;
    const double min_separation_;
    std::deque<Cluster> clusters_; // a deque: growing never copies (and never doubles the peak)
    // Centres and liveness kept apart from the (large) Cluster records: the graph update reads them
    // for many clusters at random, and this keeps those reads in cache.
    std::vector<Vec3> centres_;
    std::vector<char> alive_;
    std::priority_queue<QueueEntry> queue_;
    std::uint64_t unsettled_ = 0;
    std::uint64_t splits_ = 0;
    std::uint64_t failing_clusters_ = 0; // while > 0 the paper's literal order keeps splitting
    std::vector<std::uint32_t> gap_checked_; // per cluster: 1 + the version last judged by mark_gaps
};

bool Builder::is_flat(const Moments& m) const
{
    if (m.count < 3)
        return true;
    const double limit = options_.tau > 0 ? threshold_ : threshold_ * threshold_ * static_cast<double>(m.count);
    // The closed form is exact enough unless the value is near the limit; then ask the iterative solver.
    const double fast = smallest_eigenvalue_fast(m);
    const double margin = 1e-8 * m.sum_squared_distances();
    if (fast + margin < limit)
        return true;
    if (fast - margin > limit)
        return false;
    return eigen_decomposition(m).values[0] <= limit;
}

// Recomputes a cluster's statistics from its members (two passes: mean and M, then eq. 1) and puts
// it back in the queue if it still has to be split.
void Builder::refresh(std::uint32_t id)
{
    Cluster& c = clusters_[id];
    ++c.version;
    unsettled_ -= c.counted;
    c.counted = 0;
    if (c.members.empty()) {
        set_failing(id, false);
        c.alive = false;
        alive_[id] = 0;
        c.moments = Moments{};
        c.internal_error = 0;
        return;
    }
    Vec3 sum{0, 0, 0};
    for (const Member& mb : c.members)
        sum += mb.p;
    Moments m;
    m.count = c.members.size();
    m.mean = sum / static_cast<double>(m.count);
    double error = 0.0, radius2 = 0.0;
    for (const Member& mb : c.members) {
        const Vec3 d = mb.p - m.mean;
        radius2 = std::max(radius2, dot(d, d));
        add_outer_product(m.m2, d);
        error += std::sqrt(dot(d, d));
    }
    c.moments = m;
    centres_[id] = m.mean;
    c.internal_error = error;
    c.radius = std::sqrt(radius2);
    requeue(id);
}

void Builder::requeue(std::uint32_t id)
{
    Cluster& c = clusters_[id];
    const bool splittable = c.members.size() > options_.min_cluster;
    set_failing(id, splittable && !is_flat(c.moments));
    if (c.failing) {
        c.counted = c.members.size();
        unsettled_ += c.counted;
    }
    // One queue entry per cluster: a changed cluster keeps its entry, which is corrected when it
    // reaches the top (a lazy decrease-key; it bounds the queue by the number of clusters).
    if ((c.failing || (splittable && options_.paper_split_order)) && !c.queued) {
        queue_.push({c.internal_error, id, c.version});
        c.queued = true;
    }
}

void Builder::set_failing(std::uint32_t id, bool failing)
{
    Cluster& c = clusters_[id];
    if (c.failing == failing)
        return;
    c.failing = failing;
    if (failing)
        ++failing_clusters_;
    else
        --failing_clusters_;
}

// A neighbour that gained or lost a few points: exact moments by Welford updates, and eq. 1 and the
// bounding radius updated from the moved points only (eq. 1 only orders the splits; the stored tree
// recomputes it exactly). Large changes take the full pass.
void Builder::refresh_incremental(std::uint32_t id, const Members& left, const Members& arrived)
{
    Cluster& c = clusters_[id];
    if (c.members.empty() || 8 * (left.size() + arrived.size()) > c.members.size()) {
        refresh(id);
        return;
    }
    ++c.version;
    unsettled_ -= c.counted;
    c.counted = 0;
    const Vec3 old_centre = c.moments.mean;
    double radius = c.radius;
    for (const Member& mb : left) {
        c.moments.remove(mb.p);
        c.internal_error -= distance(mb.p, old_centre);
    }
    for (const Member& mb : arrived) {
        c.moments.add(mb.p);
        const double d = distance(mb.p, old_centre);
        c.internal_error += d;
        radius = std::max(radius, d);
    }
    c.internal_error = std::max(0.0, c.internal_error);
    centres_[id] = c.moments.mean;
    c.radius = radius + distance(c.moments.mean, old_centre); // still an upper bound
    requeue(id);
}

// Local Gabriel update after C split into a and b (paper: "the Gabriel graph is updated locally").
// The new clusters look for neighbours among each other and C's old neighbours; a candidate edge is
// tested against those clusters and the candidate's own neighbours. Edges between two old
// neighbours are left as they were: a and b sit where C was, so C's removal rarely unblocks one.
void Builder::connect_new(std::uint32_t a, std::uint32_t b, const std::vector<std::uint32_t>& old_neighbours)
{
    std::vector<std::uint32_t> local;
    local.reserve(old_neighbours.size() + 2);
    for (std::uint32_t id : old_neighbours)
        if (clusters_[id].alive)
            local.push_back(id);
    const std::size_t old_count = local.size();
    for (std::uint32_t id : {a, b})
        if (clusters_[id].alive)
            local.push_back(id);

    std::vector<Vec3> blockers; // centres, copied so the tests below read memory sequentially
    for (std::size_t i = old_count; i < local.size(); ++i) {
        const std::uint32_t x = local[i];
        for (std::size_t j = 0; j < local.size(); ++j) {
            const std::uint32_t y = local[j];
            if (y == x || (j >= old_count && j < i))
                continue; // itself, or the pair (b, a) already tested as (a, b)
            const Vec3 cx = centre(x), cy = centre(y);
            blockers.clear();
            for (std::uint32_t o : local)
                if (o != x && o != y)
                    blockers.push_back(centre(o));
            for (std::uint32_t o : clusters_[y].neighbours)
                if (o != x && alive_[o])
                    blockers.push_back(centre(o));
            bool empty = true;
            for (const Vec3& o : blockers)
                if (!is_gabriel_edge(cx, cy, o)) {
                    empty = false;
                    break;
                }
            if (empty) {
                insert_sorted(clusters_[x].neighbours, y);
                insert_sorted(clusters_[y].neighbours, x);
            }
        }
    }
}

void Builder::split(std::uint32_t id)
{
    // Copy what we need of C: the clusters_ vector grows below.
    const Members members = std::move(clusters_[id].members);
    const std::vector<std::uint32_t> neighbours = std::move(clusters_[id].neighbours);
    const Moments moments = clusters_[id].moments;
    const Vec3 c = moments.mean;
    unsettled_ -= clusters_[id].counted;
    clusters_[id].counted = 0;
    set_failing(id, false);
    clusters_[id].alive = false;
    alive_[id] = 0;
    clusters_[id].members.clear();
    std::vector<std::uint32_t>().swap(clusters_[id].neighbours); // release: dead clusters keep no memory
    for (std::uint32_t n : neighbours)
        erase_sorted(clusters_[n].neighbours, id);

    // New centres (§4.1): ± one standard deviation along the principal axis for small clusters; half
    // way towards the farthest point (the direction of highest deviation) for large ones.
    Vec3 offset;
    if (members.size() <= options_.pca_limit) {
        const Eigen3x3 e = eigen_decomposition(moments);
        offset = e.vectors[2] * std::sqrt(e.values[2] / static_cast<double>(moments.count));
    } else {
        double far = -1.0;
        for (const Member& mb : members) {
            const double d = squared_distance(mb.p, c);
            if (d > far) {
                far = d;
                offset = (mb.p - c) * 0.5;
            }
        }
    }

    const auto a = static_cast<std::uint32_t>(clusters_.size());
    const std::uint32_t b = a + 1;
    add_cluster();
    add_cluster();
    clusters_[a].members.reserve(members.size() / 2 + members.size() / 8 + 4);
    clusters_[b].members.reserve(members.size() / 2 + members.size() / 8 + 4);
    parent_of.push_back(static_cast<std::int32_t>(id));
    parent_of.push_back(static_cast<std::int32_t>(id));
    Vec3 ca = c + offset, cb = c - offset;
    // Two Lloyd steps between the two new centres alone (2-means on C's points) before the paper's
    // reclassification: one assignment pass leaves the split line where the offset guessed it, which
    // cuts across close parallel sheets; a couple of iterations settle it on the natural gap.
    for (int iteration = 0; iteration < 2; ++iteration) {
        Vec3 sa{0, 0, 0}, sb{0, 0, 0};
        std::size_t na = 0, nb = 0;
        // Nearer to ca than to cb ⟺ on ca's side of their bisector plane: one dot product.
        const Vec3 axis = ca - cb;
        const double split = dot(axis, (ca + cb) * 0.5);
        // Without a branch: the side is as good as random from point to point, and mispredicted
        // branches took most of this loop's time. Adding 0 leaves a sum as it is.
        for (const Member& mb : members) {
            const double to_a = dot(mb.p, axis) >= split ? 1.0 : 0.0;
            sa += mb.p * to_a;
            sb += mb.p * (1.0 - to_a);
            na += static_cast<std::size_t>(to_a);
        }
        nb = members.size() - na;
        if (na == 0 || nb == 0)
            break;
        ca = sa / static_cast<double>(na);
        cb = sb / static_cast<double>(nb);
    }

    // Reclassify the points of C among {a, b} ∪ neighbours(C) ...
    const bool reclassify = options_.reclassify;
    std::vector<Members> incoming(neighbours.size());
    std::vector<Vec3> neighbour_centres(neighbours.size());
    for (std::size_t k = 0; k < neighbours.size(); ++k)
        neighbour_centres[k] = centre(neighbours[k]);
    for (const Member& mb : members) {
        const Vec3& p = mb.p;
        const double da = squared_distance(p, ca), db = squared_distance(p, cb);
        double best = std::min(da, db);
        std::size_t target = da <= db ? 0 : 1; // 0 = a, 1 = b, 2 + k = neighbour k
        if (reclassify) {
            for (std::size_t k = 0; k < neighbours.size(); ++k) {
                const double d = squared_distance(p, neighbour_centres[k]);
                if (d < best) {
                    best = d;
                    target = 2 + k;
                }
            }
        }
        if (target < 2)
            clusters_[target == 0 ? a : b].members.push_back(mb);
        else
            incoming[target - 2].push_back(mb);
    }

    // ... and the points of each neighbour N among {N, a, b}.
    std::vector<Members> leaving(neighbours.size());
    if (reclassify) {
        for (std::size_t k = 0; k < neighbours.size(); ++k) {
            Cluster& n = clusters_[neighbours[k]];
            const Vec3 cn = n.moments.mean;
            // No member of N can be nearer to a new centre than to cN when N's bounding ball stays
            // on cN's side of both bisector planes: skip the scan (it is most of the build's cost).
            const double reach = 2.0 * n.radius;
            if (reach * reach < std::min(squared_distance(cn, ca), squared_distance(cn, cb)) && incoming[k].empty())
                continue;
            // Nearer to ca than to cn ⟺ dot(p, ca − cn) > (|ca|² − |cn|²) / 2: one dot product per
            // comparison. Leaving members are swapped with the last one, so members that stay are
            // never rewritten (most of them stay).
            const Vec3 ua = ca - cn, ub = cb - cn, uab = ca - cb;
            const double ta = 0.5 * (squared_norm(ca) - squared_norm(cn));
            const double tb = 0.5 * (squared_norm(cb) - squared_norm(cn));
            const double tab = 0.5 * (squared_norm(ca) - squared_norm(cb));
            Members& list = n.members;
            for (std::size_t i = 0; i < list.size();) {
                const Vec3& p = list[i].p;
                const bool nearer_a = dot(p, ua) > ta, nearer_b = dot(p, ub) > tb;
                if (!nearer_a && !nearer_b) {
                    ++i;
                    continue;
                }
                const std::uint32_t target = nearer_a && (!nearer_b || dot(p, uab) >= tab) ? a : b;
                clusters_[target].members.push_back(list[i]);
                leaving[k].push_back(list[i]);
                list[i] = list.back();
                list.pop_back();
            }
            list.insert(list.end(), incoming[k].begin(), incoming[k].end());
        }
    }

    // Move the centres (recompute statistics), then update the graph around the new clusters.
    refresh(a);
    refresh(b);
    for (std::size_t k = 0; k < neighbours.size(); ++k)
        if (!leaving[k].empty() || !incoming[k].empty())
            refresh_incremental(neighbours[k], leaving[k], incoming[k]);
    for (std::uint32_t n : neighbours)
        if (!clusters_[n].alive) {
            for (std::uint32_t m : clusters_[n].neighbours)
                erase_sorted(clusters_[m].neighbours, n);
            std::vector<std::uint32_t>().swap(clusters_[n].neighbours);
        }
    if (clusters_[a].alive || clusters_[b].alive)
        connect_new(a, b, neighbours);
}

void Builder::add_cluster()
{
    clusters_.emplace_back();
    centres_.emplace_back();
    alive_.push_back(1);
}

void Builder::split_failing()
{
    // Every split adds a cluster; reclassification can empty clusters but each split still removes
    // one unflat cluster from the queue, so 4n splits is an unreachable bound that guards the loop.
    const std::uint64_t max_splits = 4 * static_cast<std::uint64_t>(pos_.size()) + 16;
    while (!queue_.empty() && failing_clusters_ > 0 && splits_ < max_splits) {
        const QueueEntry top = queue_.top();
        queue_.pop();
        Cluster& c = clusters_[top.id];
        c.queued = false;
        const bool splittable = c.members.size() > options_.min_cluster;
        if (!c.alive || !(c.failing || (splittable && options_.paper_split_order)))
            continue;
        if (top.error != c.internal_error) { // changed since queued: take its place by its current error
            queue_.push({c.internal_error, top.id, c.version});
            c.queued = true;
            continue;
        }
        split(top.id);
        ++splits_;
        if (options_.progress && (splits_ & 1023) == 0)
            options_.progress(kBuildStage, 1.0 - static_cast<double>(unsettled_) / static_cast<double>(pos_.size()));
    }
}

// The coverage gap of a cluster (coverage_gap.h) in its own plane; its Gabriel neighbours' points near
// that plane fill the grid, so only surface nobody sampled counts.
double Builder::gap_of(std::uint32_t id) const
{
    const Cluster& c = clusters_[id];
    // Every point: this is the only time a leaf is judged at full resolution (set_coverage_gaps samples
    // large nodes), and only flat clusters are judged, each once per change.
    std::vector<Vec3> points;
    points.reserve(c.members.size());
    for (const Member& mb : c.members)
        points.push_back(mb.p);
    const Eigen3x3 frame = eigen_decomposition(c.moments);
    const CoverageOptions options;
    const double alone = std::max(coverage_gap(points, frame.vectors[2], frame.vectors[1], options),
                                  separation_gap(points, frame.vectors[2], frame.vectors[1], min_separation_, options));
    if (alone <= 0)
        return 0.0;
    const Vec3 normal = frame.vectors[0], centre = c.moments.mean;
    double thickness = 0.0;
    for (const Member& mb : c.members)
        thickness = std::max(thickness, std::abs(dot(mb.p - centre, normal)));
    thickness += 1e-9 * (c.radius + 1e-300);
    std::vector<Vec3> fill;
    for (std::uint32_t n : c.neighbours)
        for (const Member& mb : clusters_[n].members)
            if (std::abs(dot(mb.p - centre, normal)) <= thickness)
                fill.push_back(mb.p);
    return std::max(coverage_gap(points, frame.vectors[2], frame.vectors[1], options, fill),
                    separation_gap(points, frame.vectors[2], frame.vectors[1], min_separation_, options, fill));
}

// Marks every flat, splittable cluster not judged since it last changed whose tile would cover a gap
// as failing, and queues it. Returns whether any was.
bool Builder::mark_gaps()
{
    gap_checked_.resize(clusters_.size(), 0);
    bool any = false;
    for (std::uint32_t id = 0; id < clusters_.size(); ++id) {
        Cluster& c = clusters_[id];
        if (!c.alive || c.failing || c.members.size() <= options_.min_cluster || gap_checked_[id] == c.version + 1)
            continue;
        gap_checked_[id] = c.version + 1;
        if (gap_of(id) <= 0)
            continue;
        set_failing(id, true);
        any = true;
        if (!c.queued) {
            queue_.push({c.internal_error, id, c.version});
            c.queued = true;
        }
    }
    return any;
}

void Builder::run()
{
    const std::size_t n = pos_.size();
    add_cluster();
    clusters_[0].members.reserve(n);
    for (std::uint32_t i = 0; i < n; ++i)
        clusters_[0].members.push_back({pos_[i], i});
    parent_of.push_back(-1);
    refresh(0);

    split_failing();
    // Flat clusters whose tiles would cover holes or notches are split too (BuildOptions::split_gaps),
    // round by round: a split's children, and the neighbours it changed, are judged in the next round.
    // The rounds are bounded (each splits at least one cluster; 64 is far more than the depth of a
    // hole's splits) so that no input can make them run long.
    // Not with the paper's literal order: a failing cluster there makes every cluster splittable.
    for (int round = 0; round < 64 && options_.split_gaps && !options_.paper_split_order && mark_gaps(); ++round)
        split_failing();

    reserve_on_huge_pages(leaf_of_point, n);
    leaf_of_point.assign(n, 0);
    for (std::uint32_t id = 0; id < clusters_.size(); ++id)
        for (const Member& mb : clusters_[id].members)
            leaf_of_point[mb.index] = id;
    if (options_.progress)
        options_.progress(kBuildStage, 1.0);
}

} // namespace

Hierarchy assemble_hierarchy(PointCloud cloud, const std::vector<std::int32_t>& parent_of,
                             const std::vector<std::uint32_t>& leaf_of_point)
{
    const std::size_t n = cloud.positions.size();
    const std::size_t clusters = parent_of.size();
    if (leaf_of_point.size() != n || clusters == 0)
        throw InvalidInput("assemble_hierarchy: leaf_of_point must have one entry per point and parent_of at least the root");
    // What build_hierarchy checks before it partitions, checked here for callers that bring their own
    // (QA round 59: too few colours were copied past their end in the permutation below).
    if (n > 0)
        validate(cloud, "assemble_hierarchy");
    else
        check_colors(cloud, "assemble_hierarchy");

    // Children in creation order; a cluster's children are always created after it.
    std::vector<std::vector<std::uint32_t>> children(clusters);
    for (std::uint32_t c = 1; c < clusters; ++c) {
        const std::int32_t p = parent_of[c];
        if (p < 0 || static_cast<std::uint32_t>(p) >= c)
            throw InvalidInput("assemble_hierarchy: parent_of must list parents before children");
        children[static_cast<std::size_t>(p)].push_back(c);
        // A split makes two clusters: a third child had no place in the binary tree, its points no
        // leaf, and the permutation below never ended (QA round 59).
        if (children[static_cast<std::size_t>(p)].size() > 2)
            throw InvalidInput("assemble_hierarchy: cluster " + std::to_string(p) + " has more than two children (a split makes two)");
    }
    std::vector<std::uint64_t> count(clusters, 0);
    for (std::uint32_t leaf : leaf_of_point) {
        if (leaf >= clusters || !children[leaf].empty())
            throw InvalidInput("assemble_hierarchy: a point is assigned to a cluster that is not a leaf");
        ++count[leaf];
    }
    for (std::size_t c = clusters; c-- > 1;)
        count[static_cast<std::size_t>(parent_of[c])] += count[c];

    // Depth-first, parents before children, skipping empty subtrees and splicing out clusters left
    // with a single non-empty child (explicit stack: the tree can be deep).
    Hierarchy h;
    std::vector<std::int32_t> node_of_leaf(clusters, -1);
    struct Item
    {
        std::uint32_t cluster;
        std::int32_t parent;
        bool is_left;
    };
    std::vector<Item> stack;
    reserve_on_huge_pages(h.nodes, clusters); // at most one node per cluster (splicing drops some): no regrowth copies
    if (n > 0)
        stack.push_back({0, -1, true});
    while (!stack.empty()) {
        Item item = stack.back();
        stack.pop_back();
        std::uint32_t c = item.cluster;
        for (;;) { // splice chains of single non-empty children
            std::uint32_t nonempty = 0, last = 0;
            for (std::uint32_t ch : children[c])
                if (count[ch] > 0) {
                    ++nonempty;
                    last = ch;
                }
            if (nonempty == 1)
                c = last;
            else
                break;
        }
        const auto index = static_cast<std::int32_t>(h.nodes.size());
        h.nodes.emplace_back();
        Node& node = h.nodes.back();
        node.parent = item.parent;
        if (item.parent >= 0) {
            Node& parent = h.nodes[static_cast<std::size_t>(item.parent)];
            node.depth = parent.depth + 1;
            (item.is_left ? parent.left : parent.right) = index;
        }
        std::vector<std::uint32_t> kids;
        for (std::uint32_t ch : children[c])
            if (count[ch] > 0)
                kids.push_back(ch);
        if (kids.empty()) {
            node_of_leaf[c] = index;
            continue;
        }
        assert(kids.size() == 2); // at most two children (checked above), and one is spliced out
        stack.push_back({kids[1], index, false});
        stack.push_back({kids[0], index, true});
    }

    // Leaves in depth-first order get consecutive point ranges; points keep input order inside a leaf.
    std::vector<std::uint32_t> leaf_rank(h.nodes.size(), 0);
    std::vector<std::uint64_t> start(h.nodes.size() + 1, 0);
    for (std::uint32_t leaf : leaf_of_point)
        ++start[static_cast<std::size_t>(node_of_leaf[leaf]) + 1];
    for (std::size_t i = 1; i < start.size(); ++i)
        start[i] += start[i - 1];
    std::vector<std::uint64_t> fill(start.begin(), start.end() - 1);
    std::vector<std::uint32_t> order;
    reserve_on_huge_pages(order, n);
    order.resize(n);
    for (std::uint32_t i = 0; i < n; ++i)
        order[fill[static_cast<std::size_t>(node_of_leaf[leaf_of_point[i]])]++] = i;
    for (std::size_t k = 0; k < h.nodes.size(); ++k) {
        h.nodes[k].begin = static_cast<std::uint32_t>(start[k]);
        h.nodes[k].end = static_cast<std::uint32_t>(start[k + 1]);
    }
    // Internal nodes span their children (children come after parents: go backwards).
    for (std::size_t k = h.nodes.size(); k-- > 0;) {
        Node& node = h.nodes[k];
        if (!node.is_leaf()) {
            node.begin = h.nodes[static_cast<std::size_t>(node.left)].begin;
            node.end = h.nodes[static_cast<std::size_t>(node.right)].end;
        }
    }

    // Permute in place, cycle by cycle (a second copy of the positions would be the peak of the build).
    std::vector<bool> placed(n, false);
    for (std::size_t start_i = 0; start_i < n; ++start_i) {
        if (placed[start_i])
            continue;
        const Vec3 first = cloud.positions[start_i];
        const std::array<std::uint8_t, 4> first_color = cloud.has_colors() ? cloud.colors[start_i] : std::array<std::uint8_t, 4>{};
        std::size_t i = start_i;
        for (;;) {
            placed[i] = true;
            const std::size_t from = order[i];
            if (from == start_i) {
                cloud.positions[i] = first;
                if (cloud.has_colors())
                    cloud.colors[i] = first_color;
                break;
            }
            cloud.positions[i] = cloud.positions[from];
            if (cloud.has_colors())
                cloud.colors[i] = cloud.colors[from];
            i = from;
        }
    }
    h.input_index = std::move(order);
    h.cloud = std::move(cloud);

    // Exact statistics: leaves from their points, parents by merging (children come after parents).
    for (std::size_t k = h.nodes.size(); k-- > 0;) {
        Node& node = h.nodes[k];
        if (node.is_leaf()) {
            node.moments = compute_moments(h.cloud.positions.data() + node.begin, node.count());
        } else {
            node.moments = h.nodes[static_cast<std::size_t>(node.left)].moments;
            node.moments.merge(h.nodes[static_cast<std::size_t>(node.right)].moments);
        }
    }
    update_derived(h);
    for (std::size_t k = h.nodes.size(); k-- > 0;) {
        Node& node = h.nodes[k];
        if (node.is_leaf()) {
            node.box = bounding_box(h.cloud.positions.data() + node.begin, node.count());
        } else {
            const BoundingBox& l = h.nodes[static_cast<std::size_t>(node.left)].box;
            const BoundingBox& r = h.nodes[static_cast<std::size_t>(node.right)].box;
            node.box = {min(l.min, r.min), max(l.max, r.max)};
        }
    }
    for (Node& node : h.nodes) {
        double error = 0.0, max_plane = 0.0;
        const Vec3 c = node.moments.mean, normal = node.frame.vectors[0];
        for (std::uint32_t i = node.begin; i < node.end; ++i) {
            const Vec3 d = h.cloud.positions[i] - c;
            error += std::sqrt(dot(d, d));
            max_plane = std::max(max_plane, std::abs(dot(d, normal)));
        }
        node.internal_error = error;
        node.max_plane_distance = max_plane;
    }
    set_coverage_gaps(h);
    // A caller's partition has no smallest cluster size (build_hierarchy records its own): 1 lets the
    // hierarchy be saved (save_model refuses 0, QA round 59).
    h.info.min_cluster = 1;
    return h;
}

namespace {

Hierarchy build_once(PointCloud cloud, const BuildOptions& options)
{
    const auto start = std::chrono::steady_clock::now();
    validate(cloud, "build_hierarchy");
    if (cloud.size() > std::numeric_limits<std::uint32_t>::max() - 1)
        throw InvalidInput("build_hierarchy: more than 4294967294 points");
    if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance))
        throw InvalidInput("build_hierarchy: tolerance must be a finite number >= 0, got " + std::to_string(options.tolerance));
    if (!(options.tau >= 0) || !std::isfinite(options.tau))
        throw InvalidInput("build_hierarchy: tau must be a finite number >= 0, got " + std::to_string(options.tau));
    if (options.min_cluster == 0)
        throw InvalidInput("build_hierarchy: min_cluster must be at least 1");

    // Duplicates go before anything counts points (see BuildOptions::merge_duplicates); `kept` maps
    // the remaining points back to the input for input_index.
    const std::size_t input_size = cloud.size();
    std::vector<std::uint32_t> kept;
    if (options.merge_duplicates)
        kept = remove_duplicates(cloud);
    const double largest_side = tolerance_scale(cloud.positions);
    const double threshold = options.tau > 0 ? options.tau : options.tolerance * largest_side;
    std::vector<std::int32_t> parent_of;
    std::vector<std::uint32_t> leaf_of_point;
    {
        // The builder's per-cluster state is freed before the tree is assembled (peak memory).
        Builder builder(cloud.positions, options, threshold, largest_side);
        builder.run();
        parent_of = std::move(builder.parent_of);
        leaf_of_point = std::move(builder.leaf_of_point);
    }
#if defined(__GLIBC__)
    // The builder's many small vectors are freed but glibc keeps the pages; hand them back so the
    // assembly's large arrays do not stack on top of them (the build's peak memory).
    malloc_trim(0);
#endif
    Hierarchy h = assemble_hierarchy(std::move(cloud), parent_of, leaf_of_point);
    h.info.duplicates_merged = input_size - h.cloud.size();
    if (h.info.duplicates_merged > 0)
        for (std::uint32_t& i : h.input_index)
            i = kept[i];
    h.info.criterion = options.tau > 0 ? Criterion::Tau : Criterion::Tolerance;
    h.info.criterion_value = options.tau > 0 ? options.tau : options.tolerance;
    h.info.pca_limit = static_cast<std::uint32_t>(std::min<std::size_t>(options.pca_limit, std::numeric_limits<std::uint32_t>::max()));
    h.info.min_cluster = static_cast<std::uint32_t>(std::min<std::size_t>(options.min_cluster, std::numeric_limits<std::uint32_t>::max()));
    h.info.reclassify = options.reclassify;
    h.info.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return h;
}

} // namespace

Hierarchy build_hierarchy(PointCloud cloud, const BuildOptions& options)
{
    const auto start = std::chrono::steady_clock::now();
    using Denoise = BuildOptions::Denoise;
    // An enum cast from an integer (static_cast<Denoise>(42)) was taken for Auto.
    if (options.denoise != Denoise::Auto && options.denoise != Denoise::Off && options.denoise != Denoise::On)
        throw InvalidInput("build_hierarchy: BuildOptions::denoise " + std::to_string(static_cast<int>(options.denoise)) +
                           " is none of Auto, Off, On");
    // Far from their origin, doubles keep too few of the points' digits (QA round 51: a 2-unit sphere
    // at 1e12 built 54 finest tiles instead of 169, at 1e15 one tile), and the hierarchy is relative to
    // the origin anyway: such a cloud is refused, not built coarse. At a billion times their extent a
    // double's step is 2.2e-7 of it, a five-hundredth of the finest default tolerance. Non-finite points
    // are left to validate.
    {
        const BoundingBox box = bounding_box(cloud.positions);
        const double farthest = std::max({std::abs(box.min.x), std::abs(box.min.y), std::abs(box.min.z), std::abs(box.max.x),
                                          std::abs(box.max.y), std::abs(box.max.z)});
        const double extent = box.diagonal();
        if (std::isfinite(farthest) && std::isfinite(extent) && extent > 0.0 && farthest > 1e9 * extent) {
            char text[160];
            std::snprintf(text, sizeof text, "build_hierarchy: the points lie %.3g from their origin, %.3g times their extent", farthest,
                          farthest / extent);
            throw InvalidInput(std::string(text) + ": doubles keep too few of their digits there; call recenter(cloud) "
                               "(point_cloud.h) first, as the readers do");
        }
        // Nearer, the input keeps its digits but the build loses them: moments updated point by point
        // cancel (QA round 59: the bunny placed at (5e5, 5e6), 2e7 times its extent from its origin,
        // built 953 nodes instead of 5,819, its mesh 3.5 times as far from the points). The cloud is
        // recentred as the readers do; the hierarchy is relative to its origin anyway.
        if (std::isfinite(farthest) && std::isfinite(extent) && extent > 0.0 && farthest > kRecenterBeyond * extent)
            recenter(cloud);
    }
    // The points to denoise, without duplicates (a point repeated is its own nearest neighbours), and
    // where each came from in the input (empty: the same index).
    std::vector<std::uint32_t> to_input;
    std::size_t merged = 0;
    if (options.denoise == Denoise::On) {
        validate(cloud, "build_hierarchy");
        const std::size_t input_size = cloud.size();
        if (options.merge_duplicates)
            to_input = remove_duplicates(cloud);
        merged = input_size - cloud.size();
    } else {
        Hierarchy first = build_once(std::move(cloud), options);
        if (options.denoise == Denoise::Off || !sample_is_noisy(first))
            return first;
        // Noisy: again from the moved points, in the first tree's order. Its nodes are of no further
        // use: freed before the second build's peak.
        std::vector<Node>().swap(first.nodes);
        to_input = std::move(first.input_index);
        merged = first.info.duplicates_merged;
        cloud = std::move(first.cloud);
    }
    const std::vector<Vec3> raw = cloud.positions;
    DenoiseOptions denoising = options.denoising;
    if (options.progress)
        denoising.progress = [&](double fraction) { options.progress("denoising", fraction); };
    const bool moved = denoise_points(cloud.positions, denoising) > 0.0;
    BuildOptions again = options;
    again.merge_duplicates = false; // merged already
    if (options.progress)
        again.progress = [&](const char*, double fraction) { options.progress("building hierarchy of the denoised points", fraction); };
    Hierarchy h = build_once(std::move(cloud), again);
    h.raw_positions.resize(raw.size());
    for (std::size_t i = 0; i < h.input_index.size(); ++i) {
        h.raw_positions[i] = raw[h.input_index[i]];
        if (!to_input.empty())
            h.input_index[i] = to_input[h.input_index[i]];
    }
    h.info.duplicates_merged = merged;
    if (!moved) { // too few points to fit (DenoiseOptions::neighbours), or none off its neighbours' surface
        std::vector<Vec3>().swap(h.raw_positions);
        h.info.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return h;
    }
    h.info.denoised = true;
    h.denoise_moves.resize(h.cloud.size());
    for (std::size_t i = 0; i < h.cloud.size(); ++i)
        h.denoise_moves[i] = static_cast<float>(norm(h.cloud.positions[i] - h.raw_positions[i]));
    derive_noise_floor(h); // again, now that the residual noise is known
    h.info.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return h;
}

} // namespace mrt
