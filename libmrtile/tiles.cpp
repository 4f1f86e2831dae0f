// Tile generation, paper §4.2: each cut cluster becomes a nearly planar polygon (its pseudo tile)
// whose convex hull in the PCA plane is the tile outline. The hull is Andrew's monotone chain in the
// (axis_u, axis_v) coordinates of the plane, so it is exact for the projected points and
// counter-clockwise seen from the normal; collinear hull points are dropped because they would give
// zero-area fan triangles (T1) later.
//
// Coarse cut nodes are unions of leaves and need not be convex, so the hulls of neighbouring nodes can
// overlap and their fans would cover some surface twice (extra handles in the mesh). By default the
// points are therefore re-partitioned by the Voronoi cells of the cut's centres: a point goes to its
// nearest centre, found by a greedy walk on the centres' Delaunay graph (exact: a site that is not the
// nearest always has a Delaunay neighbour nearer to the point). Cells are convex and disjoint, so the
// fans are too, and every point lies in some tile, so gaps stay one spacing wide. The same pass finds
// the restricted Delaunay neighbours (tiles whose cells meet on the sampled surface): a point of cell A
// that lies within about a point spacing of the bisector plane of A and a Delaunay neighbour B
// witnesses that the sampled surface reaches the Voronoi face of A and B. The surface stage uses them to keep gap triangles between
// tiles that really meet (not across a handle's hole or a plate some 5 spacings thick or more). Thinner
// walls fool the witness (their sides both reach the bisector of a tile on each side): on request
// (TileOptions::meet_factor) such tiles must also have points near each other (meet_on_surface).
//
// The walk is the costly part, so a large node takes part with a sample only (TileOptions::max_points):
// every k-th point of its range, which the tree keeps spatially coherent, plus its own hull points, found
// in one pass of dot products that leaves only the points outside an octagon to sort. A cut then costs
// time per tile, and a tile at an open border still reaches it.
#include "libmrtile/tiles.h"

#include "libmrtile/coverage_gap.h"
#include "libmrtile/errors.h"
#include "libmrtile/gabriel_graph.h"
#include "libmrtile/median.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <string>
#include <tuple>

