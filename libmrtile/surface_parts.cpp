// The shared ground of the gap triangulation and manifold assembly (paper §4.3; steps numbered as in
// surface.cpp): the surface's vertices and tile loops with the ε-splitting (step 1), the height-field test
// (step 2a), the consistent tile orientation (step 2c), and the walks along the boundary loops of the
// surface under construction. Apart from surface.cpp because the front (surface_front.cpp) and the hole
// filling (surface_holes.cpp) walk the same loops.
#include "libmrtile/surface_parts.h"

#include "libmrtile/pca.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <queue>
#include <utility>
#include <vector>

namespace mrt::surface_detail {

// ---------------------------------------------------------------------------------------------------
// Step 1: vertices, loops, ε-splitting.

Layout make_layout(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options)
{
    Layout out;
    out.tiles.resize(tiles.size());
    double total_length = 0.0;
    std::size_t total_edges = 0;
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        const Tile& tile = tiles[t];
        TileLoop& tl = out.tiles[t];
        tl.share = static_cast<double>(h.nodes[static_cast<std::size_t>(tile.node)].count()) /
                   static_cast<double>(h.cloud.positions.size());
        const auto ti = static_cast<std::int32_t>(t);
        if (!tile.has_fan()) {
            for (std::uint32_t p : tile.boundary)
                out.vertices.push_back({h.cloud.positions[p], ti, kNone});
            continue;
        }
        tl.centre = static_cast<std::uint32_t>(out.vertices.size());
        out.vertices.push_back({tile.apex, ti, kNone}); // on the surface, not the patch's mean
        double perimeter = 0.0;
        const std::size_t n = tile.boundary.size();
        for (std::size_t i = 0; i < n; ++i)
            perimeter += distance(h.cloud.positions[tile.boundary[i]], h.cloud.positions[tile.boundary[(i + 1) % n]]);
        double eps = std::numeric_limits<double>::infinity();
        if (options.split_length > 0.0)
            eps = options.split_length;
        else if (options.split_length == 0.0)
            eps = options.split_factor * std::sqrt(tile.area / std::max<double>(1.0, tile.points));
        // Never more than 1024 points per tile, whatever ε says (a needle-thin tile has a tiny spacing).
        eps = std::max(eps, perimeter / 1024.0);
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 a = h.cloud.positions[tile.boundary[i]];
            const Vec3 b = h.cloud.positions[tile.boundary[(i + 1) % n]];
            tl.loop.push_back(static_cast<std::uint32_t>(out.vertices.size()));
            out.vertices.push_back({a, ti, static_cast<std::uint32_t>(tl.loop.size() - 1)});
            const double len = distance(a, b);
            const auto pieces = static_cast<std::size_t>(std::ceil(len / eps - 1e-9));
            for (std::size_t k = 1; k < pieces; ++k) {
                const double s = static_cast<double>(k) / static_cast<double>(pieces);
                tl.loop.push_back(static_cast<std::uint32_t>(out.vertices.size()));
                out.vertices.push_back({a + (b - a) * s, ti, static_cast<std::uint32_t>(tl.loop.size() - 1), true});
                ++out.split_points;
            }
        }
        tl.perimeter = perimeter;
        tl.spacing = tile.spacing();
        tl.node = tile.node;
        tl.normal = tile.normal;
        const std::uint32_t node_points = h.nodes[static_cast<std::size_t>(tile.node)].count();
        tl.full_spacing = node_points > tile.points && tile.points > 0
                              ? tl.spacing * std::sqrt(static_cast<double>(tile.points) / node_points)
                              : tl.spacing;
        tl.edge_length = perimeter / static_cast<double>(tl.loop.size());
        total_length += perimeter;
        total_edges += tl.loop.size();
    }
    out.mean_edge = total_edges ? total_length / static_cast<double>(total_edges) : 0.0;
    return out;
}

// ---------------------------------------------------------------------------------------------------
// Step 2a: height-field test.

