// Coverage gaps, our addition to paper §4.2: the paper's tile is the convex hull of a nearly planar
// cluster, which is exact for a convex patch of surface but covers every hole and notch of a flat one
// (the paper's clusters are split by flatness alone, so a flat plate with holes is one tile). This
// measures how far a tile reaches over unsampled surface, so that the build can split such clusters
// and cuts can refine them. A grid is used rather than a Delaunay triangulation's empty circles
// because it also gives the density around each empty region, which is what tells a hole from the
// sparse side of an uneven sample (range scans thin out with distance).
#include "libmrtile/coverage_gap.h"

#include "libmrtile/errors.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace mrt {
namespace {

struct P2
{
    double x, y;
};

double cross2(const P2& o, const P2& a, const P2& b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

bool x_then_y(const P2& a, const P2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

// Sorts by x, then y: a counting sort into about one column per 4 points (they are spread over their
// x range), then each column on its own. The sort is most of a judgement's cost.
void sort_x_then_y(std::vector<P2>& pts)
{
    const std::size_t n = pts.size();
    if (n < 64) {
        std::sort(pts.begin(), pts.end(), x_then_y);
        return;
    }
    double lo = pts[0].x, hi = lo;
    for (const P2& p : pts) {
        lo = std::min(lo, p.x);
        hi = std::max(hi, p.x);
    }
    const std::size_t columns = n / 4;
    const double scale = hi > lo ? static_cast<double>(columns) / (hi - lo) : 0.0;
    auto column = [&](const P2& p) { return std::min(columns - 1, static_cast<std::size_t>((p.x - lo) * scale)); };
    std::vector<std::size_t> start(columns + 1, 0);
    for (const P2& p : pts)
        ++start[column(p) + 1];
    for (std::size_t c = 0; c < columns; ++c)
        start[c + 1] += start[c];
    std::vector<P2> sorted(n);
    std::vector<std::size_t> next(start.begin(), start.end() - 1);
    for (const P2& p : pts)
        sorted[next[column(p)]++] = p;
    for (std::size_t c = 0; c < columns; ++c)
        std::sort(sorted.begin() + static_cast<std::ptrdiff_t>(start[c]), sorted.begin() + static_cast<std::ptrdiff_t>(start[c + 1]), x_then_y);
    pts = std::move(sorted);
}

// Andrew's monotone chain; counter-clockwise, collinear points dropped. `pts` is sorted in place.
std::vector<P2> convex_hull(std::vector<P2>& pts)
{
    sort_x_then_y(pts);
    std::vector<P2> hull(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0)
            --k;
        hull[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0)
            --k;
        hull[k++] = pts[i];
    }
    hull.resize(k > 0 ? k - 1 : 0);
    return hull;
}

// Squared distances along one line of the grid to the nearest source (f = 0 at sources, +inf
// elsewhere, or the squared distances of the previous pass): the lower envelope of parabolas of
// Felzenszwalb and Huttenlocher, exact and linear.
void distance_1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v, std::vector<double>& z)
{
    const int n = static_cast<int>(f.size());
    const double inf = std::numeric_limits<double>::infinity();
    int k = -1;
    for (int q = 0; q < n; ++q) {
        if (f[q] == inf)
            continue;
        for (;;) {
            if (k < 0) {
                v[0] = q;
                z[0] = -inf;
                z[1] = inf;
                k = 0;
                break;
            }
            const double s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
            if (s <= z[k]) {
                --k;
                continue;
            }
            ++k;
            v[k] = q;
            z[k] = s;
            z[k + 1] = inf;
            break;
        }
    }
    if (k < 0) {
        std::fill(d.begin(), d.end(), inf);
        return;
    }
    int j = 0;
    for (int q = 0; q < n; ++q) {
        while (z[j + 1] < q)
            ++j;
        d[q] = double(q - v[j]) * (q - v[j]) + f[v[j]];
    }
}

// The grid of a judgement, for CoverageMap: which cells lie in a counted empty region.
struct GapGrid
{
    double x0 = 0, y0 = 0, g = 1;
    int nx = 0, ny = 0;
    std::vector<float> counted; // the radius of the counted region a cell lies in, 0 for none
    std::vector<std::uint32_t> centre; // per counted cell: its region's cell farthest from the points
};

// The points less all but one of each clump of points within `resolution` of each other (grid keys).
std::vector<P2> distinct(const std::vector<P2>& pts, double resolution)
{
    std::vector<std::pair<std::pair<std::int64_t, std::int64_t>, std::size_t>> keys;
    keys.reserve(pts.size());
    const double limit = 1e15; // keys beyond it would not fit 64 bits: such a point stays (key of its own)
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const double kx = std::floor(pts[i].x / resolution), ky = std::floor(pts[i].y / resolution);
        if (std::abs(kx) < limit && std::abs(ky) < limit)
            keys.push_back({{static_cast<std::int64_t>(kx), static_cast<std::int64_t>(ky)}, i});
        else
            keys.push_back({{std::numeric_limits<std::int64_t>::max(), static_cast<std::int64_t>(i)}, i});
    }
    std::sort(keys.begin(), keys.end());
    std::vector<P2> out;
    for (std::size_t i = 0; i < keys.size(); ++i)
        if (i == 0 || keys[i].first != keys[i - 1].first)
            out.push_back(pts[keys[i].second]);
    return out;
}

