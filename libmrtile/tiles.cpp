// Tile generation, paper §4.2: each cut cluster becomes a nearly planar polygon (its pseudo tile)
// whose convex hull in the PCA plane is the tile outline. The hull is Andrew's monotone chain in the
// (axis_u, axis_v) coordinates of the plane, so it is exact for the projected points and
// counter-clockwise seen from the normal; collinear hull points are dropped because they would give
// zero-area fan triangles (T1) later.
#include "libmrtile/tiles.h"

#include "libmrtile/errors.h"
#include "libmrtile/gabriel_graph.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace mrt {
namespace {

struct Projected
{
    double x, y;
    std::uint32_t index;
};

double turn(const Projected& o, const Projected& a, const Projected& b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Counter-clockwise hull of the points without collinear or repeated points. For fewer than three
// non-collinear points it returns the distinct extreme points (0, 1 or 2 of them).
std::vector<std::uint32_t> convex_hull(std::vector<Projected>& pts, double tolerance)
{
    // Ties broken by index: the hull does not depend on the order the sort happens to keep.
    std::sort(pts.begin(), pts.end(), [](const Projected& a, const Projected& b) {
        if (a.x != b.x)
            return a.x < b.x;
        if (a.y != b.y)
            return a.y < b.y;
        return a.index < b.index;
    });
    const std::size_t n = pts.size();
    if (n == 0)
        return {};
    double ymin = pts.front().y, ymax = pts.front().y;
    for (const Projected& p : pts) {
        ymin = std::min(ymin, p.y);
        ymax = std::max(ymax, p.y);
    }
    const double extent = std::max(pts.back().x - pts.front().x, ymax - ymin);
    const double eps = tolerance * extent * extent;

    std::vector<Projected> hull(2 * n);
    std::size_t k = 0;
    // Invariant: hull[0..k) is a strictly convex chain (every turn > eps).
    for (std::size_t i = 0; i < n; ++i) {
        while (k >= 2 && turn(hull[k - 2], hull[k - 1], pts[i]) <= eps)
            --k;
        hull[k++] = pts[i];
    }
    for (std::size_t i = n - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && turn(hull[k - 2], hull[k - 1], pts[i]) <= eps)
            --k;
        hull[k++] = pts[i];
    }
    if (k > 1)
        --k; // the last point repeats the first
    std::vector<std::uint32_t> out;
    if (k >= 3) {
        for (std::size_t i = 0; i < k; ++i)
            out.push_back(hull[i].index);
        return out;
    }
    // Degenerate: collinear or coincident points. Keep the distinct extremes of the sorted order.
    out.push_back(pts.front().index);
    if (pts.back().x != pts.front().x || pts.back().y != pts.front().y)
        out.push_back(pts.back().index);
    return out;
}

} // namespace

Tile make_tile(const Hierarchy& h, std::int32_t node, const TileOptions& options, const std::vector<Vec3>& rivals)
{
    if (node < 0 || static_cast<std::size_t>(node) >= h.nodes.size())
        throw InvalidInput("cut: node id " + std::to_string(node) + " is not in the hierarchy (" +
                           std::to_string(h.nodes.size()) + " nodes)");
    const Node& n = h.nodes[static_cast<std::size_t>(node)];
    if (n.end <= n.begin || n.end > h.cloud.positions.size())
        throw InvalidInput("cut: node " + std::to_string(node) + " has an empty or out-of-range point range");
    Tile t;
    t.node = node;
    t.centre = n.moments.mean;
    t.normal = n.frame.vectors[0];
    t.axis_u = n.frame.vectors[2];
    // Right-handed plane basis so that counter-clockwise in (u, v) is counter-clockwise seen from normal.
    t.axis_v = cross(t.normal, t.axis_u);
    t.points = n.count();

    std::vector<Projected> pts;
    pts.reserve(n.count());
    auto in_own_cell = [&](const Vec3& p) {
        const double own = squared_distance(p, t.centre);
        for (const Vec3& r : rivals)
            if (squared_distance(p, r) < own)
                return false;
        return true;
    };
    for (std::uint32_t i = n.begin; i < n.end; ++i) {
        if (!rivals.empty() && !in_own_cell(h.cloud.positions[i]))
            continue;
        const Vec3 d = h.cloud.positions[i] - t.centre;
        pts.push_back({dot(d, t.axis_u), dot(d, t.axis_v), i});
    }
    if (pts.empty()) // every point nearer to a rival (a very non-convex node): use them all
        for (std::uint32_t i = n.begin; i < n.end; ++i) {
            const Vec3 d = h.cloud.positions[i] - t.centre;
            pts.push_back({dot(d, t.axis_u), dot(d, t.axis_v), i});
        }
    t.boundary = convex_hull(pts, options.collinear_tolerance);
    if (t.has_fan()) {
        double twice = 0.0;
        auto uv = [&](std::uint32_t i) {
            const Vec3 d = h.cloud.positions[i] - t.centre;
            return std::pair<double, double>{dot(d, t.axis_u), dot(d, t.axis_v)};
        };
        for (std::size_t i = 0; i < t.boundary.size(); ++i) {
            const auto a = uv(t.boundary[i]);
            const auto b = uv(t.boundary[(i + 1) % t.boundary.size()]);
            twice += a.first * b.second - a.second * b.first;
        }
        t.area = 0.5 * twice;
    }
    return t;
}

std::vector<Tile> make_tiles(const Hierarchy& h, const std::vector<std::int32_t>& cut, const TileOptions& options)
{
    if (!(options.collinear_tolerance >= 0.0))
        throw InvalidInput("TileOptions::collinear_tolerance must be >= 0");
    for (std::int32_t node : cut)
        if (node < 0 || static_cast<std::size_t>(node) >= h.nodes.size())
            throw InvalidInput("cut: node id " + std::to_string(node) + " is not in the hierarchy (" +
                               std::to_string(h.nodes.size()) + " nodes)");
    std::vector<std::vector<std::uint32_t>> neighbours;
    std::vector<Vec3> centres;
    if (options.voronoi_trim && cut.size() > 1) {
        for (std::int32_t node : cut)
            centres.push_back(h.nodes[static_cast<std::size_t>(node)].moments.mean);
        neighbours = delaunay_graph(centres);
    }
    std::vector<Tile> tiles;
    tiles.reserve(cut.size());
    std::vector<Vec3> rivals;
    for (std::size_t k = 0; k < cut.size(); ++k) {
        rivals.clear();
        if (!neighbours.empty())
            for (std::uint32_t j : neighbours[k])
                if (centres[j] != centres[k])
                    rivals.push_back(centres[j]);
        tiles.push_back(make_tile(h, cut[k], options, rivals));
    }
    return tiles;
}

} // namespace mrt
