// Neighbourhoods for the point-wise stages that run before the hierarchy exists (beyond the paper:
// outliers.cpp and denoise.cpp). The hierarchy's own neighbourhoods (leaves, Gabriel graph) are not
// there yet, and both stages need each point's k nearest neighbours exactly, for every point of the
// cloud. That last part is why this is our own kd-tree and not a general one: every query point is in
// the tree, so a query starts at the point's own leaf and climbs, and its first few dozen candidates
// are its true neighbourhood; queried in the tree's order with the bound the query before gives
// (query's `within`), a search visits few nodes. CGAL's kd-tree, used here before, searched from
// the root (its sorted results were a third of a noisy 2M-point build; nanoflann's was slower
// still): 1M queries of 47 neighbours 3.6 -> 3.0 s, and the noisy 2M-point build's peak memory
// 400 -> 320 MB (CGAL's tree held a copy of every point with its index and a pointer to it).
#include "libmrtile/neighbours.h"

#include "libmrtile/parallel.h"
#include "libmrtile/point_cloud.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace mrt {
namespace {

constexpr std::uint32_t kLeafSize = 16; // points per leaf at most

// Squared distance from p, inside the box, to the box's outside: a ball around p of a smaller radius
// holds no point outside the box.
double squared_depth_in_box(const Vec3& p, const BoundingBox& b)
{
    const double d = std::min({p.x - b.min.x, b.max.x - p.x, p.y - b.min.y, b.max.y - p.y, p.z - b.min.z, b.max.z - p.z});
    return d > 0.0 ? d * d : 0.0;
}

} // namespace

struct NearestNeighbours::Tree
{
    struct Node
    {
        BoundingBox box;
        std::uint32_t begin = 0, end = 0; // into order / points
        std::int32_t parent = -1, left = -1, right = -1;
    };
    std::vector<Node> nodes;          // nodes[0] = root
    std::vector<std::uint32_t> order; // tree position -> input index
    std::vector<Vec3> points;         // tree position -> position (leaves scan contiguous memory)
    std::vector<std::uint32_t> leaf;  // input index -> its leaf