double gap_of_projected(std::vector<P2> pts, std::vector<P2> fill, const CoverageOptions& o, GapGrid* out = nullptr)
{
    if (pts.size() < 8)
        return 0.0;
    double x0 = pts[0].x, x1 = x0, y0 = pts[0].y, y1 = y0;
    for (const P2& p : pts) {
        x0 = std::min(x0, p.x);
        x1 = std::max(x1, p.x);
        y0 = std::min(y0, p.y);
        y1 = std::max(y1, p.y);
    }
    const std::vector<P2> hull = convex_hull(pts); // sorts pts, whose order does not matter
    double area = 0.0;
    for (std::size_t i = 0; i < hull.size(); ++i) {
        const P2& a = hull[i];
        const P2& b = hull[(i + 1) % hull.size()];
        area += a.x * b.y - a.y * b.x;
    }
    area *= 0.5;
    if (hull.size() < 3 || !(area > 0))
        return 0.0;
    // Density is that of distinct positions: clumps of near-equal points (repeated frames of one view,
    // a cloud concatenated with itself) count once, as in Tile::distinct_points, or every gap between
    // clumps would look like a hole at the clumps' inflated density.
    // Only looked for where points sorted by x (the hull's order) have near-equal neighbours: in a
    // sample without clumps hardly any do, and the sort costs as much as the rest.
    const double resolution = 0.01 * std::sqrt(area / static_cast<double>(pts.size()));
    std::size_t near_equal = 0;
    for (std::size_t i = 1; i < pts.size(); ++i)
        near_equal += std::abs(pts[i].x - pts[i - 1].x) < resolution && std::abs(pts[i].y - pts[i - 1].y) < resolution ? 1 : 0;
    // (Grid keys must fit 64 bits: a sliver of almost no area has a vanishing resolution.)
    const double extent = std::max({std::abs(x0), std::abs(x1), std::abs(y0), std::abs(y1)});
    if (near_equal * 100 > pts.size() && extent < 1e15 * resolution) {
        pts = distinct(pts, resolution);
        fill = distinct(fill, resolution);
    }
    const std::size_t m = pts.size();
    if (m < 8)
        return 0.0;

    double g = std::sqrt(o.points_per_cell * area / static_cast<double>(m));
    // A thin diagonal patch has a bounding box far larger than its hull: bound the cells by the points.
    const double max_cells = 64.0 * static_cast<double>(m) + 64.0;
    const double cells_wanted = ((x1 - x0) / g + 1.0) * ((y1 - y0) / g + 1.0);
    if (cells_wanted > max_cells)
        g *= std::sqrt(cells_wanted / max_cells);
    const int nx = static_cast<int>((x1 - x0) / g) + 1, ny = static_cast<int>((y1 - y0) / g) + 1;
    if (nx < 3 || ny < 3)
        return 0.0; // no cell can be enclosed
    if (out) {
        out->x0 = x0;
        out->y0 = y0;
        out->g = g;
        out->nx = nx;
        out->ny = ny;
        out->counted.assign(static_cast<std::size_t>(nx) * ny, 0);
        out->centre.assign(static_cast<std::size_t>(nx) * ny, 0);
    }
    const auto cell = [nx](int i, int j) { return static_cast<std::size_t>(j) * nx + i; };
    // Points per cell, and the points of each cell (cell_start / cell_points, counting sort) to measure
    // a region's radius exactly. Points of other clusters (fill) that project into the grid occupy
    // cells without widening the hull.
    std::vector<std::uint32_t> count(static_cast<std::size_t>(nx) * ny, 0);
    std::vector<P2> all;
    std::vector<std::size_t> cell_of;
    all.reserve(pts.size() + fill.size());
    for (const P2& p : pts) {
        const int i = std::min(nx - 1, static_cast<int>((p.x - x0) / g));
        const int j = std::min(ny - 1, static_cast<int>((p.y - y0) / g));
        all.push_back(p);
        cell_of.push_back(cell(i, j));
    }
    for (const P2& p : fill) {
        const double fi = (p.x - x0) / g, fj = (p.y - y0) / g;
        if (fi >= 0 && fj >= 0 && fi < nx && fj < ny) {
            all.push_back(p);
            cell_of.push_back(cell(static_cast<int>(fi), static_cast<int>(fj)));
        }
    }
    for (const std::size_t c : cell_of)
        ++count[c];
    std::vector<std::size_t> cell_start(count.size() + 1, 0);
    for (std::size_t c = 0; c < count.size(); ++c)
        cell_start[c + 1] = cell_start[c] + count[c];
    std::vector<std::uint32_t> cell_points(all.size());
    {
        std::vector<std::size_t> next(cell_start.begin(), cell_start.end() - 1);
        for (std::size_t k = 0; k < all.size(); ++k)
            cell_points[next[cell_of[k]]++] = static_cast<std::uint32_t>(k);
    }
    // Exact distance from the centre of cell c to the nearest point, knowing it is within `reach` cells.
    const auto nearest_point = [&](std::size_t c, int reach) {
        const int ci = static_cast<int>(c % nx), cj = static_cast<int>(c / nx);
        const double x = x0 + (ci + 0.5) * g, y = y0 + (cj + 0.5) * g;
        double best = std::numeric_limits<double>::infinity();
        for (int j = std::max(0, cj - reach); j <= std::min(ny - 1, cj + reach); ++j)
            for (int i = std::max(0, ci - reach); i <= std::min(nx - 1, ci + reach); ++i) {
                const std::size_t k = cell(i, j);
                for (std::size_t q = cell_start[k]; q < cell_start[k + 1]; ++q) {
                    const P2& p = all[cell_points[q]];
                    best = std::min(best, (p.x - x) * (p.x - x) + (p.y - y) * (p.y - y));
                }
            }
        return std::sqrt(best);
    };

    // Cells whose centre lies inside the hull: per row, the hull's x-interval at the centre's height.
    std::vector<char> inside(count.size(), 0);
    for (int j = 0; j < ny; ++j) {
        const double y = y0 + (j + 0.5) * g;
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::size_t e = 0; e < hull.size(); ++e) {
            const P2& a = hull[e];
            const P2& b = hull[(e + 1) % hull.size()];
            if (a.y == b.y) {
                if (a.y == y) {
                    lo = std::min({lo, a.x, b.x});
                    hi = std::max({hi, a.x, b.x});
                }
            } else if ((a.y <= y && y <= b.y) || (b.y <= y && y <= a.y)) {
                const double x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
                lo = std::min(lo, x);
                hi = std::max(hi, x);
            }
        }
        for (int i = 0; i < nx; ++i) {
            const double x = x0 + (i + 0.5) * g;
            inside[cell(i, j)] = x >= lo && x <= hi;
        }
    }

    // Squared distance (in cells) of every cell centre to the nearest occupied cell's centre.
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> dist(count.size());
    {
        const int n = std::max(nx, ny);
        std::vector<double> f(static_cast<std::size_t>(n)), d(static_cast<std::size_t>(n)), z(static_cast<std::size_t>(n) + 1);
        std::vector<int> v(static_cast<std::size_t>(n));
        f.resize(static_cast<std::size_t>(nx));
        d.resize(static_cast<std::size_t>(nx));
        for (int j = 0; j < ny; ++j) {
            for (int i = 0; i < nx; ++i)
                f[static_cast<std::size_t>(i)] = count[cell(i, j)] > 0 ? 0.0 : inf;
            distance_1d(f, d, v, z);
            for (int i = 0; i < nx; ++i)
                dist[cell(i, j)] = d[static_cast<std::size_t>(i)];
        }
        f.resize(static_cast<std::size_t>(ny));
        d.resize(static_cast<std::size_t>(ny));
        for (int i = 0; i < nx; ++i) {
            for (int j = 0; j < ny; ++j)
                f[static_cast<std::size_t>(j)] = dist[cell(i, j)];
            distance_1d(f, d, v, z);
            for (int j = 0; j < ny; ++j)
                dist[cell(i, j)] = d[static_cast<std::size_t>(j)];
        }
    }

    // Regions of empty inside cells (4-connected), each judged by the density of the surface around it:
    // the points per inside cell two cells away, since the hole's own border cuts through the adjacent
    // ones and they hold fewer points than the surface around (the adjacent ones, if there are none
    // further out). Empty cells count too: points on lines around an empty face (a CAD part's
    // vertices along its edges) are no sign of a hole, and area density tells them from a sampled
    // surface around one.
    const double fraction = std::clamp(o.sample_fraction, 0.0, 1.0);
    const double min_radius = std::max(o.min_radius_spacings * std::sqrt(fraction), std::min(o.min_sample_radius_spacings, o.min_radius_spacings));
    const auto in_grid = [nx, ny](int i, int j) { return i >= 0 && j >= 0 && i < nx && j < ny; };

    // The regions (stamp: 1-based region of an empty inside cell), with their cells and largest
    // squared distance.
    std::vector<std::uint32_t> stamp(count.size(), 0);
    std::vector<std::vector<std::size_t>> regions;
    std::vector<double> largest;
    std::vector<std::size_t> farthest; // the cell of each region farthest from the occupied cells
    std::vector<std::size_t> stack;
    for (std::size_t start = 0; start < count.size(); ++start) {
        if (count[start] > 0 || !inside[start] || stamp[start] != 0)
            continue;
        const auto region = static_cast<std::uint32_t>(regions.size() + 1);
        regions.emplace_back();
        std::vector<std::size_t>& members = regions.back();
        double far = 0.0;
        std::size_t far_cell = start;
        stamp[start] = region;
        stack.assign(1, start);
        while (!stack.empty()) {
            const std::size_t c = stack.back();
            stack.pop_back();
            members.push_back(c);
            if (dist[c] > far) {
                far = dist[c];
                far_cell = c;
            }
            const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
            const int next[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
            for (const auto& q : next) {
                if (!in_grid(q[0], q[1]))
                    continue;
                const std::size_t k = cell(q[0], q[1]);
                if (count[k] == 0 && inside[k] && stamp[k] == 0) {
                    stamp[k] = region;
                    stack.push_back(k);
                }
            }
        }
        largest.push_back(far);
        farthest.push_back(far_cell);
    }

    // Points inside a region: groups of occupied cells (8-connected) whose every empty neighbour
    // belongs to one region. A hole holds none (or a stray few); the sparse middle of an unevenly
    // sampled surface (a remeshed part's flat face between dense curved rims) is a region around
    // many such islands, not a hole.
    std::vector<double> island_points(regions.size() + 1, 0.0);
    {
        std::vector<char> seen(count.size(), 0);
        std::vector<std::size_t> group;
        for (std::size_t start = 0; start < count.size(); ++start) {
            if (count[start] == 0 || seen[start])
                continue;
            seen[start] = 1;
            stack.assign(1, start);
            group.clear();
            std::uint32_t around = 0; // the one region around the group; kNone-like when several or open
            bool enclosed = true;
            double points = 0.0;
            while (!stack.empty()) {
                const std::size_t c = stack.back();
                stack.pop_back();
                group.push_back(c);
                points += count[c];
                const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
                for (int dj = -1; dj <= 1; ++dj)
                    for (int di = -1; di <= 1; ++di) {
                        if (di == 0 && dj == 0)
                            continue;
                        if (!in_grid(i + di, j + dj)) {
                            enclosed = false;
                            continue;
                        }
                        const std::size_t k = cell(i + di, j + dj);
                        if (count[k] > 0) {
                            if (!seen[k]) {
                                seen[k] = 1;
                                stack.push_back(k);
                            }
                        } else if (di == 0 || dj == 0) {
                            if (stamp[k] == 0 || (around != 0 && stamp[k] != around))
                                enclosed = false;
                            else
                                around = stamp[k];
                        }
                    }
            }
            if (enclosed && around != 0)
                island_points[around] += points;
        }
    }

    // Each region judged by the density of the surface around it: the points per inside cell next to
    // it and two cells away, whichever is lower (the border of a hole cuts through the cells next to
    // it, so they underestimate the density: the test errs on the side of no hole). Empty cells
    // count too: points on lines around an empty face (a CAD part's vertices along its edges) are no
    // sign of a hole, and area density tells them from a sampled surface around one.
    double gap = 0.0;
    std::vector<std::uint32_t> ring_stamp(count.size(), 0); // 2r: next to region r; 2r + 1: two away
    for (std::uint32_t region = 1; region <= regions.size(); ++region) {
        const std::vector<std::size_t>& members = regions[region - 1];
        const double far = largest[region - 1];
        if (!std::isfinite(far))
            continue;
        std::size_t near_cells = 0, far_cells = 0;
        double near_points = 0.0, far_points = 0.0;
        for (int pass = 1; pass <= 2; ++pass)
            for (const std::size_t c : members) {
                const int i = static_cast<int>(c % nx), j = static_cast<int>(c / nx);
                for (int dj = -pass; dj <= pass; ++dj)
                    for (int di = -pass; di <= pass; ++di) {
                        const int a = i + di, b = j + dj;
                        if (std::max(std::abs(di), std::abs(dj)) != pass || !in_grid(a, b))
                            continue;
                        const std::size_t k = cell(a, b);
                        if (!inside[k] || stamp[k] == region || ring_stamp[k] >= 2 * region)
                            continue;
                        ring_stamp[k] = 2 * region + (pass == 2 ? 1 : 0);
                        (pass == 1 ? near_cells : far_cells) += 1;
                        (pass == 1 ? near_points : far_points) += count[k];
                    }
            }
        if (near_cells == 0)
            continue;
        // The lower of the two: where the density jumps (a face sampled ten times more densely beside
        // a sparse one, both in one cluster across an edge) the cells further out can lie in the dense
        // part, and the sparse part would look empty.
        const double near_density = near_points / static_cast<double>(near_cells);
        const double per_cell = far_cells > 0 ? std::min(near_density, far_points / static_cast<double>(far_cells)) : near_density;
        const double spacing = g / std::sqrt(per_cell);
        // The distance of the farthest cell's centre to the nearest point itself (cell centres are up to
        // 0.7 cells from their points).
        const double radius = nearest_point(farthest[region - 1], static_cast<int>(std::ceil(std::sqrt(far))) + 1);
        const double missing = per_cell * static_cast<double>(members.size());
        if (radius >= min_radius * spacing && missing >= o.min_missing_points &&
            island_points[region] <= 2.0 + o.max_island_share * missing) {
            gap = std::max(gap, radius);
            if (out)
                for (const std::size_t c : members) {
                    out->counted[c] = static_cast<float>(radius);
                    out->centre[c] = static_cast<std::uint32_t>(farthest[region - 1]);
                }
        }
    }
    return gap;
}