namespace mrt {
namespace {

// In a scan from one viewpoint, a neighbouring node's point in a tile's Voronoi cell belongs to another
// surface when it lies farther from the tile's plane than this many times the larger of the node's own
// largest plane distance and the tile's point spacing.
constexpr double kForeignPlaneFactor = 4.0;

// Outside height fields, a point whose nearest centre is another node's stays in its own node's cell
// when it lies farther from that node's plane than this many times the largest of the node's largest
// plane distance, 3 RMS plane distances and its point spacing, and within that of its own node's plane:
// it is another surface (voronoi_partition). At 8 the points of a narrow strip of a merged scan's base,
// whose plane is poorly defined, were kept from it by 1.05-1.7 times that reach, and the strip was left
// out of bun.conf's mesh at tolerance 0.01. With the larger of the two nodes' reaches (see there), two
// surfaces part where they lie about 16 spacings apart or more: QA round 48's wall, 20 of its spacings
// behind a pipe, is 1.3 reaches off the pipe's tiles.
constexpr double kOtherSurfaceFactor = 16.0;
// Nearer than that, a small node and one at least kApartCountRatio times larger are other surfaces
// (apart) when the small one's bounding box lies off the larger one's plane farther than kApartFactor
// times the larger of their reach units (as above): the small one's points do not come near the
// larger's surface. The larger node's plane is the one to trust (a tile of 8-25 points in a concave
// corner leans whichever way its noise has it), and the box, not the centre, is what must keep off it
// (a small tile across a crease reaches the larger's plane at the crease). A point whose nearest centre
// is apart from its own node goes to the nearest centre that is not. QA round 78: a 14-point tile under
// a fandisk's overhang, 9 spacings thick, took a point of the top face 0.21 above it, and its fan rose
// through the plate as a finger 4.7 spacings from the truth. Nodes of like size are left as they were:
// without the ratio, five nested spheres 5 spacings apart lost their closure (a loop) and a stack of
// planes 5 spacings apart had 9 times the crossing faces.
constexpr double kApartFactor = 4.0;
constexpr std::uint32_t kApartCountRatio = 4;

// Tiles whose normals are this close (either way round) may be the two sides of a thin wall: with
// TileOptions::meet_factor, their adjacency asks whether their cells meet (meet_on_surface).
constexpr double kSameFacingDegrees = 30.0;

// At most this many hull points make a tile's outline (see thinned_hull).
constexpr std::size_t kMaxHullPoints = 128;

// A point of a tile lying farther off the tile's plane than this many times the robust spread of the
// tile's heights (1.4826 × their median absolute deviation, at least the node's point spacing), among at
// most kStrayShare of the points the tile stands for, is a stray: it neither shapes the outline nor
// lifts the apex (see drop_strays).
constexpr double kStrayHeightFactor = 10.0;
constexpr double kStrayShare = 0.02;

// A hull point of a tile farther from every other point of the tile than this many times the tile's
// mean spacing (the square root of its hull's area per point) is a stray too (see
// drop_isolated_hull_points). Small tiles only, of 8 points or more: a median distance between nearest
// points as the spacing of fewer (session 51) dropped real points of range scans and CAD vertices
// (bun000 at 0.002: largest distance 9x).
constexpr double kStrayIsolation = 6.0;

struct Projected
{
    double x, y;
    std::uint32_t index;
};

// The fan apex's height above the centre (along the normal) that fits the fan to the tile's points in
// least squares. A point at barycentric (λ_apex, λ_i, λ_j) in its fan triangle (apex, q_i, q_j) sees the
// fan at height λ_apex h + λ_i z_i + λ_j z_j, so the best h is Σ λ_apex (z - λ_i z_i - λ_j z_j) / Σ λ_apex².
// On a spherical cap this puts the apex about 1.4 sags above the rim and cuts the mean distance inside the
// fan about threefold against an apex on the surface (a cone under a dome). Returns false when the
// points do not determine h (all of them on the hull).
bool fitted_apex_height(const std::vector<Projected>& pts, const std::vector<double>& heights,
                        const std::vector<Projected>& hull, const std::vector<double>& hull_heights, double& h)
{
    // Hull vertices in angular order around the centre (the mean lies inside the hull).
    const std::size_t m = hull.size();
    std::vector<double> angle(m);
    for (std::size_t i = 0; i < m; ++i)
        angle[i] = std::atan2(hull[i].y, hull[i].x);
    const std::size_t first = static_cast<std::size_t>(std::min_element(angle.begin(), angle.end()) - angle.begin());
    std::vector<std::size_t> order(m); // hull positions by increasing angle (the hull is counter-clockwise)
    std::vector<double> sorted(m);
    for (std::size_t k = 0; k < m; ++k) {
        order[k] = (first + k) % m;
        sorted[k] = angle[order[k]];
    }
    double numerator = 0.0, denominator = 0.0;
    for (std::size_t p = 0; p < pts.size(); ++p) {
        const double a = std::atan2(pts[p].y, pts[p].x);
        // Sector [sorted[k], sorted[k + 1]) (the last one wraps around).
        std::size_t k = static_cast<std::size_t>(std::upper_bound(sorted.begin(), sorted.end(), a) - sorted.begin());
        k = (k + m - 1) % m;
        const Projected& qi = hull[order[k]];
        const Projected& qj = hull[order[(k + 1) % m]];
        // Barycentric coordinates of p in (origin, qi, qj).
        const double det = qi.x * qj.y - qi.y * qj.x;
        if (!(std::abs(det) > 0.0))
            continue;
        const double li = (pts[p].x * qj.y - pts[p].y * qj.x) / det;
        const double lj = (qi.x * pts[p].y - qi.y * pts[p].x) / det;
        const double la = std::clamp(1.0 - li - lj, 0.0, 1.0);
        const double rest = heights[p] - li * hull_heights[order[k]] - lj * hull_heights[order[(k + 1) % m]];
        numerator += la * rest;
        denominator += la * la;
    }
    if (!(denominator > 1e-9 * static_cast<double>(pts.size())))
        return false;
    h = numerator / denominator;
    return true;
}

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

// Thins a counter-clockwise convex hull to at most `most` vertices by dropping, again and again, the
// vertex whose triangle with its two neighbours has the least area (Visvalingam), which keeps the
// polygon convex and changes its outline least. A tile's fan has one face per hull vertex, and every
// face of a fan shares the apex, so their boxes all meet and the self-intersection tests of a mesh cost
// the square of the largest fan: points along a convex curve are all hull points (QA round qa-adv: a
// circle of 40,000 points gave tiles of 500 hull points and took 96 s to mesh, 100,000 points over 120 s,
// a coarse cut one tile of every point). Surface tiles have a few dozen hull points (the bunny and Igea
// at every cut: fan apexes of valence 36 at most), so a bound far above that changes no such mesh.
std::vector<std::uint32_t> thinned_hull(const std::vector<std::uint32_t>& hull, const std::vector<Projected>& at,
                                        std::size_t most)
{
    const std::size_t m = hull.size();
    if (m <= most || most < 3)
        return hull;
    std::vector<std::size_t> prev(m), next(m);
    for (std::size_t i = 0; i < m; ++i) {
        prev[i] = (i + m - 1) % m;
        next[i] = (i + 1) % m;
    }
    auto area = [&](std::size_t i) { return turn(at[prev[i]], at[i], at[next[i]]); };
    std::set<std::pair<double, std::size_t>> queue; // (twice the area, hull position): ties by position
    std::vector<double> key(m);
    for (std::size_t i = 0; i < m; ++i)
        queue.insert({key[i] = area(i), i});
    std::vector<bool> kept(m, true);
    for (std::size_t left = m; left > most; --left) {
        const std::size_t i = queue.begin()->second;
        queue.erase(queue.begin());
        kept[i] = false;
        next[prev[i]] = next[i];
        prev[next[i]] = prev[i];
        for (const std::size_t j : {prev[i], next[i]}) {
            queue.erase({key[j], j});
            queue.insert({key[j] = area(j), j});
        }
    }
    std::vector<std::uint32_t> out;
    out.reserve(most);
    for (std::size_t i = 0; i < m; ++i)
        if (kept[i])
            out.push_back(hull[i]);
    return out;
}

// Points of `pts` that lie apart: those in one cell of a grid of side `cell` in the plane count once
// (cells are a bound, not a metric: two points a hair apart across a cell border count twice, which
// only a clump straddling a border does, and the clumps this is for are far smaller than a cell).
std::uint32_t distinct_in_plane(const std::vector<Projected>& pts, double cell)
{
    if (!(cell > 0.0))
        return static_cast<std::uint32_t>(pts.size());
    std::vector<std::pair<double, double>> cells;
    cells.reserve(pts.size());
    for (const Projected& p : pts)
        cells.push_back({std::floor(p.x / cell), std::floor(p.y / cell)});
    std::sort(cells.begin(), cells.end());
    return static_cast<std::uint32_t>(std::unique(cells.begin(), cells.end()) - cells.begin());
}

// TileOptions::plane_axis as a unit vector, or zero for none. An axis of any length counts: one whose
// squared norm underflows (1e-300) was taken for none, one whose norm overflows (1e300) gave NaN planes.
Vec3 unit_plane_axis(const TileOptions& options)
{
    const Vec3 a = with_usable_norm(options.plane_axis);
    return squared_norm(a) > 0.0 ? normalized(a) : Vec3{0, 0, 0};
}

// `pts` without the strays far off the tile's plane (kStrayHeightFactor): a bird over a terrain, a
// mixed pixel, a stray return. The pseudo tile maps its hull points back to where they were sampled, so
// a stray on the hull of a coarse tile was a fan corner metres off the surface (QA round 60: a 100 m
// terrain with birds 5-50 m over it had tents and spikes up to 46 m at tolerance 0.02, and its tileset's
// root, one fan, a corner 39 m up). Only a few points may go, so that two surfaces in one coarse tile
// (a wall over a floor, the two halves of a step) both stay: their heights spread the deviation; and
// only points apart from the rest (see below).
void drop_strays(std::vector<Projected>& pts, const Hierarchy& h, const Tile& t, const Node& n)
{
    if (pts.size() < 8)
        return;
    std::vector<double> heights(pts.size());
    for (std::size_t k = 0; k < pts.size(); ++k)
        heights[k] = dot(h.cloud.positions[pts[k].index] - t.centre, t.normal);
    std::vector<double> deviations = heights;
    const double middle = upper_median_in_place(deviations);
    for (double& d : deviations)
        d = std::abs(d - middle);
    const double spread = std::max(1.4826 * upper_median_in_place(deviations), node_spacing(n));
    const double reach = kStrayHeightFactor * spread;
    // Strays stand apart: with any point between half the reach and the reach, the heights run on
    // (a tile reaching round a tight bend, the tip of an elongated ellipsoid) and none is dropped.
    std::size_t strays = 0;
    for (const double z : heights) {
        const double off = std::abs(z - middle);
        if (off > 0.5 * reach && !(off > reach))
            return;
        strays += off > reach;
    }
    // The share of the points the tile stands for: a large node's tile is built from a sample that
    // holds all its hull points, and strays are hull points far more often than the rest, so their
    // share of the sample overstates theirs of the node (measured against the sample's share: QA
    // round 60's inputs with outliers changed in 3 of 66 runs: crossing pairs of torus_out5pct at 0.02
    // 80 -> 15 and at 0.01 52 -> 84, of sphere_big_mixed at 0.02 78 -> 8).
    const double represented = std::max(static_cast<double>(pts.size()), static_cast<double>(n.count()));
    if (strays == 0 || static_cast<double>(strays) > kStrayShare * represented)
        return;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < pts.size(); ++k)
        if (!(std::abs(heights[k] - middle) > reach))
            pts[kept++] = pts[k];
    pts.resize(kept);
}

// `pts` without the hull points that stand apart from all the others (kStrayIsolation) and off the
// plane of the rest. A small tile that took in a bird leans to it: the bird lies on the tile's plane,
// so the height test of drop_strays does not see it, but it is a hull point metres from any other and
// off the plane of the ground (QA round 60's birds at tolerance 0.005: a chain of fan corners and split
// points up to a bird 7 m over the ground).
void drop_isolated_hull_points(std::vector<Projected>& pts, const Hierarchy& h, const Tile& t, std::size_t max_points)
{
    // Only a node's own points, and only a node whose points are all there: in the sample of a larger
    // node (TileOptions::max_points) a point at a thin part's tip is far from the other sampled points
    // (bun000 at 0.02 lost one so, its largest distance +70%).
    const Node& n = h.nodes[static_cast<std::size_t>(t.node)];
    if (pts.size() < 8 || sample_stride(n.count(), max_points) > 1)
        return;
    std::vector<Projected> sorted = pts;
    const std::vector<std::uint32_t> hull = convex_hull(sorted, 0.0);
    if (hull.size() < 3)
        return;
    double twice_area = 0.0;
    for (std::size_t k = 0; k < hull.size(); ++k) {
        const Vec3 a = h.cloud.positions[hull[k]] - t.centre, b = h.cloud.positions[hull[(k + 1) % hull.size()]] - t.centre;
        twice_area += dot(a, t.axis_u) * dot(b, t.axis_v) - dot(a, t.axis_v) * dot(b, t.axis_u);
    }
    const double spacing2 = 0.5 * twice_area / static_cast<double>(pts.size());
    const double reach2 = kStrayIsolation * kStrayIsolation * spacing2;
    Moments all; // of every point, summed once a hull point is found isolated (most tiles have none)
    std::vector<std::uint32_t> strays;
    for (const std::uint32_t i : hull) {
        if (i < n.begin || i >= n.end)
            continue;
        const Vec3& p = h.cloud.positions[i];
        double nearest2 = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < pts.size() && nearest2 > reach2; ++k)
            if (pts[k].index != i)
                nearest2 = std::min(nearest2, squared_norm(h.cloud.positions[pts[k].index] - p));
        if (!(nearest2 > reach2))
            continue;
        // And off the plane of the rest by half its distance to them or more: a point far out on the
        // plane of the others is a sparse sample of the same surface (the far end of a scan line), not
        // a stray (QA round 63: one point of a 20-point plane, 2.5 units out, was left out).
        if (all.count == 0)
            for (const Projected& q : pts)
                all.add(h.cloud.positions[q.index]);
        Moments rest = all;
        rest.remove(p);
        const Vec3 normal = eigen_decomposition(rest).vectors[0];
        const double off = dot(p - rest.mean, normal);
        if (4.0 * off * off >= nearest2)
            strays.push_back(i);
    }
    // One stray may go from a small tile (15 points, one of them a bird), more only within kStrayShare.
    if (strays.empty() || static_cast<double>(strays.size()) > std::max(1.0, kStrayShare * static_cast<double>(pts.size())))
        return;
    std::sort(strays.begin(), strays.end());
    pts.erase(std::remove_if(pts.begin(), pts.end(),
                             [&](const Projected& q) { return std::binary_search(strays.begin(), strays.end(), q.index); }),
              pts.end());
}

