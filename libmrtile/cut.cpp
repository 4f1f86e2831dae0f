// Level-of-detail selection over the persistent hierarchy (paper §3: "hierarchical clustering ... a
// means for controlling the levels of detail"; §1: "control the level of detail locally"). All cuts
// are top-down walks over node statistics stored at build time, so their cost follows the size of the
// cut, not of the input.
#include "libmrtile/cut.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <tuple>

namespace mrt {
namespace {

void check_tolerance(double value, const char* name)
{
    if (!(value >= 0) || !std::isfinite(value))
        throw InvalidInput(std::string("cut: ") + name + " must be a finite number >= 0, got " + std::to_string(value));
}

double distance_to_box(const Vec3& p, const BoundingBox& b) { return std::sqrt(b.squared_distance_to(p)); }

// How wide across a line its points may spread, in their spacing along it (is_line).
constexpr double kLineWidthSpacings = 2.0;

// Whether a node's points lie along one line: across the line they spread under a thirtieth of their
// spread along it (eigenvalues 900 apart), they are 8 or more (the fewest a leaf holds by choice: one
// or two stray points are no line, and are split off as before), and across it they spread less than
// kLineWidthSpacings of their spacing along it. A thin tube (a pipe, a cable) is as long and thin, but
// its points go round it: a tube of radius r sampled at spacing s holds about 2πr/s points per s of
// its length where a line holds one, so its spread across is r/√2 against a spacing along of
// s²/(2πr): 4 times it at r = s, 111 times at r = 5s. Taken for lines, a bent pipe's arms stopped
// every tolerance cut at the node holding both, one flat fan over the space between them (QA round 48).
// And the points run along the line's length: a blob with a stray far off spreads along the stray as a
// line does, its spacing along inflated by the stray's distance (a 40,000-point torus with a stray 10⁶
// away: a spacing along of 0.43, over half the tube's spread across), the node holding the torus and
// two strays was taken to split into a line, and every tolerance cut stopped there, at one fan (QA
// round 60: 4 faces). Such a node is no line when both its points bunch (the length their spread along
// gives, that of an even spacing, is under kLineFill of its box's diagonal: 1.7·10⁴ against 10⁶) and
// they leave an empty stretch over kLineFill of it (Node::coverage_gap: 10⁶). Either alone is no
// sign: a scan line with a dwell clump bunches but has no gap (QA round 61: taken for no line, a 20:1
// terrain at tolerance 0 lost a piece), a line with a gap spreads as an even one does.
constexpr double kLineFill = 0.5;
bool is_line(const Node& n)
{
    if (n.count() < 8 || !(n.frame.values[1] <= n.frame.values[2] / 900.0))
        return false;
    const LineSpread spread = line_spread(n);
    const double length = spread.spacing_along * static_cast<double>(n.count()), diagonal = n.box.diagonal();
    const bool blob_and_stray = length < kLineFill * diagonal && n.coverage_gap > kLineFill * diagonal;
    return spread.across <= kLineWidthSpacings * spread.spacing_along && !blob_and_stray;
}

// The refinement rule of every cut by tolerance and region: the node's RMS plane distance is above
// `limit` and above the node's noise floor (below it, children fit the noise: hierarchy.h), or its
// tile reaches farther than `limit` over a hole or notch of the surface, farther than its points lie
// from its plane (Node::coverage_gap; holes are no noise, so no floor); and it does not split into a
// line (splits_into_lines: cut.h).
bool rougher_than(const Hierarchy& h, const Node& n, double limit)
{
    return (n.rms_plane_distance > std::max(limit, n.noise_floor) || (n.coverage_gap > limit && gap_dominates(n))) &&
           !splits_into_lines(h, n);
}

// What the budget cut refines by: the plane error λ_min, or, where the gap dominates, the node's
// coverage gap counted like a plane distance of the same size at every point, whichever is larger.
double budget_error(const Node& n)
{
    if (!gap_dominates(n))
        return n.frame.values[0];
    return std::max(n.frame.values[0], static_cast<double>(n.count()) * n.coverage_gap * n.coverage_gap);
}

} // namespace

double node_error(const Node& n) { return std::max(n.max_plane_distance, n.coverage_gap); }

bool splits_into_lines(const Hierarchy& h, const Node& n)
{
    if (n.is_leaf() || is_line(n))
        return false;
    return is_line(h.nodes[static_cast<std::size_t>(n.left)]) || is_line(h.nodes[static_cast<std::size_t>(n.right)]);
}

Cut cut_by_predicate(const Hierarchy& h, const RefinePredicate& refine)
{
    if (!refine)
        throw InvalidInput("cut_by_predicate: the predicate is empty; pass a function that says whether to refine a node");
    Cut cut;
    if (h.nodes.empty())
        return cut;
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
        const std::int32_t id = stack.back();
        stack.pop_back();
        const Node& node = h.nodes[static_cast<std::size_t>(id)];
        if (!node.is_leaf() && refine(h, id)) {
            stack.push_back(node.right); // left first: depth-first = point order
            stack.push_back(node.left);
        } else {
            cut.push_back(id);
        }
    }
    return cut;
}