P2 project(const Vec3& p, const Vec3& origin, const Vec3& u, const Vec3& v)
{
    const Vec3 d = p - origin;
    return {dot(d, u), dot(d, v)};
}

} // namespace

CoverageMap::CoverageMap(const std::vector<Vec3>& points, const Vec3& axis_u, const Vec3& axis_v, const CoverageOptions& options)
    : u_(axis_u), v_(axis_v)
{
    if (points.empty())
        return;
    origin_ = points[0];
    std::vector<P2> pts;
    pts.reserve(points.size());
    for (const Vec3& p : points)
        pts.push_back(project(p, origin_, u_, v_));
    GapGrid grid;
    gap_ = gap_of_projected(std::move(pts), {}, options, &grid);
    x0_ = grid.x0;
    y0_ = grid.y0;
    g_ = grid.g;
    nx_ = grid.nx;
    ny_ = grid.ny;
    counted_ = std::move(grid.counted);
    centre_ = std::move(grid.centre);
}

std::size_t CoverageMap::gap_cell(const Vec3& p, double min_radius) const
{
    if (counted_.empty())
        return kNoCell;
    const P2 q = project(p, origin_, u_, v_);
    const double fi = (q.x - x0_) / g_, fj = (q.y - y0_) / g_;
    if (!(fi >= 0 && fj >= 0 && fi < nx_ && fj < ny_))
        return kNoCell;
    const std::size_t c = static_cast<std::size_t>(static_cast<int>(fj)) * static_cast<std::size_t>(nx_) +
                          static_cast<std::size_t>(static_cast<int>(fi));
    const float radius = counted_[c];
    return radius > 0.0f && radius >= min_radius ? c : kNoCell;
}