// The tile of `node` built from the points `indices` (into h.cloud.positions).
Tile tile_from_points(const Hierarchy& h, std::int32_t node, const std::uint32_t* indices, std::size_t count,
                      const TileOptions& options)
{
    const Node& n = h.nodes[static_cast<std::size_t>(node)];
    Tile t;
    t.node = node;
    const auto set_frame = [&](const Vec3& centre, const Eigen3x3& frame) {
        t.centre = centre;
        t.normal = frame.vectors[0];
        t.axis_u = frame.vectors[2];
        if (const Vec3 axis = unit_plane_axis(options); squared_norm(axis) > 0.0) {
            // The given plane, its normal on the side of the PCA normal (which keeps its sign convention).
            t.normal = dot(axis, t.normal) < 0.0 ? -axis : axis;
            // The largest PCA axis laid into the plane, so that a tile whose own plane is that plane (a
            // flat one) keeps its frame exactly; a helper axis where it stands on the plane.
            const Vec3 along = t.axis_u - t.normal * dot(t.axis_u, t.normal);
            t.axis_u = squared_norm(along) > 1e-6 ? normalized(along) : perpendicular_axis(t.normal);
        }
        // Right-handed plane basis so that counter-clockwise in (u, v) is counter-clockwise seen from normal.
        t.axis_v = cross(t.normal, t.axis_u);
    };
    set_frame(n.moments.mean, n.frame);
    t.points = static_cast<std::uint32_t>(count);
    std::vector<Projected> pts;
    pts.reserve(count);
    double sum_r2 = 0.0;
    for (std::size_t k = 0; k < count; ++k) {
        const Vec3 d = h.cloud.positions[indices[k]] - t.centre;
        pts.push_back({dot(d, t.axis_u), dot(d, t.axis_v), indices[k]});
    }
    drop_strays(pts, h, t, n);
    drop_isolated_hull_points(pts, h, t, options.max_points);
    if (pts.size() < count) {
        // The plane of the points without the strays: a small tile leant to its stray (a plane through
        // a bird and the ground), and the ground alone would project to a sliver of it.
        Moments kept;
        for (const Projected& q : pts)
            kept.add(h.cloud.positions[q.index]);
        set_frame(kept.mean, eigen_decomposition(kept));
        for (Projected& q : pts) {
            const Vec3 d = h.cloud.positions[q.index] - t.centre;
            q.x = dot(d, t.axis_u);
            q.y = dot(d, t.axis_v);
        }
    }
    for (const Projected& q : pts)
        sum_r2 += q.x * q.x + q.y * q.y;
    // Apex: the mean height over the points within half the RMS radius of the centre (for a disc, the
    // inner quarter of the area); all points if there are too few there.
    t.apex = t.centre;
    if (!pts.empty()) {
        const double inner = 0.25 * sum_r2 / static_cast<double>(pts.size());
        double height = 0.0;
        std::size_t used = 0;
        for (const Projected& q : pts)
            if (q.x * q.x + q.y * q.y <= inner) {
                height += dot(h.cloud.positions[q.index] - t.centre, t.normal);
                ++used;
            }
        if (used >= 3)
            t.apex = t.centre + t.normal * (height / static_cast<double>(used));
    }
    t.boundary = convex_hull(pts, options.collinear_tolerance);
    if (t.boundary.size() > kMaxHullPoints) {
        std::vector<Projected> at;
        at.reserve(t.boundary.size());
        for (const std::uint32_t i : t.boundary) {
            const Vec3 d = h.cloud.positions[i] - t.centre;
            at.push_back({dot(d, t.axis_u), dot(d, t.axis_v), i});
        }
        t.boundary = thinned_hull(t.boundary, at, kMaxHullPoints);
    }
    if (t.has_fan() && options.fit_apex) {
        std::vector<double> heights(pts.size());
        for (std::size_t k = 0; k < pts.size(); ++k)
            heights[k] = dot(h.cloud.positions[pts[k].index] - t.centre, t.normal);
        std::vector<Projected> hull;
        std::vector<double> hull_heights;
        for (std::uint32_t i : t.boundary) {
            const Vec3 d = h.cloud.positions[i] - t.centre;
            hull.push_back({dot(d, t.axis_u), dot(d, t.axis_v), i});
            hull_heights.push_back(dot(d, t.normal));
        }
        double height = 0.0;
        if (fitted_apex_height(pts, heights, hull, hull_heights, height)) {
            // Few points near the centre leave the fit barely determined (its denominator is the sum of
            // their squared apex weights), and it can throw the apex far off the tile: on a uniformly
            // sampled CAD part a tile of 11 points, 8 of them on its hull, put its apex 0.39 diagonals
            // out, a spike. A cap's best apex lies 0.4 of the height range above its highest point, so
            // half the range beyond the points either way keeps every sound fit; the tile's radius
            // bounds it where the range is no cap's (a tile folded over a corner). Tighter bounds (a
            // quarter of the radius) changed the 3-hole solid's topology at coarse cuts.
            const auto [low, high] = std::minmax_element(heights.begin(), heights.end());
            double radius2 = 0.0;
            for (const Projected& q : hull)
                radius2 = std::max(radius2, q.x * q.x + q.y * q.y);
            const double margin = std::min(0.5 * (*high - *low), std::sqrt(radius2));
            t.apex = t.centre + t.normal * std::clamp(height, *low - margin, *high + margin);
        }
    }
    if (t.has_fan()) {
        const std::size_t n = t.boundary.size();
        std::vector<std::pair<double, double>> uv(n); // hull points in the plane
        double extent2 = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const Vec3 d = h.cloud.positions[t.boundary[i]] - t.centre;
            uv[i] = {dot(d, t.axis_u), dot(d, t.axis_v)};
            extent2 = std::max(extent2, uv[i].first * uv[i].first + uv[i].second * uv[i].second);
        }
        double twice = 0.0, cx = 0.0, cy = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            const auto& a = uv[i];
            const auto& b = uv[(i + 1) % n];
            const double cross = a.first * b.second - a.second * b.first;
            twice += cross;
            cx += (a.first + b.first) * cross;
            cy += (a.second + b.second) * cross;
        }
        t.area = 0.5 * twice;
        t.distinct_points = distinct_in_plane(pts, 0.01 * std::sqrt(std::max(t.area, 0.0) / static_cast<double>(count)));
        // The apex must lie inside the hull, or fan faces fold or have no area. The node's mean is its
        // Voronoi site, inside its cell, but the cell's few points need not surround it (a cell of two or
        // three stray points): then the apex moves to the hull's centroid, at the same height.
        const Vec3 apex = t.apex - t.centre;
        const double ax = dot(apex, t.axis_u), ay = dot(apex, t.axis_v);
        bool inside = twice > 0.0;
        for (std::size_t i = 0; i < n && inside; ++i) {
            const auto& a = uv[i];
            const auto& b = uv[(i + 1) % n];
            inside = (b.first - a.first) * (ay - a.second) - (b.second - a.second) * (ax - a.first) > 1e-9 * extent2;
        }
        if (!inside && twice > 0.0)
            t.apex = t.centre + t.axis_u * (cx / (3.0 * twice)) + t.axis_v * (cy / (3.0 * twice)) +
                     t.normal * dot(apex, t.normal);
        if (options.measure_gaps) {
            std::vector<Vec3> points(count);
            for (std::size_t k = 0; k < count; ++k)
                points[k] = h.cloud.positions[indices[k]];
            CoverageOptions gap_options;
            gap_options.max_points = 0; // a tile is already a sample of at most max_points
            gap_options.sample_fraction = std::min(1.0, static_cast<double>(count) / h.nodes[static_cast<std::size_t>(node)].count());
            t.coverage_gap = coverage_gap(points, t.axis_u, t.axis_v, gap_options);
        }
    }
    return t;
}