Cut cut_by_tolerance(const Hierarchy& h, double tolerance)
{
    check_tolerance(tolerance, "tolerance");
    const double limit = tolerance * h.scale;
    return cut_by_predicate(h, [limit](const Hierarchy& hh, std::int32_t id) {
        return rougher_than(hh, hh.nodes[static_cast<std::size_t>(id)], limit);
    });
}

Cut cut_by_tau(const Hierarchy& h, double tau)
{
    check_tolerance(tau, "tau");
    return cut_by_predicate(h, [tau](const Hierarchy& hh, std::int32_t id) {
        return hh.nodes[static_cast<std::size_t>(id)].frame.values[0] > tau;
    });
}

Cut cut_by_budget(const Hierarchy& h, std::size_t tiles)
{
    if (tiles == 0)
        throw InvalidInput("cut: a tile budget must be at least 1");
    // No nodes (a default-constructed Hierarchy): no leaves, so the empty cut, as the other cuts give;
    // the root was read out of bounds before.
    if (h.nodes.empty())
        return {};
    // Max-heap of refinable nodes by plane error; leaves wait in the cut.
    using Entry = std::pair<double, std::int32_t>;
    auto less = [](const Entry& a, const Entry& b) { return std::tie(a.first, b.second) < std::tie(b.first, a.second); };
    std::priority_queue<Entry, std::vector<Entry>, decltype(less)> open(less);
    Cut done;
    auto push = [&](std::int32_t id) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        if (n.is_leaf())
            done.push_back(id);
        else
            open.push({budget_error(n), id});
    };
    push(0);
    while (!open.empty() && done.size() + open.size() < tiles) {
        const std::int32_t id = open.top().second;
        open.pop();
        push(h.nodes[static_cast<std::size_t>(id)].left);
        push(h.nodes[static_cast<std::size_t>(id)].right);
    }
    while (!open.empty()) {
        done.push_back(open.top().second);
        open.pop();
    }
    // Depth-first order = order of the point ranges.
    sort_in_point_order(h, done);
    return done;
}

bool intersects(const Node& node, const FocusRegion& region)
{
    if (region.shape == FocusRegion::Shape::Box)
        return node.box.meets(region.box);
    return distance_to_box(region.centre, node.box) <= region.radius;
}

void check_region(const FocusRegion& r)
{
    // A shape cast from an integer (static_cast<Shape>(42)) was met as a sphere, its radius unchecked.
    if (r.shape != FocusRegion::Shape::Sphere && r.shape != FocusRegion::Shape::Box)
        throw InvalidInput("cut: a focus region's shape " + std::to_string(static_cast<int>(r.shape)) +
                           " is neither Sphere nor Box");
    check_tolerance(r.tolerance, "region tolerance");
    if (r.shape == FocusRegion::Shape::Sphere && (!(r.radius >= 0) || !std::isfinite(r.radius) || !is_finite(r.centre)))
        throw InvalidInput("cut: a focus sphere needs a finite centre and a finite radius >= 0");
    if (r.shape == FocusRegion::Shape::Box &&
        (!is_finite(r.box.min) || !is_finite(r.box.max) || !(r.box.min.x <= r.box.max.x) ||
         !(r.box.min.y <= r.box.max.y) || !(r.box.min.z <= r.box.max.z)))
        throw InvalidInput("cut: a focus box needs finite corners with min <= max on every axis");
}