bool CoverageMap::in_gap(const Vec3& p, double min_radius) const { return gap_cell(p, min_radius) != kNoCell; }

bool CoverageMap::gap_disc(const Vec3& p, double min_radius, Vec3& centre, double& radius) const
{
    const std::size_t c = gap_cell(p, min_radius);
    if (c == kNoCell)
        return false;
    const P2 q = project(p, origin_, u_, v_);
    const std::size_t far = centre_[c];
    const double x = x0_ + (static_cast<double>(far % static_cast<std::size_t>(nx_)) + 0.5) * g_;
    const double y = y0_ + (static_cast<double>(far / static_cast<std::size_t>(nx_)) + 0.5) * g_;
    centre = p + u_ * (x - q.x) + v_ * (y - q.y);
    radius = counted_[c];
    return true;
}

constexpr std::size_t kMaxBucketedValues = std::size_t{1} << 20;

WidestGap widest_gap(std::vector<double> values)
{
    WidestGap out;
    if (values.size() < 2)
        return out;
    const auto [lo_it, hi_it] = std::minmax_element(values.begin(), values.end());
    const double lo = *lo_it, hi = *hi_it;
    out.extent = hi - lo;
    out.from = lo;
    if (!(hi > lo))
        return out;
    // Pigeonholes: 2n buckets over [lo, hi]. The bucket of a value never decreases as the value grows
    // (every operation below rounds monotonically), so the buckets in turn hold the values in sorted
    // order, each bucket's unordered. A gap inside a bucket is under its width, range / 2n, less than
    // half the smallest widest gap there can be, range / (n - 1): so the widest gap, and every gap as
    // wide, runs from one non-empty bucket's largest value to the next one's smallest, and scanning
    // the buckets upwards meets them as the sorted scan does.
    const std::size_t n = values.size();
    if (n > kMaxBucketedValues) { // the buckets would take 4x the values' memory: sort them in place
        std::sort(values.begin(), values.end());
        for (std::size_t i = 1; i < n; ++i)
            if (values[i] - values[i - 1] > out.width) {
                out.width = values[i] - values[i - 1];
                out.from = values[i - 1];
            }
        return out;
    }
    const std::size_t buckets = 2 * n;
    const double scale = static_cast<double>(buckets) / (hi - lo);
    std::vector<double> low(buckets, std::numeric_limits<double>::infinity());
    std::vector<double> high(buckets, -std::numeric_limits<double>::infinity());
    for (const double v : values) {
        const auto b = std::min(buckets - 1, static_cast<std::size_t>((v - lo) * scale));
        low[b] = std::min(low[b], v);
        high[b] = std::max(high[b], v);
    }
    double previous = high[0]; // bucket 0 holds lo
    for (std::size_t b = 1; b < buckets; ++b) {
        if (!(low[b] <= high[b]))
            continue; // empty
        if (low[b] - previous > out.width) {
            out.width = low[b] - previous;
            out.from = previous;
        }
        previous = high[b];
    }
    return out;
}