void check_node(const Hierarchy& h, std::int32_t node)
{
    if (node < 0 || static_cast<std::size_t>(node) >= h.nodes.size())
        throw InvalidInput("cut: node id " + std::to_string(node) + " is not in the hierarchy (" +
                           std::to_string(h.nodes.size()) + " nodes)");
    const Node& n = h.nodes[static_cast<std::size_t>(node)];
    if (n.end <= n.begin || n.end > h.cloud.positions.size())
        throw InvalidInput("cut: node " + std::to_string(node) + " has an empty or out-of-range point range");
}

// The Voronoi partition of the cut's points and the surface adjacency of the cells (see the file comment).
struct Partition
{
    std::vector<std::uint32_t> start;  // points of cell k: order[start[k] .. start[k+1])
    std::vector<std::uint32_t> order;
    // closest[k][j]: smallest distance to the bisector plane of centres k and graph[k][j] over the points
    // whose nearest centre is k (infinity if there is none).
    std::vector<std::vector<double>> closest;
};

// A convex polygon (counter-clockwise, coinciding corners skipped) that tells which points lie strictly
// inside it. A point well inside its inscribed circle about the origin passes every edge by a margin
// that rounding cannot undo, and is taken without the turn tests.
class ConvexPolygon
{
public:
    explicit ConvexPolygon(const std::vector<Projected>& corners)
    {
        double extent = 0.0;
        for (const Projected& p : corners)
            extent = std::max({extent, std::abs(p.x), std::abs(p.y)});
        double radius = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < corners.size(); ++k) {
            const Projected& a = corners[k];
            const Projected& b = corners[(k + 1) % corners.size()];
            if (a.x == b.x && a.y == b.y)
                continue;
            edges_.emplace_back(a, b);
            const double length = std::hypot(b.x - a.x, b.y - a.y);
            // Short edges or a centre near an edge: no shortcut (rounding could decide a turn's sign).
            radius = length > 1e-6 * extent ? std::min(radius, turn(a, b, Projected{0.0, 0.0, 0}) / length) : 0.0;
        }
        // Inside the radius by 1%, every turn is over 0.01 × radius × edge length > 1e-14 extent², far
        // above its rounding error (about 1e-16 extent²).
        const double safe = radius > 1e-4 * extent && std::isfinite(radius) ? 0.99 * radius : 0.0;
        safe_squared_ = safe * safe;
    }
    bool strictly_inside(const Projected& p) const
    {
        if (p.x * p.x + p.y * p.y < safe_squared_)
            return true;
        for (const auto& [a, b] : edges_)
            if (turn(a, b, p) <= 0.0)
                return false;
        return true;
    }