namespace {

// The dominant normal axis: the principal eigenvector of sum(area * n nᵀ), which ignores normal signs.
Vec3 dominant_normal_axis(const std::vector<Tile>& tiles)
{
    Moments m;
    m.count = 1;
    for (const Tile& t : tiles) {
        if (!t.has_fan())
            continue;
        const double w = t.area;
        const Vec3& n = t.normal;
        m.m2[0] += w * n.x * n.x;
        m.m2[1] += w * n.x * n.y;
        m.m2[2] += w * n.x * n.z;
        m.m2[3] += w * n.y * n.y;
        m.m2[4] += w * n.y * n.z;
        m.m2[5] += w * n.z * n.z;
    }
    const Eigen3x3 e = eigen_decomposition(m);
    return e.vectors[2];
}

// Counter-clockwise or clockwise convex polygon: inside when all turns have the same strict sign, and
// (margin > 0) at least `margin` from every edge.
bool point_in_convex(const std::vector<std::array<double, 2>>& poly, double x, double y, double margin = 0.0)
{
    int sign = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % poly.size()];
        const double c = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
        const int s = c > 0 ? 1 : (c < 0 ? -1 : 0);
        if (s == 0)
            return false;
        if (sign == 0)
            sign = s;
        else if (s != sign)
            return false;
        if (margin > 0.0 && std::abs(c) < margin * std::hypot(b[0] - a[0], b[1] - a[1]))
            return false;
    }
    return true;
}

// Whether Auto takes the tiles for a graph over p.axis (see choose_projection): few enough points on
// steep tiles, and no tile centre inside another tile's outline (an airborne scan: a few, at roofs'
// edges). `airborne` allows the walls and overhangs of an airborne scan.
bool graph_over_axis(const Hierarchy& h, const std::vector<Tile>& tiles, const Projection& p, const std::vector<bool>& steep,
                     double steep_points, double fan_points, bool airborne)
{
    if (steep_points > (airborne ? kMaxSteepShare : 0.0) * fan_points || steep_points == fan_points)
        return false;
    // Overlap test: bucket projected tile centres in a grid, test each against the outlines whose
    // bounding boxes cover its cell. In an airborne scan a centre within two spacings of an outline's
    // edge is no overhang: at a wall the tiles on both sides reach the wall's line.
    struct Outline
    {
        std::vector<std::array<double, 2>> poly;
        double x0, y0, x1, y1;
        double margin;
    };
    std::vector<Outline> outlines;
    std::vector<std::array<double, 2>> centres;
    double mean_size = 0.0;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const Tile& t = tiles[k];
        if (!t.has_fan() || steep[k])
            continue;
        Outline o;
        o.x0 = o.y0 = std::numeric_limits<double>::infinity();
        o.x1 = o.y1 = -o.x0;
        o.margin = airborne ? 2.0 * t.spacing() : 0.0;
        for (std::uint32_t i : t.boundary) {
            const Vec3& q = h.cloud.positions[i];
            const double x = dot(q, p.u), y = dot(q, p.v);
            o.poly.push_back({x, y});
            o.x0 = std::min(o.x0, x);
            o.y0 = std::min(o.y0, y);
            o.x1 = std::max(o.x1, x);
            o.y1 = std::max(o.y1, y);
        }
        mean_size += std::max(o.x1 - o.x0, o.y1 - o.y0);
        outlines.push_back(std::move(o));
        centres.push_back({dot(t.centre, p.u), dot(t.centre, p.v)});
    }
    if (outlines.empty())
        return false;
    mean_size /= static_cast<double>(outlines.size());
    if (!(mean_size > 0.0))
        return true;
    const double cell = mean_size;
    auto cell_of = [&](double x, double y) {
        return std::pair<std::int64_t, std::int64_t>{static_cast<std::int64_t>(std::floor(x / cell)),
                                                     static_cast<std::int64_t>(std::floor(y / cell))};
    };
    std::vector<std::pair<std::pair<std::int64_t, std::int64_t>, std::uint32_t>> grid;
    for (std::uint32_t i = 0; i < centres.size(); ++i)
        grid.push_back({cell_of(centres[i][0], centres[i][1]), i});
    std::sort(grid.begin(), grid.end());
    const auto allowed = static_cast<std::size_t>(airborne ? kMaxOverhangShare * static_cast<double>(outlines.size()) : 0.0);
    std::size_t overhangs = 0;
    for (std::uint32_t k = 0; k < outlines.size(); ++k) {
        const Outline& o = outlines[k];
        const auto c0 = cell_of(o.x0, o.y0), c1 = cell_of(o.x1, o.y1);
        for (std::int64_t cx = c0.first; cx <= c1.first; ++cx) {
            auto it = std::lower_bound(grid.begin(), grid.end(), std::make_pair(std::make_pair(cx, c0.second), 0u));
            for (; it != grid.end() && it->first.first == cx && it->first.second <= c1.second; ++it)
                if (it->second != k && point_in_convex(o.poly, centres[it->second][0], centres[it->second][1], o.margin) &&
                    ++overhangs > allowed)
                    return false;
        }
    }
    return true;
}

} // namespace