double separation_gap(const std::vector<Vec3>& points, const Vec3& axis_u, const Vec3& axis_v, double min_width,
                      const CoverageOptions& options, const std::vector<Vec3>& fill)
{
    if (points.size() < 8 || !(min_width > 0))
        return 0.0;
    double widest = 0.0;
    for (int axis = 0; axis < 2; ++axis) {
        const Vec3& along = axis == 0 ? axis_u : axis_v;
        const Vec3& across = axis == 0 ? axis_v : axis_u;
        std::vector<double> values;
        values.reserve(points.size());
        double lo = dot(points[0], across), hi = lo;
        for (const Vec3& p : points) {
            values.push_back(dot(p, along));
            lo = std::min(lo, dot(p, across));
            hi = std::max(hi, dot(p, across));
        }
        const WidestGap gap = widest_gap(std::move(values));
        const double strip = gap.width, from = gap.from, extent = gap.extent;
        if (!(strip > 0.25 * extent) || !(strip > min_width))
            continue;
        std::size_t inside = 0;
        for (const Vec3& p : fill) {
            const double a = dot(p, along), c = dot(p, across);
            inside += a > from && a < from + strip && c >= lo && c <= hi ? 1 : 0;
        }
        if (static_cast<double>(inside) <= 2.0 + options.max_island_share * static_cast<double>(points.size()))
            widest = std::max(widest, strip);
    }
    return 0.5 * widest;
}