private:
    std::vector<std::pair<Projected, Projected>> edges_;
    double safe_squared_ = 0.0;
};

// The convex hull of all of a node's points in its PCA plane, ascending. Only the points outside the
// octagon of the extremes along x, y, x + y and x - y can be on the hull (Akl and Toussaint), so one
// cheap pass over the points leaves few to sort. Saving a model does this for every large node (a pass
// over every point per level of the tree), so the octagon's leftovers (an eighth of the points of a
// torus) are thinned again by the 16-gon that adds the extremes at the 8 directions between, found among
// them (a point extreme in any direction is on the hull, so never inside the octagon): a third less
// time. The hull is the same whichever points strictly inside it are dropped first (checked against
// the octagon alone on 19 scans and generated clouds, grids with collinear borders among them).
// `candidates`: scratch, one per thread.
std::vector<std::uint32_t> hull_from_points(const Hierarchy& h, const Node& n, std::vector<Projected>& candidates)
{
    const Vec3 u = n.frame.vectors[2], v = cross(n.frame.vectors[0], u), c = n.moments.mean;
    auto project = [&](std::uint32_t i) {
        const Vec3 d = h.cloud.positions[i] - c;
        return Projected{dot(d, u), dot(d, v), i};
    };
    // Extremes in 8 directions, counter-clockwise from +x (the first point to reach each: strict
    // comparisons).
    std::vector<Projected> corners(8);
    double max_x = -std::numeric_limits<double>::infinity(), max_y = max_x, max_s = max_x, max_t = max_x;
    double min_x = std::numeric_limits<double>::infinity(), min_y = min_x, min_s = min_x, min_t = min_x;
    for (std::uint32_t i = n.begin; i < n.end; ++i) {
        const Projected p = project(i);
        const double s = p.x + p.y, t = p.x - p.y;
        if (p.x > max_x) { max_x = p.x; corners[0] = p; }
        if (s > max_s) { max_s = s; corners[1] = p; }
        if (p.y > max_y) { max_y = p.y; corners[2] = p; }
        if (t < min_t) { min_t = t; corners[3] = p; }
        if (p.x < min_x) { min_x = p.x; corners[4] = p; }
        if (s < min_s) { min_s = s; corners[5] = p; }
        if (p.y < min_y) { min_y = p.y; corners[6] = p; }
        if (t > max_t) { max_t = t; corners[7] = p; }
    }
    const ConvexPolygon octagon(corners);
    candidates.clear();
    for (std::uint32_t i = n.begin; i < n.end; ++i)
        if (const Projected p = project(i); !octagon.strictly_inside(p))
            candidates.push_back(p);
    // The 16-gon: between each two octagon corners, the extreme at the direction halfway.
    std::vector<Projected> sixteen(16);
    for (std::size_t k = 0; k < 8; ++k) {
        const double angle = (static_cast<double>(k) + 0.5) * M_PI / 4.0;
        const double dx = std::cos(angle), dy = std::sin(angle);
        double best = -std::numeric_limits<double>::infinity();
        for (const Projected& p : candidates)
            if (dx * p.x + dy * p.y > best) {
                best = dx * p.x + dy * p.y;
                sixteen[2 * k + 1] = p;
            }
        sixteen[2 * k] = corners[k];
    }
    const ConvexPolygon polygon(sixteen);
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [&](const Projected& p) { return polygon.strictly_inside(p); }),
                     candidates.end());
    std::vector<std::uint32_t> hull = convex_hull(candidates, 0.0);
    std::sort(hull.begin(), hull.end());
    return hull;
}

bool hull_stored(const Hierarchy& h, std::size_t node)
{
    return h.hull_start.size() == h.nodes.size() + 1 && h.hull_start[node + 1] > h.hull_start[node];
}