Projection choose_projection(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options)
{
    Projection p;
    if (options.height_field == HeightField::Off)
        return p;
    p.axis = normalized(dominant_normal_axis(tiles));
    if (squared_norm(p.axis) == 0.0)
        p.axis = {0, 0, 1};
    // Face the axis to the positive side of its largest component (deterministic "up").
    int big = 0;
    for (int i = 1; i < 3; ++i)
        if (std::abs(p.axis[i]) > std::abs(p.axis[big]))
            big = i;
    if (p.axis[big] < 0)
        p.axis = -p.axis;
    // A scan's height field faces its scanner: "up" is the side the viewpoint is on.
    if (h.cloud.viewpoint) {
        double toward = 0.0;
        for (const Tile& t : tiles)
            toward += dot(p.axis, *h.cloud.viewpoint - t.centre) * static_cast<double>(t.points);
        if (toward < 0.0)
            p.axis = -p.axis;
    }
    p.u = perpendicular_axis(p.axis);
    p.v = cross(p.axis, p.u);
    // Steep tiles: the walls of a height field (a building's, sampled by a few points of an airborne
    // scan) or parts that are no height field at all. In a height field they get no fan, and the gap
    // triangulation bridges their neighbours across them (the paper's step discontinuities, Fig. 9c).
    // Auto takes them for walls only in a georeferenced cloud (a CRS) whose surface faces up (its axis
    // within 10 degrees of z) while they hold at most kMaxSteepShare of the points: the ground and
    // roofs of an airborne scan. A range scan is a graph over its view direction too, and its steep
    // tiles are surface seen at a grazing angle: bridged, its depth jumps became curtains (the bunny's
    // raw scans: 6-10% of the diagonal off).
    const double min_cos = std::cos(radians(options.max_tilt_degrees));
    std::vector<bool> steep(tiles.size(), false);
    double steep_points = 0.0, fan_points = 0.0;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const Tile& t = tiles[k];
        if (!t.has_fan())
            continue;
        const double count = static_cast<double>(h.nodes[static_cast<std::size_t>(t.node)].count());
        fan_points += count;
        if (std::abs(dot(t.normal, p.axis)) < min_cos) {
            steep[k] = true;
            steep_points += count;
        }
    }
    if (options.height_field == HeightField::On) {
        p.used = true;
        p.steep = std::move(steep);
        return p;
    }
    // An airborne scan is no single view: a cloud with a viewpoint (a terrestrial scanner on its tripod
    // in a georeferenced survey) saw its walls, which the airborne rule would bridge and leave out (QA
    // round 32's terrestrial scan with a CRS: 1,033 points of its box walls off the mesh, 9.6% of the
    // diagonal away).
    const bool up = std::abs(p.axis.z) >= std::cos(radians(10.0)) && !h.cloud.viewpoint;
    if (graph_over_axis(h, tiles, p, steep, steep_points, fan_points, !h.cloud.crs.empty() && up)) {
        p.used = true;
        p.steep = std::move(steep);
    } else {
        // Without a CRS, whether the points would pass as an airborne scan: the mesh says so, since
        // a height field is then one option away (QA round 32: a 1M-point town in 98 pieces, whole
        // with --height-field on).
        p.looks_airborne = h.cloud.crs.empty() && up && graph_over_axis(h, tiles, p, steep, steep_points, fan_points, true);
    }
    return p;
}

// ---------------------------------------------------------------------------------------------------
// Step 2c: consistent tile orientation.

namespace {

// How much the normals of neighbouring tiles a, b agree: n_a against n_b reflected across the plane
// bisecting the segment between the centres. On a surface that is symmetric about that plane the
// reflection maps one normal onto the other exactly, so the score is +1 for consistent and -1 for
// opposite signs whatever the angle between the tiles (a plain dot product is 0 across a 90-degree edge).
double agreement(const Tile& a, const Tile& b)
{
    const Vec3 d = normalized(b.centre - a.centre);
    const Vec3 reflected = b.normal - d * (2.0 * dot(b.normal, d));
    return dot(a.normal, reflected);
}

} // namespace