std::size_t coverage_stride(std::size_t count, const CoverageOptions& options)
{
    return options.max_points > 0 && count > options.max_points ? (count + options.max_points - 1) / options.max_points : 1;
}

namespace {

// A NaN point, axis or option made the grid or the hole test NaN, and the gap came out 0 (no hole)
// without a word; set_coverage_gaps clamped a NaN sample_fraction (QA round 51).
void check_coverage_options(const CoverageOptions& options)
{
    if (!(options.points_per_cell > 0.0) || !std::isfinite(options.points_per_cell) || !(options.min_radius_spacings >= 0.0) ||
        !std::isfinite(options.min_radius_spacings) || !(options.min_missing_points >= 0.0) ||
        !std::isfinite(options.min_missing_points) || !(options.sample_fraction >= 0.0 && options.sample_fraction <= 1.0) ||
        !(options.max_island_share >= 0.0) || !std::isfinite(options.max_island_share) ||
        !(options.min_sample_radius_spacings >= 0.0) || !std::isfinite(options.min_sample_radius_spacings))
        throw InvalidInput("CoverageOptions: points_per_cell must be finite and > 0, sample_fraction in [0, 1], the other "
                           "fields finite and >= 0");
}

} // namespace

double coverage_gap(const std::vector<Vec3>& points, const Vec3& axis_u, const Vec3& axis_v, const CoverageOptions& options,
                    const std::vector<Vec3>& fill)
{
    check_coverage_options(options);
    if (!is_finite(axis_u) || !is_finite(axis_v))
        throw InvalidInput("coverage_gap: the axes must be finite");
    for (const std::vector<Vec3>* set : {&points, &fill})
        for (std::size_t i = 0; i < set->size(); ++i)
            if (!is_finite((*set)[i]))
                throw InvalidInput(std::string("coverage_gap: ") + (set == &points ? "point " : "fill point ") +
                                   std::to_string(i) + " is not finite");
    if (points.empty())
        return 0.0;
    std::vector<P2> pts, extra;
    pts.reserve(points.size());
    extra.reserve(fill.size());
    const Vec3 origin = points[0];
    for (const Vec3& p : points)
        pts.push_back(project(p, origin, axis_u, axis_v));
    for (const Vec3& p : fill)
        extra.push_back(project(p, origin, axis_u, axis_v));
    return gap_of_projected(std::move(pts), extra, options);
}