// The points a node's tile is built from (TileOptions::max_points), ascending: every stride-th point of
// its range and its hull points, or all of them.
std::vector<std::uint32_t> node_sample(const Hierarchy& h, std::int32_t node, std::size_t max_points)
{
    const Node& n = h.nodes[static_cast<std::size_t>(node)];
    // Step between the points of a node used for its tile (TileOptions::max_points).
    const auto stride = static_cast<std::uint32_t>(sample_stride(n.count(), max_points));
    std::vector<std::uint32_t> sample;
    for (std::uint32_t i = n.begin; i < n.end; i += stride)
        sample.push_back(i);
    if (stride > 1) {
        for (std::uint32_t i : node_hull(h, node))
            if ((i - n.begin) % stride != 0)
                sample.push_back(i);
        std::sort(sample.begin(), sample.end());
    }
    return sample;
}

// A point in the coordinates the Voronoi partition is taken in: as it is, or in the plane normal to
// TileOptions::plane_axis (u, v, 0: exactly coplanar, so that the Delaunay graph is the plane's).
struct PartitionSpace
{
    bool flat = false;
    Vec3 u{1, 0, 0}, v{0, 1, 0};
    Vec3 operator()(const Vec3& p) const { return flat ? Vec3{dot(p, u), dot(p, v), 0.0} : p; }
};

PartitionSpace partition_space(const TileOptions& options)
{
    PartitionSpace space;
    if (const Vec3 axis = unit_plane_axis(options); squared_norm(axis) > 0.0) {
        space.flat = true;
        space.u = perpendicular_axis(axis);
        space.v = cross(axis, space.u);
    }
    return space;
}

Partition voronoi_partition(const Hierarchy& h, const std::vector<std::int32_t>& cut, const std::vector<Vec3>& centres,
                            const std::vector<std::vector<std::uint32_t>>& graph, std::size_t max_points,
                            const PartitionSpace& space)
{
    const auto tiles = static_cast<std::uint32_t>(cut.size());
    // Coincident centres: the Delaunay graph keeps only the first; walks start there.
    std::vector<std::uint32_t> by_position(tiles);
    std::iota(by_position.begin(), by_position.end(), 0u);
    std::sort(by_position.begin(), by_position.end(), [&](std::uint32_t a, std::uint32_t b) {
        const Vec3 &p = centres[a], &q = centres[b];
        return std::tie(p.x, p.y, p.z, a) < std::tie(q.x, q.y, q.z, b);
    });
    std::vector<std::uint32_t> representative(tiles);
    for (std::size_t i = 0; i < by_position.size(); ++i)
        representative[by_position[i]] = i > 0 && centres[by_position[i]] == centres[by_position[i - 1]]
                                             ? representative[by_position[i - 1]]
                                             : by_position[i];
    Partition out;
    out.closest.resize(tiles);
    for (std::uint32_t k = 0; k < tiles; ++k)
        out.closest[k].assign(graph[k].size(), std::numeric_limits<double>::infinity());
    std::vector<std::uint32_t> owner;
    std::vector<std::uint32_t> point;
    // The unit of each cell's reaches off its node's plane (kOtherSurfaceFactor, kApartFactor).
    std::vector<double> unit(tiles);
    for (std::uint32_t k = 0; k < tiles; ++k) {
        const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
        // (3 RMS plane distances stand in for the largest where a hierarchy was not built by
        // build_hierarchy, which alone records it.)
        unit[k] = std::max({n.max_plane_distance, 3.0 * n.rms_plane_distance, node_spacing(n)});
    }
    // Whether the nodes of tiles a and b are other surfaces (kApartFactor).
    const auto apart = [&](std::uint32_t a, std::uint32_t b) {
        const Node& na = h.nodes[static_cast<std::size_t>(cut[a])];
        const Node& nb = h.nodes[static_cast<std::size_t>(cut[b])];
        const bool a_larger = na.count() > nb.count() || (na.count() == nb.count() && a < b);
        const Node& larger = a_larger ? na : nb;
        const Node& smaller = a_larger ? nb : na;
        if (larger.count() < static_cast<std::uint64_t>(kApartCountRatio) * smaller.count())
            return false;
        // How near the smaller node's box comes to the larger node's plane.
        const Vec3 normal = larger.frame.vectors[0];
        const Vec3 half = smaller.box.size() * 0.5;
        const double box_reach = std::abs(normal.x) * half.x + std::abs(normal.y) * half.y + std::abs(normal.z) * half.z;
        const double nearest = std::abs(dot(smaller.box.centre() - larger.moments.mean, normal)) - box_reach;
        return nearest > kApartFactor * std::max(unit[a], unit[b]);
    };
    // Greedy walk from `start` to p over the centres `allowed` admits: (distance, index) strictly
    // decreases, so it ends, at a centre with no allowed neighbour nearer to p (with all allowed, a
    // nearest centre: the graph is Delaunay). Returns the centre and its squared distance.
    const auto walk = [&](std::uint32_t start, const Vec3& p, const auto& allowed) {
        std::uint32_t best = start;
        double best_d = squared_distance(p, centres[best]);
        for (bool moved = true; moved;) {
            moved = false;
            for (std::uint32_t j : graph[best]) {
                const double d = squared_distance(p, centres[j]);
                if ((d < best_d || (d == best_d && j < best)) && allowed(j)) {
                    best = j;
                    best_d = d;
                    moved = true;
                }
            }
        }
        return std::pair{best, best_d};
    };
    for (std::uint32_t k = 0; k < tiles; ++k) {
        const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
        for (std::uint32_t i : node_sample(h, cut[k], max_points)) {
            const Vec3 p = space(h.cloud.positions[i]);
            const auto [best, best_d] = walk(representative[k], p, [](std::uint32_t) { return true; });
            // A point of another surface (a wall behind a pipe whose tile's centre is nearer than the
            // wall's own: QA round 48, the pipe's fan reached across to the wall; a slab's top under a
            // small tile of its underside: QA round 43) stays in its own node's cell, and is no witness
            // of the cells' meeting on the surface.
            // Not in a height field's plane partition: its cells must not overlap seen along the axis
            // (a roof's cell takes the ground points beside the wall below it).
            if (!space.flat && best != representative[k]) {
                const Node& other = h.nodes[static_cast<std::size_t>(cut[best])];
                const Vec3& q = h.cloud.positions[i];
                // The larger of the two reaches: where a coarse node meets fine ones (a focus region, a
                // camera cut), its points beside a fine tile lie off that tile's plane by the curvature
                // of the coarse node's span, not of the fine tile's (with the fine tile's reach alone,
                // the torus's focus cut kept such points from the fine cells: overlapping tiles, and its
                // mesh took 3 times as long).
                const double off = kOtherSurfaceFactor * std::max(unit[best], unit[k]);
                const double height = std::abs(dot(q - other.moments.mean, other.frame.vectors[0]));
                if (height > off && std::abs(dot(q - n.moments.mean, n.frame.vectors[0])) <= off) {
                    owner.push_back(k);
                    point.push_back(i);
                    continue;
                }
                if (apart(best, k)) {
                    // The nearest centre among those not apart from k; no witness either.
                    owner.push_back(walk(representative[k], p, [&](std::uint32_t j) { return !apart(j, k); }).first);
                    point.push_back(i);
                    continue;
                }
            }
            // Distance to the bisector plane with each Delaunay neighbour of the nearest centre (every
            // Voronoi face of the cell is with one of them).
            const std::vector<std::uint32_t>& around = graph[best];
            for (std::size_t j = 0; j < around.size(); ++j) {
                const double d = squared_distance(p, centres[around[j]]);
                const double gap = distance(centres[best], centres[around[j]]);
                if (gap > 0.0) {
                    double& c = out.closest[best][j];
                    c = std::min(c, (d - best_d) / (2.0 * gap));
                }
            }
            owner.push_back(best);
            point.push_back(i);
        }
    }
    const std::size_t total = owner.size();
    // Counting sort by owner, stable in point order (deterministic).
    out.start.assign(tiles + 1, 0);
    for (std::uint32_t o : owner)
        ++out.start[o + 1];
    for (std::uint32_t k = 0; k < tiles; ++k)
        out.start[k + 1] += out.start[k];
    out.order.resize(total);
    std::vector<std::uint32_t> fill(out.start.begin(), out.start.end() - 1);
    for (std::size_t i = 0; i < total; ++i)
        out.order[fill[owner[i]]++] = point[i];
    return out;
}