void check_node_ids(const Hierarchy& h, const Cut& cut)
{
    for (std::int32_t id : cut)
        if (id < 0 || static_cast<std::size_t>(id) >= h.nodes.size())
            throw InvalidInput("cut: node id " + std::to_string(id) + " is not in the hierarchy");
}

namespace {

bool before_in_points(const Hierarchy& h, std::int32_t a, std::int32_t b)
{
    return h.nodes[static_cast<std::size_t>(a)].begin < h.nodes[static_cast<std::size_t>(b)].begin;
}

} // namespace

void sort_in_point_order(const Hierarchy& h, Cut& cut)
{
    std::sort(cut.begin(), cut.end(), [&](std::int32_t a, std::int32_t b) { return before_in_points(h, a, b); });
}

bool in_point_order(const Hierarchy& h, const Cut& cut)
{
    return std::is_sorted(cut.begin(), cut.end(), [&](std::int32_t a, std::int32_t b) { return before_in_points(h, a, b); });
}

std::string cut_problem(const Hierarchy& h, const Cut& cut)
{
    for (std::int32_t id : cut)
        if (id < 0 || static_cast<std::size_t>(id) >= h.nodes.size())
            return "node id " + std::to_string(id) + " of the cut is not in the hierarchy";
    // Nodes own contiguous point ranges and nest as the tree does: in range order (a node before those
    // inside it), a frontier's ranges follow one another from the first point to the last.
    Cut order = cut;
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
        const Node& na = h.nodes[static_cast<std::size_t>(a)];
        const Node& nb = h.nodes[static_cast<std::size_t>(b)];
        return std::make_tuple(na.begin, nb.end, a) < std::make_tuple(nb.begin, na.end, b);
    });
    const auto points = [](std::uint32_t begin, std::uint32_t end) {
        return "points " + std::to_string(begin) + " to " + std::to_string(end - 1);
    };
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
        const Node& n = h.nodes[static_cast<std::size_t>(order[i])];
        if (i > 0 && order[i] == order[i - 1])
            return "node " + std::to_string(order[i]) + " is listed twice in the cut";
        if (n.begin < next)
            return "node " + std::to_string(order[i]) + " of the cut lies inside node " + std::to_string(order[i - 1]) +
                   " of it (a cut holds each point once)";
        if (n.begin > next)
            return points(next, n.begin) + " are in no node of the cut (a subtree is missing)";
        next = n.end;
    }
    if (next < h.cloud.size())
        return points(next, static_cast<std::uint32_t>(h.cloud.size())) + " are in no node of the cut (a subtree is missing)";
    return {};
}

void check_cut(const Hierarchy& h, const Cut& cut, const std::string& what)
{
    if (const std::string problem = cut_problem(h, cut); !problem.empty())
        throw InvalidInput(what + ": " + problem);
}

Cut cut_by_regions(const Hierarchy& h, double base_tolerance, const std::vector<FocusRegion>& regions)
{
    check_tolerance(base_tolerance, "base tolerance");
    for (const FocusRegion& r : regions)
        check_region(r);
    const double side = h.scale;
    return cut_by_predicate(h, [&](const Hierarchy& hh, std::int32_t id) {
        const Node& n = hh.nodes[static_cast<std::size_t>(id)];
        return rougher_than(hh, n, region_tolerance(n, base_tolerance, regions) * side);
    });
}

double region_tolerance(const Node& n, double base_tolerance, const std::vector<FocusRegion>& regions)
{
    double tolerance = base_tolerance;
    for (const FocusRegion& r : regions)
        if (intersects(n, r))
            tolerance = std::min(tolerance, r.tolerance);
    return tolerance;
}