namespace {

double node_gap(const Hierarchy& h, const Node& node, const CoverageOptions& options)
{
    CoverageOptions sampled = options;
    const std::size_t stride = coverage_stride(node.count(), options);
    sampled.sample_fraction = 1.0 / static_cast<double>(stride);
    std::vector<Vec3> points;
    points.reserve(node.count() / stride + 1);
    for (std::uint32_t i = node.begin; i < node.end; i += static_cast<std::uint32_t>(stride))
        points.push_back(h.cloud.positions[i]);
    const Vec3 u = node.frame.vectors[2], v = node.frame.vectors[1];
    const double gap = coverage_gap(points, u, v, sampled);
    // Other nodes' points can only make it smaller, and a gap no larger than the node's plane distance
    // changes no error (cut.h): the costly look at the neighbours is needed only beyond that.
    if (gap <= node.max_plane_distance)
        return gap;
    // Other nodes' points can lie inside this node's hull (a coarse node is a union of leaves and need
    // not be convex): look only where the hull is, within the node's thickness of its plane.
    const double thickness = node.max_plane_distance + 1e-9 * (h.scale > 0 ? h.scale : 1.0);
    const Vec3 pad{thickness, thickness, thickness};
    const BoundingBox box{node.box.min - pad, node.box.max + pad};
    std::vector<Vec3> fill;
    for (const std::uint32_t i : points_in_box(h, box, stride)) {
        const Vec3& p = h.cloud.positions[i];
        if ((i < node.begin || i >= node.end) && std::abs(dot(p - node.centre(), node.frame.vectors[0])) <= thickness)
            fill.push_back(p);
    }
    return coverage_gap(points, u, v, sampled, fill);
}

// Whether a node's least-spread direction is a surface's normal: it is not a line. A stretch of a scan
// line has no normal of its own (its least-spread direction is the noise's, or exactly zero across a
// straight profile), and two neighbouring stretches seemed to face each other across the empty strip
// between them: lines 15 of their spacings apart were holes of 4 spacings, every cut refined to pairs
// of stretches, and the surface came out in pieces (QA round 54: profiles 15:1 with range noise of
// 0.24 spacings, 9 pieces and 127 loops; a cylinder scanned in rings 19:1, 58 loops). A line spreads
// across less than half its spacing along it (noise under half a spacing); a strip two rows wide
// spreads as much as its spacing along it (two points per row step), and has the normal of its side:
// the narrow strips of a thin plate's two sides, which the rule below is for, still face each other
// (taking 2-3-row strips for lines too joined coarse cuts of uniform thin parts: a mug with 4-spacing
// walls at 0.01 went 1 -> 3 pieces, 46 -> 735 crossing pairs).
bool has_normal(const Node& n)
{
    constexpr double kLineWidthSpacings = 0.5;
    const LineSpread spread = line_spread(n); // an empty node, or one with no spread across, has none
    return spread.across > kLineWidthSpacings * spread.spacing_along;
}

} // namespace