// Whether the sampled surface runs from cell a into cell b: some point of one cell within `reach` of
// their bisector plane lies within `near` of some point of the other. The bisector test alone cannot
// tell the two sides of a thin wall apart: the bisector of an outer and an inner centre set apart along
// the wall crosses both sides, so each cell has points at it, but on its own side. (A sphere shell 3
// point spacings thick, 100,000 points, meshed in 109 pieces with 110 loops, 1.2% of the diagonal from
// its points on average.) Checked only for tiles facing the same way (kSameFacingDegrees): two faces of
// an edge are no two sides of a wall. A pair of neighbours has witnesses all along its border, so the
// first ones asked usually settle it; only cells that do not meet are scanned whole.
bool meet_on_surface(const Hierarchy& h, const Partition& part, const std::vector<Vec3>& centres, std::uint32_t a,
                     std::uint32_t b, double reach, double near)
{
    const double gap = distance(centres[a], centres[b]);
    if (!(gap > 0.0))
        return true;
    const double near2 = near * near;
    for (const auto& [cell, other] : {std::pair{a, b}, std::pair{b, a}})
        for (std::uint32_t k = part.start[cell]; k < part.start[cell + 1]; ++k) {
            const Vec3& p = h.cloud.positions[part.order[k]];
            if ((squared_distance(p, centres[other]) - squared_distance(p, centres[cell])) / (2.0 * gap) > reach)
                continue; // no witness: farther from the bisector
            for (std::uint32_t m = part.start[other]; m < part.start[other + 1]; ++m)
                if (squared_distance(p, h.cloud.positions[part.order[m]]) <= near2)
                    return true;
        }
    return false;
}

} // namespace

void check_tile_options(const TileOptions& options)
{
    // Finite too: an infinite tolerance dropped every hull point, and mesh_cut then blamed the cut
    // ("no tile has three non-collinear points; choose a coarser cut").
    if (!(options.collinear_tolerance >= 0.0) || !std::isfinite(options.collinear_tolerance))
        throw InvalidInput("TileOptions::collinear_tolerance must be a finite number >= 0");
    if (!(options.adjacency_factor >= 0.0))
        throw InvalidInput("TileOptions::adjacency_factor must be >= 0");
    if (!(options.meet_factor >= 0.0))
        throw InvalidInput("TileOptions::meet_factor must be >= 0");
    if (!std::isfinite(options.plane_axis.x) || !std::isfinite(options.plane_axis.y) || !std::isfinite(options.plane_axis.z))
        throw InvalidInput("TileOptions::plane_axis must be finite");
}

std::vector<std::uint32_t> node_hull(const Hierarchy& h, std::int32_t node)
{
    check_node(h, node);
    const auto k = static_cast<std::size_t>(node);
    if (hull_stored(h, k))
        return {h.hull_points.begin() + static_cast<std::ptrdiff_t>(h.hull_start[k]),
                h.hull_points.begin() + static_cast<std::ptrdiff_t>(h.hull_start[k + 1])};
    std::vector<Projected> scratch;
    return hull_from_points(h, h.nodes[k], scratch);
}

void compute_node_hulls(const Hierarchy& h, std::vector<std::size_t>& start, std::vector<std::uint32_t>& points,
                        std::size_t threads)
{
    const std::size_t count = h.nodes.size();
    std::vector<std::vector<std::uint32_t>> hulls(count);
    // Blocks of 64 nodes: a large node's hull costs a pass over its points, a small one nothing.
    run_parallel_ranges(count, 64, threads, [&](std::size_t begin, std::size_t end) {
        std::vector<Projected> scratch;
        for (std::size_t k = begin; k < end; ++k) {
            const Node& n = h.nodes[k];
            // (A range outside the points, which load_model refuses, is skipped: save_model calls
            // this before it would find out.)
            if (n.count() > kHullStoredAbove && n.begin < n.end && n.end <= h.cloud.positions.size())
                hulls[k] = hull_from_points(h, n, scratch);
        }
    });
    start.assign(count + 1, 0);
    points.clear();
    for (std::size_t k = 0; k < count; ++k) {
        points.insert(points.end(), hulls[k].begin(), hulls[k].end());
        start[k + 1] = points.size();
    }
}