namespace {

bool box_inside(const BoundingBox& b, const FocusRegion& r)
{
    if (r.shape == FocusRegion::Shape::Box)
        return r.box.min.x <= b.min.x && r.box.min.y <= b.min.y && r.box.min.z <= b.min.z &&
               b.max.x <= r.box.max.x && b.max.y <= r.box.max.y && b.max.z <= r.box.max.z;
    // The farthest corner of the box from the centre lies within the radius.
    const Vec3 far{std::max(std::abs(b.min.x - r.centre.x), std::abs(b.max.x - r.centre.x)),
                   std::max(std::abs(b.min.y - r.centre.y), std::abs(b.max.y - r.centre.y)),
                   std::max(std::abs(b.min.z - r.centre.z), std::abs(b.max.z - r.centre.z))};
    return norm(far) <= r.radius;
}

} // namespace

Cut refine_cut(const Hierarchy& h, const Cut& cut, double base_tolerance, const std::vector<FocusRegion>& regions)
{
    check_tolerance(base_tolerance, "base tolerance");
    for (const FocusRegion& r : regions)
        check_region(r);
    // A cut that is no frontier was refined as given: a node listed twice came out twice, a node
    // inside another was kept beside it, and the result was no cut either.
    check_cut(h, cut, "refine_cut");
    const double side = h.scale;
    Cut out;
    std::vector<std::int32_t> stack;
    for (std::int32_t id : cut) {
        bool meets = false;
        for (const FocusRegion& r : regions)
            meets = meets || intersects(h.nodes[static_cast<std::size_t>(id)], r);
        if (!meets) {
            out.push_back(id);
            continue;
        }
        stack.assign(1, id);
        while (!stack.empty()) {
            const std::int32_t k = stack.back();
            stack.pop_back();
            const Node& n = h.nodes[static_cast<std::size_t>(k)];
            if (!n.is_leaf() && rougher_than(h, n, region_tolerance(n, base_tolerance, regions) * side)) {
                stack.push_back(n.right);
                stack.push_back(n.left);
            } else {
                out.push_back(k);
            }
        }
    }
    // In point order, as every cut is returned (QA round 59: a caller's cut in another order came back in it).
    sort_in_point_order(h, out);
    return out;
}

Cut coarsen_cut(const Hierarchy& h, const Cut& cut, const FocusRegion& region, double tolerance)
{
    check_tolerance(tolerance, "tolerance");
    check_region(region);
    check_cut(h, cut, "coarsen_cut");
    const double limit = tolerance * h.scale;
    // For each cut node, its highest ancestor (or itself) inside the region and flat enough; a chain
    // qualifies only as long as every node on it does (a parent is never flatter-tested past a failure).
    std::vector<std::int32_t> replacement(cut.size());
    for (std::size_t i = 0; i < cut.size(); ++i) {
        std::int32_t best = cut[i];
        for (std::int32_t k = cut[i]; k >= 0; k = h.nodes[static_cast<std::size_t>(k)].parent) {
            const Node& n = h.nodes[static_cast<std::size_t>(k)];
            if (!box_inside(n.box, region) || rougher_than(h, n, limit))
                break;
            best = k;
        }
        replacement[i] = best;
    }
    // A replacement absorbs every cut node in its range (the cut is a frontier). Keep the outermost
    // replacements: sorted by range start (longer first), drop those inside the last kept one.
    std::sort(replacement.begin(), replacement.end(), [&](std::int32_t a, std::int32_t b) {
        const Node& na = h.nodes[static_cast<std::size_t>(a)];
        const Node& nb = h.nodes[static_cast<std::size_t>(b)];
        return na.begin != nb.begin ? na.begin < nb.begin : na.end > nb.end;
    });
    Cut out;
    for (std::int32_t r : replacement) {
        const Node& node = h.nodes[static_cast<std::size_t>(r)];
        if (!out.empty() && node.end <= h.nodes[static_cast<std::size_t>(out.back())].end)
            continue;
        out.push_back(r);
    }
    return out;
}