// Two children whose boxes lie apart: the node's tile would span the space between them. Counted
// when wider than a quarter of the node's box diagonal (so that a node split across a little empty
// space is not) and than twice min_radius_spacings (two objects far apart in one cloud; two scan lines
// of one surface side by side stay under it) — or, where the children face each other across the
// space, than min_radius_spacings, the width of a hole the surface keeps open: the two sides of a thin
// plate, where a narrow strip of both is flat in the plane across the plate and coarse cuts kept it as
// a wall inside it (a plate 6.6 spacings thick at tolerance 0.01: 66 loops in 11 pieces, now 15 in one).
double children_separation(const Hierarchy& h, const Node& n, const CoverageOptions& options)
{
    constexpr double kMinShare = 0.25;
    const double kFacing = std::cos(30.0 * M_PI / 180.0); // children's normals this near the line between them
    if (n.is_leaf() || !(n.frame.values[1] > 0.0))
        return 0.0;
    const Node& l = h.nodes[static_cast<std::size_t>(n.left)];
    const Node& r = h.nodes[static_cast<std::size_t>(n.right)];
    const BoundingBox &a = l.box, &b = r.box;
    const double dx = std::max({0.0, a.min.x - b.max.x, b.min.x - a.max.x});
    const double dy = std::max({0.0, a.min.y - b.max.y, b.min.y - a.max.y});
    const double dz = std::max({0.0, a.min.z - b.max.z, b.min.z - a.max.z});
    const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
    // The spacing of the node's points over the disc its two largest eigenvalues span (a uniform disc
    // of radius R has λ = count R² / 4 along each of its axes).
    const double count = static_cast<double>(n.count());
    const double area = 4.0 * M_PI * std::sqrt(n.frame.values[2] * n.frame.values[1]) / count;
    const double spacing = std::sqrt(area / count);
    const Vec3 between = r.centre() - l.centre();
    const double length = norm(between);
    const bool facing = length > 0.0 && has_normal(l) && has_normal(r) &&
                        std::abs(dot(l.frame.vectors[0], between)) > kFacing * length &&
                        std::abs(dot(r.frame.vectors[0], between)) > kFacing * length;
    const double holes = (facing ? 1.0 : 2.0) * options.min_radius_spacings * spacing;
    return d > std::max(holes, kMinShare * n.box.diagonal()) ? d : 0.0;
}

void set_coverage_gaps(Hierarchy& h, std::size_t threads, const CoverageOptions& options)
{
    check_coverage_options(options);
    const std::size_t count = h.nodes.size();
    std::vector<double> gap(count, 0.0);
    run_parallel_ranges(count, 256, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            if (h.nodes[k].count() >= options.max_points)
                gap[k] = node_gap(h, h.nodes[k], options);
            gap[k] = std::max(gap[k], children_separation(h, h.nodes[k], options));
        }
    });
    for (std::size_t k = count; k-- > 0;) { // children come after their parents
        Node& node = h.nodes[k];
        node.coverage_gap = gap[k];
        if (!node.is_leaf())
            node.coverage_gap = std::max({node.coverage_gap, h.nodes[static_cast<std::size_t>(node.left)].coverage_gap,
                                          h.nodes[static_cast<std::size_t>(node.right)].coverage_gap});
    }
}

} // namespace mrt