void set_node_hulls(Hierarchy& h, std::size_t threads)
{
    compute_node_hulls(h, h.hull_start, h.hull_points, threads);
}

Tile make_tile(const Hierarchy& h, std::int32_t node, const TileOptions& options)
{
    // Checked here too: refine_mesh builds its pseudo tiles with make_tile alone, and a NaN
    // collinear_tolerance overflowed an integer in its hull (undefined behaviour).
    check_tile_options(options);
    check_node(h, node);
    const std::vector<std::uint32_t> indices = node_sample(h, node, options.max_points);
    return tile_from_points(h, node, indices.data(), indices.size(), options);
}

std::vector<Tile> make_tiles(const Hierarchy& h, const std::vector<std::int32_t>& cut, const TileOptions& options)
{
    check_tile_options(options);
    for (std::int32_t node : cut)
        check_node(h, node);
    std::vector<Tile> tiles;
    tiles.reserve(cut.size());
    if (!options.voronoi_trim || cut.size() < 2) {
        for (std::int32_t node : cut)
            tiles.push_back(make_tile(h, node, options));
        return tiles;
    }
    // Height-field mode partitions in the plane: cells that do not overlap seen along the axis, so
    // that neither do the tiles' hulls (a ground cell beside a wall otherwise took in wall points and
    // reached under the roof's edge).
    const PartitionSpace space = partition_space(options);
    std::vector<Vec3> centres;
    for (std::int32_t node : cut)
        centres.push_back(space(h.nodes[static_cast<std::size_t>(node)].moments.mean));
    const std::vector<std::vector<std::uint32_t>> graph = delaunay_graph(centres);
    const Partition part = voronoi_partition(h, cut, centres, graph, options.max_points, space);
    // In a scan seen from one viewpoint, a neighbouring node's points of a cell far off the tile's
    // plane are another surface across a depth jump (a ball's underside and the floor behind it, in
    // a depth camera's view), and the hull would join the two. Only there: in merged scans the points
    // off the plane are as often the same surface seen twice, a little misregistered (bun.conf at
    // 0.002 lost a 70-face strip to them).
    const bool single_view = h.cloud.viewpoint.has_value();
    std::vector<std::uint32_t> own;
    for (std::size_t k = 0; k < cut.size(); ++k) {
        const std::uint32_t* cell = part.order.data() + part.start[k];
        const std::size_t size = part.start[k + 1] - part.start[k];
        tiles.push_back(tile_from_points(h, cut[k], cell, size, options));
        const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
        const bool own_node_only = tiles.back().coverage_gap > 0.0;
        if (!own_node_only && !single_view)
            continue;
        const double off_plane = kForeignPlaneFactor * std::max(n.max_plane_distance, tiles.back().spacing());
        own.clear();
        for (std::size_t i = 0; i < size; ++i)
            if ((cell[i] >= n.begin && cell[i] < n.end) ||
                (!own_node_only && std::abs(dot(h.cloud.positions[cell[i]] - n.moments.mean, n.frame.vectors[0])) <= off_plane))
                own.push_back(cell[i]);
        // The cell took in points across a hole from a neighbouring node (coverage_gap), or from
        // another surface: the tile keeps its own node's points of the cell, and the others near its
        // plane (a subset of a convex cell, so it still overlaps no other tile; the gap triangulation
        // covers the points it leaves out).
        if (own.size() < size && own.size() >= 3)
            tiles.back() = tile_from_points(h, cut[k], own.data(), own.size(), options);
    }
    // Surface neighbours: witnessed from either side within the larger of the two spacings, and with
    // TileOptions::meet_factor, where they face the same way, met by the surface (not across a thin
    // wall; see meet_on_surface).
    const double same_facing = std::cos(radians(kSameFacingDegrees));
    for (std::uint32_t k = 0; k < cut.size(); ++k)
        for (std::size_t j = 0; j < graph[k].size(); ++j) {
            const std::uint32_t other = graph[k][j];
            const double spacing = std::max(tiles[k].spacing(), tiles[other].spacing());
            const double reach = options.adjacency_factor * spacing;
            if (part.closest[k][j] <= reach &&
                (space.flat || options.meet_factor == 0.0 || std::abs(dot(tiles[k].normal, tiles[other].normal)) < same_facing ||
                 meet_on_surface(h, part, centres, k, other, reach, options.meet_factor * spacing))) {
                tiles[k].neighbours.push_back(other);
                tiles[other].neighbours.push_back(k);
            }
        }
    for (Tile& t : tiles) {
        std::sort(t.neighbours.begin(), t.neighbours.end());
        t.neighbours.erase(std::unique(t.neighbours.begin(), t.neighbours.end()), t.neighbours.end());
    }
    return tiles;
}

std::vector<Tile> make_tiles(const Hierarchy& h, const std::vector<std::int32_t>& cut, const TileOptions& options,
                             const std::vector<bool>& fanless)
{
    if (fanless.size() != cut.size())
        throw InvalidInput("make_tiles: one fanless flag per cut entry expected, got " + std::to_string(fanless.size()) +
                           " for " + std::to_string(cut.size()));
    std::vector<std::int32_t> kept;
    std::vector<std::size_t> position; // in `cut`, of each kept entry
    for (std::size_t k = 0; k < cut.size(); ++k)
        if (!fanless[k]) {
            kept.push_back(cut[k]);
            position.push_back(k);
        }
    if (kept.size() == cut.size())
        return make_tiles(h, cut, options);
    for (std::int32_t node : cut)
        check_node(h, node);
    std::vector<Tile> built = kept.empty() ? std::vector<Tile>{} : make_tiles(h, kept, options);
    std::vector<Tile> tiles(cut.size());
    for (std::size_t j = 0; j < built.size(); ++j) {
        for (std::uint32_t& n : built[j].neighbours)
            n = static_cast<std::uint32_t>(position[n]); // still ascending: positions grow with j
        tiles[position[j]] = std::move(built[j]);
    }
    for (std::size_t k = 0; k < cut.size(); ++k)
        if (fanless[k]) {
            const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
            Tile& t = tiles[k];
            t.node = cut[k];
            t.centre = t.apex = n.moments.mean;
            t.normal = n.frame.vectors[0];
            t.axis_u = n.frame.vectors[2];
            t.axis_v = cross(t.normal, t.axis_u);
            t.fanless = true;
        }
    return tiles;
}

} // namespace mrt