// +1/-1 per tile: orientations of the tile normals that agree across the surface neighbour graph,
// propagated along the most confident edges first (a maximum spanning tree on |agreement|, as in Hoppe
// et al.'s normal orientation), starting from the largest tile of each connected part. Tiles without
// neighbours keep +1.
std::vector<int> orient_tiles(const std::vector<Tile>& tiles)
{
    std::vector<int> orientation(tiles.size(), 0);
    std::vector<std::uint32_t> order(tiles.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return tiles[a].points > tiles[b].points; });
    struct Edge
    {
        double confidence;
        std::uint32_t from, to;
        bool operator<(const Edge& o) const
        {
            return confidence != o.confidence ? confidence < o.confidence : std::tie(from, to) > std::tie(o.from, o.to);
        }
    };
    std::priority_queue<Edge> queue;
    for (std::uint32_t seed : order) {
        if (orientation[seed] != 0)
            continue;
        orientation[seed] = 1;
        for (std::uint32_t n : tiles[seed].neighbours)
            queue.push({std::abs(agreement(tiles[seed], tiles[n])), seed, n});
        while (!queue.empty()) {
            const Edge e = queue.top();
            queue.pop();
            if (orientation[e.to] != 0)
                continue;
            orientation[e.to] = orientation[e.from] * (agreement(tiles[e.from], tiles[e.to]) >= 0.0 ? 1 : -1);
            for (std::uint32_t n : tiles[e.to].neighbours)
                if (orientation[n] == 0)
                    queue.push({std::abs(agreement(tiles[e.to], tiles[n])), e.to, n});
        }
    }
    return orientation;
}

// ---------------------------------------------------------------------------------------------------
// Step 3: the manifold surface under construction.

namespace {

// The fans (link arcs) of v in counter-clockwise order around its normal.
std::vector<std::pair<std::uint32_t, std::uint32_t>> ordered_fans(const Surface& s, const std::vector<Vec3>& positions, std::uint32_t v)
{
    auto fans = s.arcs(v);
    if (fans.size() < 2)
        return fans;
    Vec3 n;
    for (std::uint32_t f : s.faces_at(v)) {
        const Tri& t = s.faces()[f];
        n += triangle_cross(positions[t[0]], positions[t[1]], positions[t[2]]);
    }
    const AngleAround angle(positions[v], normalized(n));
    std::sort(fans.begin(), fans.end(), [&](const auto& a, const auto& b) {
        const double aa = angle(positions[a.first]), ab = angle(positions[b.first]);
        return aa != ab ? aa < ab : a.first < b.first;
    });
    return fans;
}

} // namespace

// The vertex after v on the boundary loop that arrives at v by the free half-edge u -> v. At a pinched
// vertex the loop continues into the fan gap it came from (fans ordered counter-clockwise around the
// vertex normal), so a loop never crosses itself: it leaves v along the free edge of the fan before
// u's (a fan (first, last) has the free half-edges first -> v and v -> last).
std::uint32_t next_boundary_vertex(const Surface& s, const std::vector<Vec3>& positions, std::uint32_t u, std::uint32_t v)
{
    // Most boundary vertices have one fan: its arc is the way on, no ordering needed.
    if (s.arc_count(v) == 1)
        if (const std::uint32_t w = s.arc_end(v, u); w != kNone)
            return w;
    const auto fans = ordered_fans(s, positions, v);
    for (std::size_t j = 0; j < fans.size(); ++j)
        if (fans[j].first == u)
            return fans[(j + fans.size() - 1) % fans.size()].second;
    assert(false);
    return fans[0].second;
}

// The inverse step: the vertex before u on the loop that leaves u by the free half-edge u -> v.
std::uint32_t previous_boundary_vertex(const Surface& s, const std::vector<Vec3>& positions, std::uint32_t u, std::uint32_t v)
{
    if (s.arc_count(u) == 1)
        if (const std::uint32_t w = s.arc_start(u, v); w != kNone)
            return w;
    const auto fans = ordered_fans(s, positions, u);
    for (std::size_t j = 0; j < fans.size(); ++j)
        if (fans[j].second == v)
            return fans[(j + 1) % fans.size()].first;
    assert(false);
    return fans[0].first;
}

// The same two steps on the surface as split_pinches will leave it, where each fan of a pinched vertex is
// a vertex of its own: a cycle arriving at v by the free half-edge u -> v leaves by the other end of
// the same fan's arc (first -> v, v -> last). kNone if no fan of v starts at u.
std::uint32_t next_in_fan(const Surface& s, std::uint32_t u, std::uint32_t v)
{
    return s.arc_end(v, u);
}

// The inverse step: the vertex before u on the cycle that leaves u by the free half-edge u -> v.
std::uint32_t previous_in_fan(const Surface& s, std::uint32_t u, std::uint32_t v)
{
    return s.arc_start(u, v);
}

} // namespace mrt::surface_detail