namespace {

double screen_space_error_of(const Node& node, const Camera& camera)
{
    const double distance = distance_to_box(camera.position, node.box);
    if (distance <= 0)
        return std::numeric_limits<double>::infinity();
    const double half_fov = radians(0.5 * camera.fov_y_degrees);
    return node_error(node) * camera.viewport_height / (distance * 2.0 * std::tan(half_fov));
}

bool in_view_of(const Node& node, const Camera& camera)
{
    // The direction may have any length (Camera::direction): one whose norm would overflow (1e300 made
    // every node out of view) or underflow to 0 (1e-300 looked all around) is scaled first.
    const Vec3 direction = with_usable_norm(camera.direction);
    const double length = norm(direction);
    if (!(length > 0))
        return true;
    const Vec3 centre = (node.box.min + node.box.max) * 0.5;
    const double radius = 0.5 * norm(node.box.max - node.box.min);
    const Vec3 to = centre - camera.position;
    const double far = norm(to);
    if (far <= radius)
        return true;
    // The sphere is seen under asin(radius / far) around its centre's direction; it misses the cone
    // when the angle from the view axis exceeds the cone's half-angle by more than that.
    const double half_fov = radians(0.5 * camera.fov_y_degrees);
    const double half_cone = std::atan(std::tan(half_fov) * std::sqrt(1.0 + camera.aspect * camera.aspect));
    const double off_axis = std::acos(std::clamp(dot(to, direction) / (far * length), -1.0, 1.0));
    return off_axis - std::asin(radius / far) <= half_cone;
}

bool asks_finer(const Node& node, const Camera& camera)
{
    const double error = screen_space_error_of(node, camera);
    return error > camera.max_pixel_error && (error > camera.max_pixel_error * camera.out_of_view_factor || in_view_of(node, camera));
}

} // namespace

void check_camera(const Camera& camera)
{
    // Finite too: an infinite viewport height refined every node to the leaves, an infinite pixel error
    // kept the root alone (QA round 51). The per-node functions check too (a NaN field of view made
    // every error NaN, so no node was ever refined and nothing said why: QA round 51).
    if (!(camera.fov_y_degrees > 0 && camera.fov_y_degrees < 180) || !(camera.viewport_height > 0) ||
        !std::isfinite(camera.viewport_height) || !(camera.max_pixel_error > 0) || !std::isfinite(camera.max_pixel_error) ||
        !is_finite(camera.position) || !is_finite(camera.direction) || !(camera.aspect > 0) || !std::isfinite(camera.aspect) ||
        !(camera.out_of_view_factor >= 1))
        throw InvalidInput("camera: needs 0 < fov < 180 degrees, a positive, finite viewport height, pixel error and aspect, "
                           "an out-of-view factor of at least 1, and a finite position and direction");
}

double screen_space_error(const Node& node, const Camera& camera)
{
    check_camera(camera);
    return screen_space_error_of(node, camera);
}

bool in_view(const Node& node, const Camera& camera)
{
    check_camera(camera);
    return in_view_of(node, camera);
}

Cut cut_for_camera(const Hierarchy& h, const Camera& camera)
{
    check_camera(camera);
    return cut_by_predicate(h, [&](const Hierarchy& hh, std::int32_t id) {
        const Node& n = hh.nodes[static_cast<std::size_t>(id)];
        return asks_finer(n, camera) && rougher_than(hh, n, 0.0);
    });
}

bool camera_asks_finer(const Node& node, const Camera& camera)
{
    check_camera(camera);
    return asks_finer(node, camera);
}

double cut_plane_error(const Hierarchy& h, const Cut& cut)
{
    // A frontier, not any nodes: a node and its child both counted their points twice (QA round 51).
    check_cut(h, cut, "cut_plane_error");
    double sum = 0.0;
    for (std::int32_t id : cut)
        sum += h.nodes[static_cast<std::size_t>(id)].frame.values[0];
    return sum;
}

bool is_partition(const Hierarchy& h, const Cut& cut) { return cut_problem(h, cut).empty(); }

} // namespace mrt