    // Candidates (squared distance, input index) no farther than `bound`, an upper bound on the k-th
    // nearest distance once k candidates were seen. Collected, then selected: a heap kept at k
    // (tried first) spent half the query reordering itself.
    struct Best
    {
        std::size_t k;
        std::vector<std::pair<double, std::uint32_t>> found;
        double bound = std::numeric_limits<double>::infinity();
        // Keeps the k best by (distance, index) and makes the k-th distance the bound.
        void tighten()
        {
            if (found.size() < k)
                return;
            std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(k - 1), found.end());
            found.resize(k);
            bound = found[k - 1].first;
        }
    };

    // Offers the leaf's points. Written without a branch per point: whether a point is within the
    // bound is a coin toss near the bound's edge, and mispredicted branches were most of a query.
    void scan(std::int32_t id, const Vec3& q, std::uint32_t self, Best& best) const
    {
        const Node& n = nodes[static_cast<std::size_t>(id)];
        std::size_t count = best.found.size();
        best.found.resize(count + (n.end - n.begin));
        std::pair<double, std::uint32_t>* out = best.found.data();
        for (std::uint32_t t = n.begin; t < n.end; ++t) {
            const Vec3 d = points[t] - q;
            const double d2 = d.x * d.x + d.y * d.y + d.z * d.z;
            out[count] = {d2, order[t]};
            count += static_cast<std::size_t>((d2 <= best.bound) & (order[t] != self));
        }
        best.found.resize(count);
    }

    // Every point of the subtree that can still make the k best, nearer child first. A subtree no
    // nearer than the bound is skipped: its points could only tie with the k-th. (Searching those
    // too, to break ties by index, made a point repeated 50,000 times quadratic: every copy's box
    // is at distance 0 from every copy.)
    void search(std::int32_t id, const Vec3& q, std::uint32_t self, Best& best) const
    {
        const Node& n = nodes[static_cast<std::size_t>(id)];
        if (n.box.squared_distance_to(q) >= best.bound)
            return;
        if (n.left < 0) {
            scan(id, q, self, best);
            return;
        }
        const double dl = nodes[static_cast<std::size_t>(n.left)].box.squared_distance_to(q);
        const double dr = nodes[static_cast<std::size_t>(n.right)].box.squared_distance_to(q);
        const bool left_first = dl <= dr;
        search(left_first ? n.left : n.right, q, self, best);
        search(left_first ? n.right : n.left, q, self, best);
    }

    // Splits nodes[id] at the median of its box's longest side until leaves hold kLeafSize points.
    void build(std::int32_t id, const std::vector<Vec3>& input)
    {
        std::vector<std::int32_t> stack{id};
        while (!stack.empty()) {
            const std::int32_t at = stack.back();
            stack.pop_back();
            Node n = nodes[static_cast<std::size_t>(at)];
            n.box = bounding_box_of(n.begin, n.end, input);
            nodes[static_cast<std::size_t>(at)].box = n.box;
            if (n.end - n.begin <= kLeafSize)
                continue;
            const Vec3 size = n.box.size();
            const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
            const std::uint32_t middle = n.begin + (n.end - n.begin) / 2;
            // By coordinate, then index: a deterministic split whatever the input order.
            const auto key = [&](std::uint32_t i) { return std::make_pair(axis == 0 ? input[i].x : axis == 1 ? input[i].y : input[i].z, i); };
            std::nth_element(order.begin() + n.begin, order.begin() + middle, order.begin() + n.end,
                             [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
            const auto left = static_cast<std::int32_t>(nodes.size());
            nodes.push_back({BoundingBox{}, n.begin, middle, at, -1, -1});
            nodes.push_back({BoundingBox{}, middle, n.end, at, -1, -1});
            nodes[static_cast<std::size_t>(at)].left = left;
            nodes[static_cast<std::size_t>(at)].right = left + 1;
            stack.push_back(left + 1);
            stack.push_back(left);
        }
    }

    BoundingBox bounding_box_of(std::uint32_t begin, std::uint32_t end, const std::vector<Vec3>& input) const
    {
        BoundingBox b{input[order[begin]], input[order[begin]]};
        for (std::uint32_t t = begin + 1; t < end; ++t) {
            const Vec3& p = input[order[t]];
            b.min = min(b.min, p);
            b.max = max(b.max, p);
        }
        return b;
    }
};

NearestNeighbours::NearestNeighbours(const std::vector<Vec3>& positions) : positions_(&positions), tree_(std::make_unique<Tree>())
{
    Tree& t = *tree_;
    const auto n = static_cast<std::uint32_t>(positions.size());
    t.order.resize(n);
    for (std::uint32_t i = 0; i < n; ++i)
        t.order[i] = i;
    if (n == 0)
        return;
    t.nodes.reserve(2 * (n / kLeafSize + 1));
    t.nodes.push_back({BoundingBox{}, 0, n, -1, -1, -1});
    t.build(0, positions);
    t.points.resize(n);
    for (std::uint32_t k = 0; k < n; ++k)
        t.points[k] = positions[t.order[k]];
    t.leaf.resize(n);
    for (std::size_t id = 0; id < t.nodes.size(); ++id)
        if (t.nodes[id].left < 0)
            for (std::uint32_t k = t.nodes[id].begin; k < t.nodes[id].end; ++k)
                t.leaf[t.order[k]] = static_cast<std::uint32_t>(id);
}

NearestNeighbours::~NearestNeighbours() = default;

const std::vector<std::uint32_t>& NearestNeighbours::order() const { return tree_->order; }

void NearestNeighbours::query(std::uint32_t i, std::size_t k, std::vector<std::uint32_t>& index, std::vector<double>& distance,
                              double within) const
{
    const Tree& t = *tree_;
    assert(i < t.leaf.size());
    index.clear();
    distance.clear();
    if (k == 0)
        return;
    Tree::Best best{k, {}};
    best.found.reserve(4 * k);
    if (within >= 0.0 && std::isfinite(within))
        best.bound = within * within;
    const std::int32_t start = static_cast<std::int32_t>(t.leaf[i]);
    const Vec3 q = (*positions_)[i];
    t.scan(start, q, i, best);
    // Climb: each ancestor's other child may hold nearer points, until the ball of the bound lies
    // inside the subtree searched so far.
    for (std::int32_t below = start; below != 0;) {
        const std::int32_t up = t.nodes[static_cast<std::size_t>(below)].parent;
        // Without a radius, the first bound once the climb has seen twice k points (from fewer, it is
        // loose and lets in most of what follows); after that only when the candidates pile up.
        if (std::isinf(best.bound) ? best.found.size() >= 2 * k : best.found.size() > 8 * k)
            best.tighten();
        if (best.bound < squared_depth_in_box(q, t.nodes[static_cast<std::size_t>(below)].box))
            break;
        const Tree::Node& parent = t.nodes[static_cast<std::size_t>(up)];
        t.search(parent.left == below ? parent.right : parent.left, q, i, best);
        below = up;
    }
    if (best.found.size() < k && best.found.size() + 1 < t.order.size() && std::isfinite(within) && within >= 0.0) {
        query(i, k, index, distance); // the radius held fewer than k points: without it
        return;
    }
    best.tighten();
    std::sort(best.found.begin(), best.found.end()); // nearest first (at most k)
    for (const auto& [d2, j] : best.found) {
        index.push_back(j);
        distance.push_back(std::sqrt(d2));
    }
}

void NearestNeighbours::for_each_point(std::size_t k, std::size_t threads, const Visit& visit) const
{
    const std::vector<std::uint32_t>& order = tree_->order;
    const std::vector<Vec3>& p = *positions_;
    run_parallel_ranges(order.size(), 4096, threads, [&](std::size_t begin, std::size_t end) {
        std::vector<std::uint32_t> index;
        std::vector<double> distance;
        for (std::size_t at = begin; at < end; ++at) {
            const std::uint32_t i = order[at];
            double within = std::numeric_limits<double>::infinity();
            if (at > begin && !distance.empty()) {
                const Vec3 step = p[i] - p[order[at - 1]];
                within = distance.back() + std::sqrt(dot(step, step));
            }
            query(i, k, index, distance, within);
            visit(i, index, distance);
        }
    });
}

} // namespace mrt
