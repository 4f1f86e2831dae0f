// Reconstruction, paper §4.3 (Algorithm 2), made to always output a valid oriented 2-manifold (the
// paper's §6 "future work": remove all tetrahedra, insert no holes).
//
// Pipeline:
//  1. T1 fans and ε-splitting: every tile with a fan gets a centre vertex and its boundary loop, with
//     long edges split so that gap triangles are not long and skinny (§4.3).
//  2. Delaunay of the boundary points (gap_triangulation.h). With the tiles' surface neighbours
//     (Tile::neighbours, from the Voronoi partition in tiles.cpp) every tile triangulates its loop and
//     its neighbours' loops in 2D in its own plane; a triangle is a candidate only if every tile it
//     touches proposes it, so candidates are locally Delaunay on the surface and never fold. Without
//     neighbours: one 3D Delaunay of all boundary points; height fields: one 2D Delaunay on the axis
//     (§4.3). A triangle is pruned when all its vertices lie in one tile, when one of its edges joins two
//     non-adjacent points of a tile (it would cross the fan), when it joins tiles that do not meet on the
//     surface, or when it does not fit in a sphere of the local alpha radius b (§4.3).
//  3. Manifold extraction: the Delaunay triangles left are only candidates. The tiles are first
//     oriented consistently over their neighbour graph (Hoppe-style spanning tree; normals compared
//     through the reflection across the bisector of the centres, which works across sharp edges). An
//     advancing front, seeded with the largest tile's fan, accepts a candidate across a front edge only
//     if every half-edge is new (edges keep <= 2 faces with opposite orientation), every vertex stays a
//     set of fans whose union can still become a disk (never a closed fan plus another one), and the
//     face looks the way its tiles do; among valid candidates the one with the smallest radius relative
//     to b and the least turn from its neighbour wins (like Cohen-Steiner & Da's advancing front). A
//     tile's fan is placed, with its precomputed orientation, when the front first reaches its points.
//     Triangles proposed by only some of their tiles are fallback candidates: where the consensus front
//     strands tiles (thin features such as the bunny's ear tips, whose tiles would otherwise be dropped
//     and covered over), the front is resumed with the fallback candidates that touch them. A face
//     that would join two boundary loops of one piece adds a handle: fallback faces never do, and
//     consensus ones wait until everything else is placed (a torus still closes with its handle).
//  4. Holes are filled with a minimum-area triangulation of the loop whose faces look like the hole or
//     like the surface at their corners (every face checked as in 3) when they are gaps between tiles:
//     the loop touches only interior tiles (surrounded by neighbours), or its perimeter is small next to
//     its tiles, and it is not much wider than a point spacing (every point lies in a tile, so a hole
//     holds none: a wide one is a hole in the sample). Other loops are the sample's borders and holes
//     and stay open. A fill through a pinched vertex that would add a handle (counted locally with
//     Euler's formula) is refused and the hole widened. Islands are dropped, holes filled once more,
//     and islands put back where the rest of the surface does not cover their place (unless they are
//     a closed bubble). Widening can cut fans loose: the same is also tried after seeding the dropped
//     tiles again and growing the front into the widened holes (no handles); the way that leaves fewer
//     tiles out is kept. Vertices still pinched (two fans touching) are duplicated per fan.
//  5. The faces go into OpenMesh component by component in breadth-first order, so add_face always
//     attaches to an existing boundary; closed components are flipped to positive volume, open ones to
//     face the cloud's viewpoint when it has one (where the scanner stood), else up the axis (height
//     fields) or to positive volume. A lone fan whose neighbours' surface closed over it is left out.
//  6. The ε-split points that carry no shape are collapsed into their loop neighbours (they lie on the
//     fans' straight edges, so the fans do not change): a third to a half fewer faces, same error. Then
//     near-collinear rim points, then rim points across the one-spacing strips of gap faces between
//     tiles, each while the surface moves by little next to the tile's own RMS plane distance.
//
// GCC 12 at -O2 warns inside OpenMesh's PropertyT<Vec3d>::push_back that it copies a default,
// deliberately uninitialised normal; harmless, and attributed to a standard header, so it can only be
// silenced before the first include.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "libmrtile/surface.h"

#include "libmrtile/errors.h"
#include "libmrtile/gap_triangulation.h"
#include "libmrtile/parallel.h"
#include "libmrtile/pca.h"
#include "libmrtile/union_find.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <queue>
#include <string>
#include <utility>

namespace mrt {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// Largest angle between a gap face and its tiles' oriented normals (a 90-degree edge bends a gap face by
// about 45 degrees from either tile).
constexpr double kMaxTileDeviationDegrees = 80.0;
using Tri = std::array<std::uint32_t, 3>;

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b)
{
    return (static_cast<std::uint64_t>(a) << 32) | b;
}
std::uint64_t undirected_key(std::uint32_t a, std::uint32_t b)
{
    return a < b ? edge_key(a, b) : edge_key(b, a);
}

Vec3 triangle_cross(const Vec3& a, const Vec3& b, const Vec3& c)
{
    return cross(b - a, c - a);
}

// Circumradius of a triangle (infinite when degenerate).
double circumradius(const Vec3& a, const Vec3& b, const Vec3& c)
{
    const double la = distance(b, c), lb = distance(a, c), lc = distance(a, b);
    const double twice_area = norm(triangle_cross(a, b, c));
    if (!(twice_area > 0.0))
        return std::numeric_limits<double>::infinity();
    return la * lb * lc / (2.0 * twice_area);
}

// A triangle so thin that its area vanishes against its longest edge: it would be a zero-area face.
bool is_sliver(const Vec3& a, const Vec3& b, const Vec3& c)
{
    const double longest = std::max({squared_distance(a, b), squared_distance(b, c), squared_distance(a, c)});
    return !(norm(triangle_cross(a, b, c)) > 1e-9 * longest);
}

struct SurfaceVertex
{
    Vec3 position;
    std::int32_t tile = -1;      // index into the tiles vector
    std::uint32_t loop_pos = kNone; // position in the tile's boundary loop; kNone for centres and fanless tiles
    bool split = false;             // inserted on a long hull edge (step 1), not an input point
};

struct TileLoop
{
    std::uint32_t centre = kNone;     // centre vertex, kNone for fanless tiles
    std::vector<std::uint32_t> loop;  // boundary loop (counter-clockwise seen from the tile normal)
    double perimeter = 0.0;
    double edge_length = 0.0;         // mean loop edge length (0 for fanless tiles)
    double spacing = 0.0;             // the tile's point spacing (Tile::spacing)
    double share = 0.0;               // the fraction of the cloud's points in the tile's node
    bool placed = false;
};

// ---------------------------------------------------------------------------------------------------
// Step 1: vertices, loops, ε-splitting.

struct Layout
{
    std::vector<SurfaceVertex> vertices;
    std::vector<TileLoop> tiles;
    std::size_t split_points = 0;
    double mean_edge = 0.0;
};

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
        tl.edge_length = perimeter / static_cast<double>(tl.loop.size());
        total_length += perimeter;
        total_edges += tl.loop.size();
    }
    out.mean_edge = total_edges ? total_length / static_cast<double>(total_edges) : 0.0;
    return out;
}

// ---------------------------------------------------------------------------------------------------
// Step 2a: height-field test.

struct Projection
{
    bool used = false;
    Vec3 axis{0, 0, 1}, u{1, 0, 0}, v{0, 1, 0};
};

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

bool point_in_convex(const std::vector<std::array<double, 2>>& poly, double x, double y)
{
    // Counter-clockwise or clockwise convex polygon: inside when all turns have the same strict sign.
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
    }
    return true;
}

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
    const Vec3 helper = std::abs(p.axis.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    p.u = normalized(cross(helper, p.axis));
    p.v = cross(p.axis, p.u);
    if (options.height_field == HeightField::On) {
        p.used = true;
        return p;
    }
    const double min_cos = std::cos(radians(options.max_tilt_degrees));
    for (const Tile& t : tiles)
        if (t.has_fan() && std::abs(dot(t.normal, p.axis)) < min_cos)
            return p;
    // Overlap test: bucket projected tile centres in a grid, test each against the outlines whose
    // bounding boxes cover its cell.
    struct Outline
    {
        std::vector<std::array<double, 2>> poly;
        double x0, y0, x1, y1;
    };
    std::vector<Outline> outlines;
    std::vector<std::array<double, 2>> centres;
    double mean_size = 0.0;
    for (const Tile& t : tiles) {
        if (!t.has_fan())
            continue;
        Outline o;
        o.x0 = o.y0 = std::numeric_limits<double>::infinity();
        o.x1 = o.y1 = -o.x0;
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
        return p;
    mean_size /= static_cast<double>(outlines.size());
    if (!(mean_size > 0.0)) {
        p.used = true;
        return p;
    }
    const double cell = mean_size;
    auto cell_of = [&](double x, double y) {
        return std::pair<std::int64_t, std::int64_t>{static_cast<std::int64_t>(std::floor(x / cell)),
                                                     static_cast<std::int64_t>(std::floor(y / cell))};
    };
    std::vector<std::pair<std::pair<std::int64_t, std::int64_t>, std::uint32_t>> grid;
    for (std::uint32_t i = 0; i < centres.size(); ++i)
        grid.push_back({cell_of(centres[i][0], centres[i][1]), i});
    std::sort(grid.begin(), grid.end());
    for (std::uint32_t k = 0; k < outlines.size(); ++k) {
        const Outline& o = outlines[k];
        const auto c0 = cell_of(o.x0, o.y0), c1 = cell_of(o.x1, o.y1);
        for (std::int64_t cx = c0.first; cx <= c1.first; ++cx) {
            auto it = std::lower_bound(grid.begin(), grid.end(), std::make_pair(std::make_pair(cx, c0.second), 0u));
            for (; it != grid.end() && it->first.first == cx && it->first.second <= c1.second; ++it)
                if (it->second != k && point_in_convex(o.poly, centres[it->second][0], centres[it->second][1]))
                    return p;
        }
    }
    p.used = true;
    return p;
}

// ---------------------------------------------------------------------------------------------------
// Step 2c: consistent tile orientation.

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

//! Face f seen from one of its vertices v: f = (v, first, second), so v's link edge is first -> second
//! and f holds the half-edge v -> first, numbered 3 f + (v's index in f). Kept per vertex so that
//! half-edge and link queries read one short contiguous list instead of the faces themselves.
struct Corner
{
    std::uint32_t halfedge, first, second;
    std::uint32_t face() const { return halfedge / 3; }
};

//! A vertex's corners in the order its faces were added. Most vertices have two fan faces and a few gap
//! faces: up to kInline corners live in place (no pointer to follow; the front's lookups all over the
//! surface are cache misses), more move to the heap.
class CornerList
{
public:
    CornerList() = default;
    CornerList(CornerList&&) noexcept = default;
    CornerList& operator=(CornerList&&) noexcept = default;
    // A copy holds the corners in place when they fit (hole filling tries two ways from one surface).
    CornerList(const CornerList& other) { *this = other; }
    CornerList& operator=(const CornerList& other)
    {
        if (this == &other)
            return *this;
        size_ = 0;
        heap_.reset();
        heap_capacity_ = 0;
        for (const Corner& c : other)
            push_back(c);
        return *this;
    }

    const Corner* begin() const { return heap_ ? heap_.get() : in_place_.data(); }
    const Corner* end() const { return begin() + size_; }
    Corner* begin() { return heap_ ? heap_.get() : in_place_.data(); }
    Corner* end() { return begin() + size_; }
    std::size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }

    void push_back(const Corner& c)
    {
        const std::uint32_t capacity = heap_ ? heap_capacity_ : kInline;
        if (size_ == capacity) {
            const std::uint32_t grown = 2 * capacity;
            std::unique_ptr<Corner[]> bigger(new Corner[grown]);
            std::copy(begin(), end(), bigger.get());
            heap_ = std::move(bigger);
            heap_capacity_ = grown;
        }
        begin()[size_++] = c;
    }
    void pop_back() { --size_; }
    //! Removes the corner at `at`, keeping the order of the others.
    void erase(Corner* at)
    {
        std::copy(at + 1, end(), at);
        --size_;
    }

private:
    static constexpr std::uint32_t kInline = 6;
    std::uint32_t size_ = 0;
    std::uint32_t heap_capacity_ = 0;
    std::array<Corner, kInline> in_place_{};
    std::unique_ptr<Corner[]> heap_;
};

class Surface
{
public:

    //! The faces at a vertex, in the order they were added (iterates face ids).
    class FaceRange
    {
    public:
        class Iterator
        {
        public:
            explicit Iterator(const Corner* at) : at_(at) {}
            std::uint32_t operator*() const { return at_->face(); }
            Iterator& operator++()
            {
                ++at_;
                return *this;
            }
            bool operator!=(const Iterator& o) const { return at_ != o.at_; }

        private:
            const Corner* at_;
        };
        explicit FaceRange(const CornerList& corners) : corners_(corners) {}
        Iterator begin() const { return Iterator(corners_.begin()); }
        Iterator end() const { return Iterator(corners_.end()); }
        std::size_t size() const { return corners_.size(); }
        bool empty() const { return corners_.empty(); }

    private:
        const CornerList& corners_;
    };

    explicit Surface(std::size_t vertex_count) : corners_(vertex_count), changed_(vertex_count, 0) {}

    const std::vector<Tri>& faces() const { return faces_; }
    const std::vector<std::int32_t>& face_tile() const { return face_tile_; }
    FaceRange faces_at(std::uint32_t v) const { return FaceRange(corners_[v]); }
    const CornerList& corners_at(std::uint32_t v) const { return corners_[v]; }
    bool has_halfedge(std::uint32_t a, std::uint32_t b) const { return face_of(a, b) != kNone; }
    //! The face with half-edge a -> b, or kNone (half-edges are unique, so there is at most one).
    std::uint32_t face_of(std::uint32_t a, std::uint32_t b) const
    {
        const std::uint32_t h = halfedge_of(a, b);
        return h == kNone ? kNone : h / 3;
    }
    //! The number 3 f + k of half-edge a -> b (a = faces()[f][k]), or kNone. Scans the corners of a or b,
    //! whichever has fewer (only fan centres have many).
    std::uint32_t halfedge_of(std::uint32_t a, std::uint32_t b) const
    {
        const CornerList& ca = corners_[a];
        const CornerList& cb = corners_[b];
        if (ca.size() <= cb.size()) {
            for (const Corner& c : ca)
                if (c.first == b)
                    return c.halfedge;
        } else {
            for (const Corner& c : cb)
                if (c.second == a) // face (b, first, a): a follows b by two
                    return c.halfedge - c.halfedge % 3 + (c.halfedge % 3 + 2) % 3;
        }
        return kNone;
    }
    bool on_surface(std::uint32_t v) const { return !corners_[v].empty(); }
    //! Number of face changes so far (a logical clock for changed_at).
    std::uint64_t clock() const { return clock_; }
    //! The clock value of the last change of the faces at v (0 = never changed): anything computed from
    //! v's faces at clock t is still valid while changed_at(v) <= t.
    std::uint64_t changed_at(std::uint32_t v) const { return changed_[v]; }

    //! Whether face (a, b, c) can be added keeping the surface an oriented manifold-in-progress.
    bool can_add(std::uint32_t a, std::uint32_t b, std::uint32_t c) const
    {
        if (a == b || b == c || c == a)
            return false;
        if (has_halfedge(a, b) || has_halfedge(b, c) || has_halfedge(c, a))
            return false;
        return link_ok(a, b, c) && link_ok(b, c, a) && link_ok(c, a, b);
    }

    bool alive(std::uint32_t f) const { return alive_[f]; }

    void add(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::int32_t tile)
    {
        const auto f = static_cast<std::uint32_t>(faces_.size());
        assert(f < kNone / 3);
        faces_.push_back({a, b, c});
        face_tile_.push_back(tile);
        alive_.push_back(true);
        corners_[a].push_back({3 * f, b, c});
        corners_[b].push_back({3 * f + 1, c, a});
        corners_[c].push_back({3 * f + 2, a, b});
        touch(faces_.back());
    }

    //! Removes the `count` most recently added faces.
    void pop_n(std::size_t count)
    {
        for (; count > 0; --count)
            pop();
    }

    //! Removes the most recently added face (used to roll back a hole fill).
    void pop()
    {
        const Tri t = faces_.back();
        faces_.pop_back();
        face_tile_.pop_back();
        alive_.pop_back();
        for (int i = 0; i < 3; ++i)
            corners_[t[i]].pop_back();
        touch(t);
    }

    //! Removes face f (it stays in faces() as a dead entry).
    void remove(std::uint32_t f)
    {
        assert(alive_[f]);
        alive_[f] = false;
        const Tri& t = faces_[f];
        for (int i = 0; i < 3; ++i)
            erase_corner(t[i], f);
        touch(t);
    }

    //! Link arcs of v: (first, last) link vertex of each maximal path, counter-clockwise order unknown.
    //! A closed link (interior vertex) gives no arc.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> arcs(std::uint32_t v) const
    {
        const CornerList& link = corners_[v]; // directed link edges first -> second
        std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
        for (const Corner& e : link) {
            if (has_link_edge_into(link, e.first))
                continue;
            std::uint32_t end = e.second;
            for (bool moved = true; moved;) {
                moved = false;
                for (const Corner& o : link)
                    if (o.first == end) {
                        end = o.second;
                        moved = true;
                        break;
                    }
            }
            out.push_back({e.first, end});
        }
        return out;
    }

    //! arcs(v).size() without building them.
    std::size_t arc_count(std::uint32_t v) const
    {
        const CornerList& link = corners_[v];
        std::size_t count = 0;
        for (const Corner& e : link)
            count += has_link_edge_into(link, e.first) ? 0 : 1;
        return count;
    }

    std::pair<std::uint32_t, std::uint32_t> link_edge(std::uint32_t f, std::uint32_t v) const
    {
        const Tri& t = faces_[f];
        const int k = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        return {t[(k + 1) % 3], t[(k + 2) % 3]};
    }

    //! Replaces vertex `from` by `to` in face f, moving f's corner at `from` to `to` (only used after the
    //! construction, for pinch splits).
    void relabel(std::uint32_t f, std::uint32_t from, std::uint32_t to)
    {
        for (auto& x : faces_[f])
            if (x == from)
                x = to;
        for (std::uint32_t w : faces_[f]) {
            if (w == to)
                continue;
            for (Corner& c : corners_[w])
                if (c.face() == f) {
                    c.first = c.first == from ? to : c.first;
                    c.second = c.second == from ? to : c.second;
                }
        }
        Corner* const it = std::find_if(corners_[from].begin(), corners_[from].end(), [&](const Corner& c) { return c.face() == f; });
        assert(it != corners_[from].end());
        const Corner moved = *it;
        corners_[from].erase(it);
        corners_[to].push_back(moved);
    }

    //! Duplicates every vertex whose faces form more than one fan: each extra fan gets a new vertex id
    //! (appended after the existing ones). Returns origin[k] = the vertex new id `first_new + k` copies.
    std::vector<std::uint32_t> split_pinches()
    {
        std::vector<std::uint32_t> origin;
        const auto n = static_cast<std::uint32_t>(corners_.size());
        for (std::uint32_t v = 0; v < n; ++v) {
            if (arc_count(v) < 2)
                continue; // one fan or none: nothing to split (and no list to build)
            const auto fans = arcs(v);
            for (std::size_t k = 1; k < fans.size(); ++k) {
                const auto copy = static_cast<std::uint32_t>(corners_.size());
                corners_.emplace_back();
                changed_.push_back(clock_);
                origin.push_back(v);
                // Walk the fan from its first link vertex, moving its faces to the copy.
                for (std::uint32_t x = fans[k].first; x != fans[k].second;) {
                    std::uint32_t found = kNone;
                    for (const Corner& c : corners_[v])
                        if (c.first == x)
                            found = c.face();
                    if (found == kNone)
                        break; // not a fan after all (cannot happen on a surface the front built): leave it
                    x = link_edge(found, v).second;
                    relabel(found, v, copy);
                }
            }
        }
        return origin;
    }

private:
    static bool has_link_edge_into(const CornerList& link, std::uint32_t x)
    {
        for (const Corner& o : link)
            if (o.second == x)
                return true;
        return false;
    }

    void erase_corner(std::uint32_t v, std::uint32_t f)
    {
        auto& cs = corners_[v];
        cs.erase(std::find_if(cs.begin(), cs.end(), [&](const Corner& c) { return c.face() == f; }));
    }

    // After adding face (v, x, y), v's link (directed edges x -> y of its faces) must be a disjoint
    // union of simple paths, or a single cycle: a closed fan plus anything else can never become a disk.
    bool link_ok(std::uint32_t v, std::uint32_t x, std::uint32_t y) const
    {
        const CornerList& link = corners_[v];
        if (link.empty())
            return true;
        if (is_closed(v))
            return false; // an interior vertex takes no more faces
        // Half-edge uniqueness already guarantees in/out degree <= 1 in the link; the only failure is a
        // cycle while other link edges remain outside it.
        std::uint32_t end = y;
        std::size_t steps = 1;
        for (bool moved = true; moved && end != x;) {
            moved = false;
            for (const Corner& e : link) {
                if (e.first == end) {
                    end = e.second;
                    ++steps;
                    moved = true;
                    break;
                }
            }
        }
        if (end != x)
            return true; // no cycle through the new edge
        return steps == link.size() + 1;
    }

    // Every edge at v has two faces: v's fan is a closed disk. Edge v -> x (a corner's first) has its
    // twin x -> v exactly when another face at v has x as its corner's second: v's corners suffice.
    bool is_closed(std::uint32_t v) const
    {
        const CornerList& link = corners_[v];
        for (const Corner& c : link)
            if (!has_link_edge_into(link, c.first))
                return false;
        return true;
    }

    void touch(const Tri& t)
    {
        ++clock_;
        for (std::uint32_t v : t)
            changed_[v] = clock_;
    }

    std::vector<Tri> faces_;
    std::vector<std::int32_t> face_tile_;
    std::vector<bool> alive_;
    std::vector<CornerList> corners_; // per vertex
    std::vector<std::uint64_t> changed_;
    std::uint64_t clock_ = 0;
};

// Angles of points around a centre, counter-clockwise about a normal, from a fixed zero direction:
// orders the fans of a pinched vertex.
class AngleAround
{
public:
    AngleAround(const Vec3& centre, const Vec3& normal) : centre_(centre)
    {
        const Vec3 helper = std::abs(normal.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        e1_ = normalized(cross(helper, normal));
        e2_ = cross(normal, e1_);
    }
    double operator()(const Vec3& p) const
    {
        const Vec3 d = p - centre_;
        return std::atan2(dot(d, e2_), dot(d, e1_));
    }

private:
    Vec3 centre_, e1_, e2_;
};

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

// The vertex after v on the boundary loop that arrives at v by the free half-edge u -> v. At a pinched
// vertex the loop continues into the fan gap it came from (fans ordered counter-clockwise around the
// vertex normal), so a loop never crosses itself: it leaves v along the free edge of the fan before
// u's (a fan (first, last) has the free half-edges first -> v and v -> last).
std::uint32_t next_boundary_vertex(const Surface& s, const std::vector<Vec3>& positions, std::uint32_t u, std::uint32_t v)
{
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
    for (const auto& fan : s.arcs(v))
        if (fan.first == u)
            return fan.second;
    return kNone;
}

// The inverse step: the vertex before u on the cycle that leaves u by the free half-edge u -> v.
std::uint32_t previous_in_fan(const Surface& s, std::uint32_t u, std::uint32_t v)
{
    for (const auto& fan : s.arcs(u))
        if (fan.second == v)
            return fan.first;
    return kNone;
}

// ---------------------------------------------------------------------------------------------------
// Step 3: advancing front over the candidate triangles.

struct Candidates
{
    std::vector<Tri> triangles;
    std::vector<double> relative_radius; // radius / local b, in (0, 1]
    std::vector<bool> fallback;          // proposed by some of its tiles but not all (local candidates)
};

// Fallback candidates (proposed by some but not all of their tiles) rank after every consensus one:
// consensus priorities are relative radius (<= 1) times (2 - turn) (<= 3).
constexpr double kFallbackRank = 4.0;

struct Candidate
{
    double priority;
    std::uint32_t a, b, c; // front half-edge a -> b (in an existing face), new face (b, a, c)
    std::uint32_t index;   // into the candidate list
    std::uint64_t clock;   // Surface::clock() when it was evaluated (not part of the order)
    bool operator>(const Candidate& o) const
    {
        if (priority != o.priority)
            return priority > o.priority;
        return std::tie(a, b, c) > std::tie(o.a, o.b, o.c);
    }
};

// The front closes a handle only around a boundary loop of at least this many edges (see Front::grow);
// holes with fewer edges are filled before it may (see fill_holes).
constexpr std::size_t kMinHandleLoopEdges = 24;

class Front
{
public:
    //! `relative_radius[i]`: radius of candidate i divided by its local alpha radius b (<= 1).
    //! `fallback[i]`: candidate i lacks consensus and is taken only where no consensus one fits.
    //! `orientation`: +1/-1 per tile (orient_tiles), or empty to orient each fan from the face reaching it.
    Front(const Layout& layout, const std::vector<Tile>& tiles, Surface& surface, const Projection& projection,
          const std::vector<Vec3>& positions, const Candidates& candidates, double max_turn_degrees,
          const std::vector<int>& orientation)
        : layout_(layout), tiles_(tiles), surface_(surface), projection_(projection), positions_(positions),
          orientation_(orientation), candidates_(candidates.triangles), relative_radius_(candidates.relative_radius),
          fallback_(candidates.fallback), min_cos_(std::cos(radians(max_turn_degrees))),
          placed_(layout.tiles.size(), false), oriented_normal_(layout.tiles.size()),
          banned_(candidates.triangles.size(), false),
          held_(candidates.triangles.size(), false), rescuing_(candidates.triangles.size(), false),
          parts_(layout.vertices.size())
    {
        const std::vector<Tri>& triangles = candidates.triangles;
        // Candidates by vertex (compressed rows, candidate order within a row): for every edge (u, w) of
        // candidate i, the entry {w, i} in u's row and {u, i} in w's. Looking up an edge scans one short
        // row instead of binary-searching all edges.
        std::vector<std::uint32_t> degree(layout.vertices.size() + 1, 0);
        for (const Tri& t : triangles)
            for (std::uint32_t v : t)
                degree[v + 1] += 2;
        row_start_.assign(degree.size(), 0);
        for (std::size_t v = 1; v < degree.size(); ++v)
            row_start_[v] = row_start_[v - 1] + degree[v];
        rows_.resize(row_start_.back());
        std::vector<std::uint32_t> fill(row_start_.begin(), row_start_.end() - 1);
        for (std::uint32_t i = 0; i < triangles.size(); ++i) {
            const Tri& t = triangles[i];
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t u = t[k], w = t[(k + 1) % 3];
                rows_[fill[u]++] = {w, i};
                rows_[fill[w]++] = {u, i};
            }
        }
    }

    //! Second chance for the stranded tiles, whose islands the caller removed from the surface: the
    //! fallback candidates that touch them become usable, and the front grows again from where it is.
    void rescue(const std::vector<bool>& stranded)
    {
        for (std::uint32_t i = 0; i < candidates_.size(); ++i)
            for (std::uint32_t v : candidates_[i])
                if (stranded[static_cast<std::size_t>(layout_.vertices[v].tile)])
                    rescuing_[i] = true;
        for (std::size_t t = 0; t < placed_.size(); ++t)
            if (stranded[t])
                placed_[t] = false;
        edges_.clear(); // cached candidates predate the new rules (and the removed islands)
        recount_parts();
        reset_pieces();
        grow_whole_front();
        run();
    }

    //! After hole filling: the tiles whose fans it dropped as islands are seeded again and the front
    //! grows from the whole surface into the holes that widening opened around them (widening removes
    //! the gap faces at a hole's vertices, which can cut fans loose; dropped, they leave a hole too
    //! large to fill). No face may add a handle here: a re-seeded fan joins the surface first as a
    //! separate piece, and every later face splits a loop. Hole filling runs again afterwards.
    void regrow(const std::vector<bool>& dropped)
    {
        allow_handles_ = false;
        for (std::size_t t = 0; t < placed_.size(); ++t)
            if (dropped[t])
                placed_[t] = false;
        // Hole filling rolled faces back (their ids are reused), so cached geometry may be stale.
        edges_.clear();
        face_normals_.clear();
        vertex_normals_.clear();
        recount_parts();
        reset_pieces();
        grow_whole_front();
        run();
    }

    //! Last: the faces held back because they add a handle.
    void finish()
    {
        reset_pieces();
        allow_handles_ = true;
        edges_.clear(); // cached candidates predate the new rule
        grow_whole_front();
    }

    //! Grows from every tile in seed order until no candidate can be added.
    void run()
    {
        std::vector<std::uint32_t> order;
        for (std::uint32_t t = 0; t < layout_.tiles.size(); ++t)
            if (layout_.tiles[t].centre != kNone)
                order.push_back(t);
        // Largest tiles first: their normals are the most reliable orientation seeds.
        std::stable_sort(order.begin(), order.end(),
                         [&](std::uint32_t a, std::uint32_t b) { return tiles_[a].points > tiles_[b].points; });
        for (std::uint32_t t : order) {
            if (placed_[t])
                continue;
            place(t, seed_orientation(t));
            grow();
        }
    }

private:
    Vec3 position(std::uint32_t v) const { return layout_.vertices[v].position; }

    Vec3 face_normal(std::uint32_t a, std::uint32_t b, std::uint32_t c) const
    {
        return normalized(triangle_cross(position(a), position(b), position(c)));
    }

    // face_normal of surface face f, computed once (faces are never removed while the front runs).
    const Vec3& surface_normal(std::uint32_t f) const
    {
        const auto& faces = surface_.faces();
        for (std::size_t g = face_normals_.size(); g < faces.size(); ++g)
            face_normals_.push_back(face_normal(faces[g][0], faces[g][1], faces[g][2]));
        return face_normals_[f];
    }

    // The normalized sum of the face normals at v, remembered until v's faces change (it reads every
    // face at v and their corners' positions: many cache misses for a value asked for again and again).
    Vec3 vertex_normal(std::uint32_t v) const
    {
        if (vertex_normals_.empty())
            vertex_normals_.resize(layout_.vertices.size());
        CachedNormal& cached = vertex_normals_[v];
        if (cached.valid && surface_.changed_at(v) <= cached.clock)
            return cached.normal;
        Vec3 n;
        for (std::uint32_t f : surface_.faces_at(v)) {
            const Tri& t = surface_.faces()[f];
            n += triangle_cross(position(t[0]), position(t[1]), position(t[2]));
        }
        cached = {normalized(n), surface_.clock(), true};
        return cached.normal;
    }

    // +1: fan counter-clockwise about the tile normal. Height fields face up the axis; otherwise the
    // precomputed orientation, or (without one) that of the placed surface the seed is a candidate
    // neighbour of, so a surface reached from two seeds still agrees.
    int seed_orientation(std::uint32_t t) const
    {
        const Vec3& n = tiles_[t].normal;
        if (projection_.used)
            return dot(n, projection_.axis) >= 0 ? 1 : -1;
        if (!orientation_.empty())
            return orientation_[t];
        double vote = 0.0;
        for (std::uint32_t v : layout_.tiles[t].loop)
            for (std::uint32_t r = row_start_[v]; r < row_start_[v + 1]; ++r) // v's candidate neighbours
                if (const std::uint32_t w = rows_[r].first; surface_.on_surface(w))
                    vote += dot(vertex_normal(w), n);
        return vote >= 0 ? 1 : -1;
    }

    void place(std::uint32_t t, int orientation)
    {
        placed_[t] = true;
        oriented_normal_[t] = tiles_[t].normal * static_cast<double>(orientation);
        const TileLoop& tl = layout_.tiles[t];
        const std::size_t n = tl.loop.size();
        const auto node_tile = static_cast<std::int32_t>(t);
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t p = tl.loop[i], q = tl.loop[(i + 1) % n];
            if (orientation > 0)
                surface_.add(tl.centre, p, q, node_tile);
            else
                surface_.add(tl.centre, q, p, node_tile);
            parts_.unite(tl.centre, p);
        }
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint32_t p = tl.loop[i], q = tl.loop[(i + 1) % n];
            if (orientation > 0)
                push_best(p, q);
            else
                push_best(q, p);
        }
    }

    // Best valid candidate for the front half-edge a -> b, or priority = inf.
    Candidate best(std::uint32_t a, std::uint32_t b) const
    {
        Candidate out{std::numeric_limits<double>::infinity(), a, b, kNone, kNone, surface_.clock()};
        const std::uint32_t f = surface_.face_of(a, b);
        if (f == kNone || surface_.has_halfedge(b, a))
            return out;
        const Vec3 ns = surface_normal(f);
        for (std::uint32_t r = row_start_[a]; r < row_start_[a + 1]; ++r) {
            if (rows_[r].first != b)
                continue;
            const std::uint32_t index = rows_[r].second;
            if (banned_[index] || (held_[index] && !allow_handles_) || (fallback_[index] && !rescuing_[index]))
                continue;
            const Tri& cand = candidates_[index];
            const std::uint32_t c = cand[0] != a && cand[0] != b ? cand[0] : (cand[1] != a && cand[1] != b ? cand[1] : cand[2]);
            // The geometric tests and the priority come first: they do not depend on the surface, and a
            // candidate that cannot beat the best one so far need not be checked against it.
            const Vec3 nt = face_normal(b, a, c);
            if (squared_norm(nt) == 0.0)
                continue;
            // A height field is a graph: every face looks up the axis, so faces never overlap in projection.
            if (projection_.used && !(dot(nt, projection_.axis) > 0.0))
                continue;
            const double turn = dot(ns, nt);
            if (turn < min_cos_)
                continue;
            const double p = relative_radius_[index] * (2.0 - turn) + (fallback_[index] ? kFallbackRank : 0.0);
            if (!(p < out.priority || (p == out.priority && c < out.c)))
                continue;
            if (!surface_.can_add(b, a, c))
                continue;
            if (!folds_ok(a, c, nt) || !folds_ok(c, b, nt))
                continue;
            if (!merge_in_order(b, a, c) || !merge_in_order(a, c, b) || !merge_in_order(c, b, a))
                continue;
            if (!projection_.used && !faces_like_tiles(a, b, c, nt))
                continue;
            // Gluing onto a vertex whose surface faces the other way could never close consistently.
            if (surface_.on_surface(c) && dot(vertex_normal(c), nt) < 0.0)
                continue;
            out.priority = p;
            out.c = c;
            out.index = index;
        }
        return out;
    }

    // Whether a face with normal nt looks the way its tiles do (their oriented normals, summed) to within
    // kMaxTileDeviationDegrees: a face folded back through a sliver hinge can pass the turn test edge by
    // edge, never this one.
    bool faces_like_tiles(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& nt) const
    {
        Vec3 ref;
        for (std::uint32_t v : {a, b, c}) {
            const auto t = static_cast<std::size_t>(layout_.vertices[v].tile);
            if (placed_[t])
                ref += oriented_normal_[t];
            else if (!orientation_.empty() && !projection_.used)
                ref += tiles_[t].normal * static_cast<double>(orientation_[t]);
        }
        if (squared_norm(ref) == 0.0)
            return true;
        return dot(nt, normalized(ref)) >= std::cos(radians(kMaxTileDeviationDegrees));
    }

    // The new face adds link edge x -> y at v. When that joins the end of one fan of v to the start of
    // another and v has three or more fans, the two must be neighbours counter-clockwise around v;
    // joining fans out of their angular order makes the surface wind twice around v (a handle).
    bool merge_in_order(std::uint32_t v, std::uint32_t x, std::uint32_t y) const
    {
        if (surface_.faces_at(v).size() < 2 || surface_.arc_count(v) < 3)
            return true;
        const auto fans = surface_.arcs(v);
        std::size_t from = kNone, to = kNone;
        for (std::size_t k = 0; k < fans.size(); ++k) {
            if (fans[k].second == x)
                from = k;
            if (fans[k].first == y)
                to = k;
        }
        if (from == kNone || to == kNone || from == to)
            return true;
        const AngleAround around(position(v), vertex_normal(v));
        auto angle = [&](std::uint32_t w) { return around(position(w)); };
        const double start = angle(x);
        std::size_t next = kNone;
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t k = 0; k < fans.size(); ++k) {
            if (k == from)
                continue;
            double delta = angle(fans[k].first) - start;
            while (delta < 0.0)
                delta += 2.0 * kPi;
            if (delta < best) {
                best = delta;
                next = k;
            }
        }
        return next == to;
    }

    // New edge x -> y of a candidate with normal nt: if the opposite half-edge y -> x has a face, the two
    // faces must not fold onto each other.
    bool folds_ok(std::uint32_t x, std::uint32_t y, const Vec3& nt) const
    {
        const std::uint32_t g = surface_.face_of(y, x);
        if (g == kNone)
            return true;
        return dot(surface_normal(g), nt) >= min_cos_;
    }

    // Pieces of the surface as split_pinches will leave it: faces joined across shared edges (a pinched
    // vertex joins nothing). A union-find over face ids, grown and synced lazily with the faces added.
    void sync_pieces()
    {
        const auto& faces = surface_.faces();
        if (pieces_.size() > faces.size())
            reset_pieces(); // faces were rolled back: start again
        while (pieces_.size() < faces.size())
            pieces_.add();
        for (; pieces_synced_ < faces.size(); ++pieces_synced_) {
            const std::uint32_t f = pieces_synced_;
            if (!surface_.alive(f))
                continue;
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t g = surface_.face_of(faces[f][(k + 1) % 3], faces[f][k]);
                if (g != kNone && surface_.alive(g))
                    pieces_.unite(f, g);
            }
        }
    }
    void reset_pieces()
    {
        pieces_ = UnionFind();
        pieces_synced_ = 0;
    }

    // Whether face (b, a, c) joins two boundary cycles of one piece as the surface will be once pinched
    // vertices are split (makes_handle walks loops through a pinched vertex from whichever fan it
    // arrives by, and sees one piece where the fans may lie in two). The face is glued along the free
    // half-edge b -> a and along a -> c and c -> b where those are free; a handle needs two glued
    // half-edges on different cycles of one piece.
    bool split_view_handle(std::uint32_t a, std::uint32_t b, std::uint32_t c)
    {
        if (!surface_.on_surface(c))
            return false;
        const std::uint32_t fac = surface_.face_of(c, a), fcb = surface_.face_of(b, c);
        if (fac == kNone && fcb == kNone)
            return false;
        const std::uint32_t fab = surface_.face_of(a, b);
        if (fab == kNone)
            return false; // not a front edge (cannot happen: the front runs along faces' half-edges)
        // Glued half-edges of another piece join two pieces: no handle.
        sync_pieces();
        const std::uint32_t mine = pieces_.find(fab);
        const bool ac = fac != kNone && pieces_.find(fac) == mine, cb = fcb != kNone && pieces_.find(fcb) == mine;
        if (!ac && !cb)
            return false;
        // Walk the split-view cycle of b -> a both ways at once (the glued half-edges are usually a step
        // or two away): arriving at v by u -> v, leave by the other end of the same fan's arc.
        bool seen_ac = false, seen_cb = false;
        const auto see = [&](std::uint32_t from, std::uint32_t to) {
            seen_ac = seen_ac || (from == a && to == c);
            seen_cb = seen_cb || (from == c && to == b);
            return (!ac || seen_ac) && (!cb || seen_cb);
        };
        std::uint32_t u = b, v = a; // forward: free half-edge u -> v
        std::uint32_t x = b, y = a; // backward: free half-edge x -> y
        for (std::size_t steps = 0; steps <= 3 * surface_.faces().size(); ++steps) {
            const std::uint32_t w = next_in_fan(surface_, u, v);
            if (w == kNone)
                return false; // not a plain cycle here: leave it to makes_handle
            u = v;
            v = w;
            if (see(u, v))
                return false; // every glued half-edge of this piece on this cycle: it splits or shortens
            if (u == x && v == y)
                return true; // the whole cycle seen: a glued half-edge on another cycle of the same piece
            const std::uint32_t z = previous_in_fan(surface_, x, y);
            if (z == kNone)
                return false;
            y = x;
            x = z;
            if (see(x, y))
                return false;
            if (u == x && v == y)
                return true;
        }
        assert(false); // a boundary cycle has at most 3 F half-edges
        return false;
    }

    // Whether face (b, a, c) on the front half-edge a -> b would join two different boundary loops of
    // one connected piece: that adds a handle (Euler: the face changes V - E + F by -1 and the loop count
    // by -1, so the genus grows by 1). Joining another piece, or a vertex of the same loop (which splits
    // it in two), keeps the genus. Consensus faces may make the handles a torus needs; fallback faces,
    // taken where the tiles' planes disagree, must not.
    // When it does, `loop_edges` (if given) gets the length of the loop of a -> b.
    bool makes_handle(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::size_t* loop_edges = nullptr)
    {
        if (!surface_.on_surface(c) || parts_.find(c) != parts_.find(a))
            return false;
        // Walk the loop of the free half-edge b -> a both ways at once: c is usually a few steps away
        // (the face closes a notch), and only a handle costs the whole loop. The two walks meet once
        // their steps add up to the loop's length.
        std::uint32_t u = b, v = a; // forward: free half-edge u -> v
        std::uint32_t x = b, y = a; // backward: free half-edge x -> y
        std::size_t steps = 0;
        for (;;) {
            if (v == c || x == c)
                return false;
            const std::uint32_t w = next_boundary_vertex(surface_, positions_, u, v);
            u = v;
            v = w;
            ++steps;
            if (u == x && v == y)
                break; // forward met backward: the whole loop seen
            const std::uint32_t z = previous_boundary_vertex(surface_, positions_, x, y);
            y = x;
            x = z;
            ++steps;
            if (u == x && v == y)
                break;
        }
        if (loop_edges)
            *loop_edges = steps;
        return true;
    }

    // The connected pieces of the surface as it is now (after faces were removed).
    void recount_parts()
    {
        parts_ = UnionFind(layout_.vertices.size());
        for (std::uint32_t f = 0; f < surface_.faces().size(); ++f)
            if (surface_.alive(f)) {
                const Tri& t = surface_.faces()[f];
                parts_.unite(t[0], t[1]);
                parts_.unite(t[0], t[2]);
            }
    }

    void grow_whole_front()
    {
        for (std::uint32_t f = 0; f < surface_.faces().size(); ++f)
            if (surface_.alive(f)) {
                const Tri& t = surface_.faces()[f];
                for (int k = 0; k < 3; ++k)
                    if (!surface_.has_halfedge(t[(k + 1) % 3], t[k]))
                        push_best(t[k], t[(k + 1) % 3]);
            }
        grow();
    }

    // Whether no face changed at the ends of c's edge or at any apex of its candidates after c was
    // evaluated (tile placement adds faces at all the tile's vertices, so placed_ is covered too).
    bool unchanged_since(const Candidate& c) const
    {
        if (surface_.changed_at(c.a) > c.clock || surface_.changed_at(c.b) > c.clock)
            return false;
        for (std::uint32_t r = row_start_[c.a]; r < row_start_[c.a + 1]; ++r) {
            if (rows_[r].first != c.b)
                continue;
            for (std::uint32_t v : candidates_[rows_[r].second])
                if (surface_.changed_at(v) > c.clock)
                    return false;
        }
        return true;
    }

    // Per front half-edge (by its number, Surface::halfedge_of): the last best() result, and the key of
    // the entry last pushed for it while that entry is still queued.
    struct EdgeState
    {
        double best_priority = 0.0;
        double queued_priority = 0.0;
        std::uint64_t best_clock = 0;
        std::uint32_t best_c = kNone;
        std::uint32_t queued_c = kNone;
        std::uint32_t best_index = kNone;
        bool evaluated = false;
        bool queued = false;
    };

    // The state of front half-edge a -> b, or nullptr when no face has that half-edge.
    EdgeState* edge_state(std::uint32_t a, std::uint32_t b)
    {
        const std::uint32_t slot = surface_.halfedge_of(a, b);
        if (slot == kNone)
            return nullptr;
        if (slot >= edges_.size())
            edges_.resize(3 * surface_.faces().size());
        return &edges_[slot];
    }

    // best(a, b) for the edge with state e, reusing the last result while nothing it depends on changed
    // (see unchanged_since): refreshes around a new face and pops ask for the same edges several times.
    Candidate cached_best(EdgeState& e, std::uint32_t a, std::uint32_t b) const
    {
        Candidate c{e.best_priority, a, b, e.best_c, e.best_index, e.best_clock};
        if (!e.evaluated || !unchanged_since(c)) {
            c = best(a, b);
            e.best_priority = c.priority;
            e.best_c = c.c;
            e.best_index = c.index;
            e.best_clock = c.clock;
            e.evaluated = true;
        }
        return c;
    }

    // Queues c unless an entry with the same key for the same edge is still queued. Such a duplicate
    // changes nothing: identical keys pop one after the other, and the second finds the edge either
    // closed (the first was accepted), in the same state (the first was dropped or re-queued with a
    // larger key, which the second would re-queue again), or already handled (re-queued with a smaller
    // key, which popped first and was accepted).
    void enqueue(EdgeState& e, const Candidate& c)
    {
        if (e.queued && e.queued_priority == c.priority && e.queued_c == c.c)
            return;
        e.queued = true;
        e.queued_priority = c.priority;
        e.queued_c = c.c;
        queue_.push(c);
    }

    void push_best(std::uint32_t a, std::uint32_t b)
    {
        EdgeState* e = edge_state(a, b);
        if (e == nullptr)
            return; // not a front edge: best(a, b) has no candidate
        const Candidate c = cached_best(*e, a, b);
        if (c.c != kNone)
            enqueue(*e, c);
    }

    // Re-examines the front edges around v (their candidates may have become valid or invalid).
    // v's corners alone tell which of its edges are on the front: edge v -> x (corner first x) has a twin
    // when a corner has second x, edge x -> v (corner second x) when one has first x. The order of the
    // pushes does not matter (the queue orders them).
    void refresh(std::uint32_t v)
    {
        const CornerList& corners = surface_.corners_at(v); // push_best leaves the surface as it is
        for (const Corner& c : corners) {
            bool out_twin = false, in_twin = false;
            for (const Corner& o : corners) {
                out_twin = out_twin || o.second == c.first;
                in_twin = in_twin || o.first == c.second;
            }
            if (!out_twin)
                push_best(v, c.first);
            if (!in_twin)
                push_best(c.second, v);
        }
    }

    void grow()
    {
        while (!queue_.empty()) {
            const Candidate top = queue_.top();
            queue_.pop();
            EdgeState& e = *edge_state(top.a, top.b); // a queued edge has its face (faces stay)
            if (e.queued && e.queued_priority == top.priority && e.queued_c == top.c)
                e.queued = false;
            // The edge's best candidate now (`top` itself if nothing changed since it was evaluated).
            const Candidate now = cached_best(e, top.a, top.b);
            if (now.c == kNone)
                continue;
            if (now.c != top.c || now.priority != top.priority) {
                enqueue(e, now);
                continue;
            }
            const std::uint32_t a = top.a, b = top.b, c = top.c;
            // A face that would add a handle waits until every tile is in (finish): a torus needs its
            // handle once the surface has closed around it; a spurious one across a local gap is
            // usually made impossible by the faces that fill the gap first. Fallback faces never add one.
            // Handles are looked for in the surface as it is and as split_pinches will leave it.
            if (!allow_handles_ && (makes_handle(a, b, c) || split_view_handle(a, b, c))) {
                (fallback_[top.index] ? banned_ : held_)[top.index] = true;
                e.evaluated = false; // the cached best is the candidate just set aside
                push_best(a, b);
                continue;
            }
            // At the end a handle is made only around a long loop: the loop around a tube runs over many
            // tiles (89 to 311 edges on the torus and the 3-hole solid at tolerances 0.01–0.001, and the
            // coarsest tori with ~40 tiles still close), a spurious one closes over a gap between a few
            // tiles (3 to 16 edges seen), which hole filling then closes without a handle.
            std::size_t loop_edges = 0;
            if (allow_handles_ && makes_handle(a, b, c, &loop_edges) && loop_edges < kMinHandleLoopEdges) {
                banned_[top.index] = true;
                e.evaluated = false;
                push_best(a, b);
                continue;
            }
            const std::int32_t ct = layout_.vertices[c].tile;
            if (ct >= 0 && layout_.tiles[static_cast<std::size_t>(ct)].centre != kNone && !placed_[static_cast<std::size_t>(ct)]) {
                const Vec3 nt = face_normal(b, a, c);
                const auto t = static_cast<std::size_t>(ct);
                place(static_cast<std::uint32_t>(ct), !orientation_.empty() && !projection_.used
                                                          ? orientation_[t]
                                                          : (dot(nt, tiles_[t].normal) >= 0 ? 1 : -1));
                if (!surface_.can_add(b, a, c))
                    continue; // cannot happen: the fan only touches its own points
            }
            surface_.add(b, a, c, -1);
            parts_.unite(a, c);
            push_best(a, c);
            push_best(c, b);
            refresh(a);
            refresh(b);
            refresh(c);
        }
    }

    const Layout& layout_;
    const std::vector<Tile>& tiles_;
    Surface& surface_;
    const Projection& projection_;
    const std::vector<Vec3>& positions_;
    const std::vector<int>& orientation_;
    const std::vector<Tri>& candidates_;
    const std::vector<double>& relative_radius_;
    const std::vector<bool>& fallback_;
    double min_cos_;
    std::vector<bool> placed_;
    std::vector<Vec3> oriented_normal_; // tile normal times its placed orientation
    std::vector<std::uint32_t> row_start_;                      // candidates by vertex, see the constructor
    std::vector<std::pair<std::uint32_t, std::uint32_t>> rows_; // {other vertex, candidate}
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> queue_;
    std::vector<bool> banned_;   // fallback candidates found to add a handle
    std::vector<bool> held_;     // consensus candidates found to add a handle (wait for finish)
    bool allow_handles_ = false;
    std::vector<bool> rescuing_; // fallback candidates in use (they touch a stranded tile)
    UnionFind pieces_;                  // see sync_pieces
    std::uint32_t pieces_synced_ = 0;
    UnionFind parts_;          // connected pieces of the surface, over vertices
    std::vector<EdgeState> edges_; // by face and edge, see edge_state
    mutable std::vector<Vec3> face_normals_; // see surface_normal
    struct CachedNormal
    {
        Vec3 normal;
        std::uint64_t clock = 0;
        bool valid = false;
    };
    mutable std::vector<CachedNormal> vertex_normals_; // see vertex_normal
};

// ---------------------------------------------------------------------------------------------------
// Step 2b: pruning of the Delaunay triangles (paper §4.3's removal rules, plus chords).

// The removal rules of paper §4.3 (one-tile triangles, local alpha radius b) plus chords across a
// fan, slivers, and triangles joining tiles that do not meet on the surface.
class Pruner
{
public:
    Pruner(const Layout& layout, const std::vector<Tile>& tiles, const Projection& projection, double alpha,
           const SurfaceOptions& options)
        : layout_(layout), tiles_(tiles), projection_(projection), alpha_(alpha), options_(options)
    {
        // A height field is triangulated in its domain (paper §4.3): tiles across a jump are not
        // neighbours in space but are joined when steps are bridged.
        know_neighbours_ = !projection.used &&
                           std::any_of(tiles.begin(), tiles.end(), [](const Tile& t) { return !t.neighbours.empty(); });
    }

    bool know_neighbours() const { return know_neighbours_; }

    //! Radius of t over its local alpha radius b, in (0, 1], or -1 when t is removed.
    double relative_radius(const Tri& t) const
    {
        const SurfaceVertex& a = layout_.vertices[t[0]];
        const SurfaceVertex& b = layout_.vertices[t[1]];
        const SurfaceVertex& c = layout_.vertices[t[2]];
        if (a.tile == b.tile && b.tile == c.tile)
            return -1.0;
        if (is_sliver(a.position, b.position, c.position))
            return -1.0;
        if (chord(t[0], t[1]) || chord(t[1], t[2]) || chord(t[0], t[2]))
            return -1.0;
        // Only tiles that meet on the sampled surface are joined (not across a thin wall or a hole).
        if (apart(a.tile, b.tile) || apart(b.tile, c.tile) || apart(a.tile, c.tile))
            return -1.0;
        const double local_b = alpha_ * std::max({scale(t[0]), scale(t[1]), scale(t[2])}) / layout_.mean_edge;
        const double r = circumradius(flat(a.position), flat(b.position), flat(c.position));
        if (!(r <= local_b))
            return -1.0;
        if (projection_.used && !options_.bridge_steps) {
            const double limit = options_.step_height > 0.0 ? options_.step_height : local_b;
            const double ha = dot(a.position, projection_.axis), hb = dot(b.position, projection_.axis),
                         hc = dot(c.position, projection_.axis);
            if (std::max({ha, hb, hc}) - std::min({ha, hb, hc}) > limit)
                return -1.0;
        }
        return r / local_b;
    }

private:
    bool apart(std::int32_t a, std::int32_t b) const
    {
        if (!know_neighbours_ || a == b)
            return false;
        const auto& n = tiles_[static_cast<std::size_t>(a)].neighbours;
        return !std::binary_search(n.begin(), n.end(), static_cast<std::uint32_t>(b));
    }
    // An edge joining two non-adjacent points of one tile's loop would cross its fan.
    bool chord(std::uint32_t a, std::uint32_t b) const
    {
        const SurfaceVertex& va = layout_.vertices[a];
        const SurfaceVertex& vb = layout_.vertices[b];
        if (va.tile != vb.tile || va.loop_pos == kNone || vb.loop_pos == kNone)
            return false;
        const auto n = static_cast<std::uint32_t>(layout_.tiles[static_cast<std::size_t>(va.tile)].loop.size());
        const std::uint32_t d = va.loop_pos > vb.loop_pos ? va.loop_pos - vb.loop_pos : vb.loop_pos - va.loop_pos;
        return d != 1 && d != n - 1;
    }
    double scale(std::uint32_t v) const
    {
        const double e = layout_.tiles[static_cast<std::size_t>(layout_.vertices[v].tile)].edge_length;
        return e > 0.0 ? e : layout_.mean_edge;
    }
    Vec3 flat(const Vec3& p) const
    {
        return projection_.used ? Vec3{dot(p, projection_.u), dot(p, projection_.v), 0.0} : p;
    }

    const Layout& layout_;
    const std::vector<Tile>& tiles_;
    const Projection& projection_;
    double alpha_;
    const SurfaceOptions& options_;
    bool know_neighbours_ = false;
};

// Candidates from one Delaunay triangulation of all boundary points (3D, or 2D for height fields).
Candidates global_candidates(const Pruner& pruner, const DelaunayTriangles& dt, const std::vector<std::uint32_t>& vertex_of)
{
    Candidates out;
    for (const auto& d : dt.triangles) {
        const Tri t{vertex_of[d[0]], vertex_of[d[1]], vertex_of[d[2]]};
        const double r = pruner.relative_radius(t);
        if (r < 0.0)
            continue;
        out.triangles.push_back(t);
        out.relative_radius.push_back(r);
        out.fallback.push_back(false);
    }
    return out;
}

// True when p, projected into the tile's plane, lies strictly inside its (convex) outline.
bool inside_outline(const Hierarchy& h, const Tile& tile, const Vec3& p)
{
    if (!tile.has_fan())
        return false;
    auto uv = [&](const Vec3& q) {
        const Vec3 d = q - tile.centre;
        return std::array<double, 2>{dot(d, tile.axis_u), dot(d, tile.axis_v)};
    };
    const auto x = uv(p);
    const std::size_t n = tile.boundary.size();
    for (std::size_t i = 0; i < n; ++i) {
        const auto a = uv(h.cloud.positions[tile.boundary[i]]);
        const auto b = uv(h.cloud.positions[tile.boundary[(i + 1) % n]]);
        if ((b[0] - a[0]) * (x[1] - a[1]) - (b[1] - a[1]) * (x[0] - a[0]) <= 0.0)
            return false;
    }
    return true;
}

// Candidates from local Delaunay triangulations: for every tile, its loop and its surface neighbours'
// loops projected into its own plane (the surface is nearly flat at that scale, so the 2D Delaunay
// triangulation there is a fold-free piece of the restricted Delaunay triangulation). A triangle is a
// candidate only when every tile it touches proposes it (consensus): triangles that look Delaunay from
// one tile's plane only are where the planes disagree, and taking them made folds and handles. The
// gaps they leave are closed by hole filling.
Candidates local_candidates(const Hierarchy& h, const Pruner& pruner, const Layout& layout, const std::vector<Tile>& tiles,
                            std::size_t threads)
{
    std::vector<std::vector<std::uint32_t>> members(layout.tiles.size());
    for (std::uint32_t v = 0; v < layout.vertices.size(); ++v) {
        const auto t = static_cast<std::size_t>(layout.vertices[v].tile);
        if (layout.tiles[t].centre != v)
            members[t].push_back(v);
    }
    // The tiles' triangulations are independent: blocks of tiles go to worker threads, and since the
    // proposals are sorted afterwards (no two are equal), the result does not depend on the threads.
    constexpr std::uint32_t kBlock = 64;
    const auto tile_count = static_cast<std::uint32_t>(layout.tiles.size());
    std::vector<std::vector<std::pair<Tri, std::uint32_t>>> block_proposals((tile_count + kBlock - 1) / kBlock);
    run_parallel(block_proposals.size(), threads, [&](std::size_t block) {
        std::vector<std::pair<Tri, std::uint32_t>>& proposals = block_proposals[block]; // (sorted triangle, tile)
        std::vector<Vec3> points;
        std::vector<std::uint32_t> ids;
        const auto first = static_cast<std::uint32_t>(block * kBlock);
        for (std::uint32_t t = first; t < std::min(tile_count, first + kBlock); ++t) {
            if (layout.tiles[t].centre == kNone)
                continue;
            points.clear();
            ids.clear();
            for (std::uint32_t v : members[t])
                ids.push_back(v);
            for (std::uint32_t n : tiles[t].neighbours)
                for (std::uint32_t v : members[n])
                    ids.push_back(v);
            for (std::uint32_t v : ids)
                points.push_back(layout.vertices[v].position);
            DelaunayOptions o;
            o.projected = true;
            o.axis_u = tiles[t].axis_u;
            o.axis_v = tiles[t].axis_v;
            const DelaunayTriangles dt = delaunay_triangles(points, o);
            for (const auto& d : dt.triangles) {
                Tri tri{ids[d[0]], ids[d[1]], ids[d[2]]};
                const auto tile_of = [&](std::uint32_t v) { return static_cast<std::uint32_t>(layout.vertices[v].tile); };
                if (tile_of(tri[0]) != t && tile_of(tri[1]) != t && tile_of(tri[2]) != t)
                    continue;
                std::sort(tri.begin(), tri.end());
                proposals.push_back({tri, t});
            }
        }
    });
    std::vector<std::pair<Tri, std::uint32_t>> proposals;
    for (const auto& block : block_proposals)
        proposals.insert(proposals.end(), block.begin(), block.end());
    block_proposals = {};
    std::sort(proposals.begin(), proposals.end());
    Candidates out;
    for (std::size_t i = 0; i < proposals.size();) {
        std::size_t j = i;
        while (j < proposals.size() && proposals[j].first == proposals[i].first)
            ++j;
        const Tri& tri = proposals[i].first;
        std::array<std::uint32_t, 3> fan_tiles{};
        std::size_t fans = 0;
        for (std::uint32_t v : tri) {
            const auto t = static_cast<std::uint32_t>(layout.vertices[v].tile);
            if (layout.tiles[t].centre != kNone)
                fan_tiles[fans++] = t;
        }
        std::sort(fan_tiles.begin(), fan_tiles.begin() + static_cast<std::ptrdiff_t>(fans));
        fans = static_cast<std::size_t>(std::unique(fan_tiles.begin(), fan_tiles.begin() + static_cast<std::ptrdiff_t>(fans)) -
                                        fan_tiles.begin());
        const std::size_t votes = j - i;
        i = j;
        // Triangles without consensus are kept as fallback candidates (used only for stranded tiles).
        double r = pruner.relative_radius(tri);
        if (r < 0.0)
            continue;
        // A triangle over a fan (its tiles seen in their own planes) would overlap it.
        const Vec3 centroid = (layout.vertices[tri[0]].position + layout.vertices[tri[1]].position +
                               layout.vertices[tri[2]].position) / 3.0;
        if (std::any_of(fan_tiles.begin(), fan_tiles.begin() + static_cast<std::ptrdiff_t>(fans),
                        [&](std::uint32_t t) { return inside_outline(h, tiles[t], centroid); }))
            continue;
        out.triangles.push_back(tri);
        out.relative_radius.push_back(r);
        out.fallback.push_back(votes < fans);
    }
    return out;
}

// ---------------------------------------------------------------------------------------------------
// Step 4: boundary loops and hole filling.

// The pieces of the surface that broke off a larger one: a part with a tile whose surface neighbour
// lies in a larger part, a small part (under 5% of the largest) with a tile whose neighbour lies
// outside it, and a part of gap faces only. Such an island meets the rest of the surface in the
// sampled data but failed to join it (typically at a thin or sharp feature), and the larger surface
// around it then has a hole with the island inside that no disk can fill. Parts whose tiles have no
// neighbours elsewhere (separate objects) are not islands.
struct Islands
{
    UnionFind parts{0};                      // faces -> part
    std::vector<bool> doomed;                // per part root: an island
    std::vector<std::uint32_t> part_of_tile; // kNone for tiles without faces
};

Islands find_islands(const Surface& s, const std::vector<Tile>& tiles)
{
    const auto count = static_cast<std::uint32_t>(s.faces().size());
    UnionFind parts(count);
    for (std::uint32_t f = 0; f < count; ++f) {
        if (!s.alive(f))
            continue;
        const Tri& t = s.faces()[f];
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t g = s.face_of(t[(k + 1) % 3], t[k]);
            if (g != kNone)
                parts.unite(f, g);
        }
    }
    std::vector<std::uint32_t> size(count, 0);
    std::vector<std::uint32_t> part_of_tile(tiles.size(), kNone);
    for (std::uint32_t f = 0; f < count; ++f)
        if (s.alive(f)) {
            ++size[parts.find(f)];
            if (s.face_tile()[f] >= 0)
                part_of_tile[static_cast<std::size_t>(s.face_tile()[f])] = parts.find(f);
        }
    std::vector<bool> doomed(count, false);
    // A part made of gap faces only (a bubble closed between two sides of a thin feature) represents
    // no tile at all: it goes unless it is the largest part.
    std::vector<bool> has_fan(count, false);
    std::uint32_t largest = kNone;
    for (std::uint32_t f = 0; f < count; ++f)
        if (s.alive(f)) {
            const std::uint32_t p = parts.find(f);
            has_fan[p] = has_fan[p] || s.face_tile()[f] >= 0;
            if (largest == kNone || size[p] > size[largest])
                largest = p;
        }
    for (std::uint32_t f = 0; f < count; ++f)
        if (s.alive(f) && parts.find(f) == f && !has_fan[f] && f != largest)
            doomed[f] = true;
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        const std::uint32_t p = part_of_tile[t];
        if (p == kNone)
            continue;
        for (std::uint32_t n : tiles[t].neighbours) {
            const std::uint32_t q = part_of_tile[n];
            // A neighbour in a larger part, or (for a small part) anywhere else: this part is a piece
            // broken off a larger surface (its neighbours may be broken-off pieces themselves).
            const bool larger = q != kNone && (size[q] > size[p] || (size[q] == size[p] && q < p));
            const bool small_piece = q != p && p != largest && 20 * size[p] < size[largest];
            if (larger || small_piece) {
                doomed[p] = true;
                break;
            }
        }
    }
    return Islands{std::move(parts), std::move(doomed), std::move(part_of_tile)};
}

// Tiles whose fans are in an island.
std::vector<bool> island_tiles(const Islands& islands)
{
    std::vector<bool> out(islands.part_of_tile.size(), false);
    for (std::size_t t = 0; t < out.size(); ++t)
        out[t] = islands.part_of_tile[t] != kNone && islands.doomed[islands.part_of_tile[t]];
    return out;
}

// Removes the faces of the islands: once one is gone, its hole is an ordinary one.
void remove_islands(Surface& s, Islands& islands)
{
    for (std::uint32_t f = 0; f < s.faces().size(); ++f)
        if (s.alive(f) && islands.doomed[islands.parts.find(f)])
            s.remove(f);
}

// Finds and removes the islands. Returns the tiles whose fans were removed; `removed` gets the (now
// dead) face ids of each island, in face order.
std::vector<bool> drop_islands(Surface& s, const std::vector<Tile>& tiles, std::vector<std::vector<std::uint32_t>>& removed)
{
    Islands islands = find_islands(s, tiles);
    std::map<std::uint32_t, std::size_t> index_of_part;
    for (std::uint32_t f = 0; f < s.faces().size(); ++f) {
        if (!s.alive(f))
            continue;
        const std::uint32_t part = islands.parts.find(f);
        if (!islands.doomed[part])
            continue;
        const auto inserted = index_of_part.emplace(part, removed.size());
        if (inserted.second)
            removed.emplace_back();
        removed[inserted.first->second].push_back(f);
        s.remove(f);
    }
    return island_tiles(islands);
}

// An island is dropped on the grounds that it broke off a larger surface which, once the island is gone,
// closes over its place. Where that did not happen (the island is a separate strip of the sample seen
// beside the main surface, as behind a bunny's leg in a single range scan, or its hole was too wide to
// fill) the island is put back: its points are far better off with their own surface than with none.
// An island counts as covered when most of its fan centres lie within `reach` × their tile spacing of
// a face of the rest. Islands are put back whole (all faces addable) or not at all, and never a closed
// one; an island of fewer than kMinRestoredTiles fans only when it holds at least kMinRestoredShare of
// the points (in a dense sample a lone fan or two is noise or a sliver at a sharp edge; in a sparse one,
// 100 points of a bunny's head, three lone fans held 23% of the points, up to 36% of the diagonal
// away). Returns the number of islands put back; `restored_tiles` is set for each of their fans.
constexpr std::size_t kMinRestoredTiles = 3;
constexpr double kMinRestoredShare = 0.01;
std::size_t restore_uncovered_islands(Surface& s, const std::vector<std::vector<std::uint32_t>>& removed,
                                      const std::vector<Vec3>& positions, const std::vector<TileLoop>& loops,
                                      std::vector<bool>& restored_tiles, double reach = 2.0)
{
    std::size_t restored = 0;
    for (const std::vector<std::uint32_t>& island : removed) {
        // Fan centres of the island (one per tile) and the box around them, widened by the reach.
        std::vector<std::pair<Vec3, double>> centres; // position, reach distance
        std::vector<std::int32_t> island_tiles;
        double share = 0.0;
        std::vector<bool> seen_tile(loops.size(), false);
        for (std::uint32_t f : island) {
            const std::int32_t t = s.face_tile()[f];
            if (t < 0 || seen_tile[static_cast<std::size_t>(t)])
                continue;
            seen_tile[static_cast<std::size_t>(t)] = true;
            const TileLoop& tl = loops[static_cast<std::size_t>(t)];
            if (tl.centre != kNone) {
                centres.push_back({positions[tl.centre], reach * tl.spacing});
                island_tiles.push_back(t);
                share += tl.share;
            }
        }
        if (centres.empty() || (centres.size() < kMinRestoredTiles && share < kMinRestoredShare))
            continue;
        // A closed island is a bubble (both sides of a thin tip closed onto each other instead of onto
        // the surface): put back, it would float beside the surface as a component of its own.
        std::vector<std::uint64_t> edges;
        for (std::uint32_t f : island)
            for (int k = 0; k < 3; ++k)
                edges.push_back(edge_key(s.faces()[f][k], s.faces()[f][(k + 1) % 3]));
        std::sort(edges.begin(), edges.end());
        const bool closed = std::all_of(island.begin(), island.end(), [&](std::uint32_t f) {
            const Tri& t = s.faces()[f];
            for (int k = 0; k < 3; ++k)
                if (!std::binary_search(edges.begin(), edges.end(), edge_key(t[(k + 1) % 3], t[k])))
                    return false;
            return true;
        });
        if (closed)
            continue;
        Vec3 lo = centres[0].first, hi = lo;
        double margin = 0.0;
        for (const auto& [c, r] : centres) {
            lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
            hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
            margin = std::max(margin, r);
        }
        // Faces of the rest near the island: one with a vertex in the widened box, or larger than the box.
        std::vector<std::uint32_t> near;
        auto inside = [&](const Vec3& p, double m) {
            return p.x >= lo.x - m && p.y >= lo.y - m && p.z >= lo.z - m && p.x <= hi.x + m && p.y <= hi.y + m && p.z <= hi.z + m;
        };
        for (std::uint32_t f = 0; f < s.faces().size(); ++f) {
            if (!s.alive(f))
                continue;
            const Tri& t = s.faces()[f];
            const double size = std::max({distance(positions[t[0]], positions[t[1]]), distance(positions[t[1]], positions[t[2]]),
                                          distance(positions[t[2]], positions[t[0]])});
            if (inside(positions[t[0]], margin + size) || inside(positions[t[1]], margin + size) || inside(positions[t[2]], margin + size))
                near.push_back(f);
        }
        std::size_t covered = 0;
        for (const auto& [c, r] : centres)
            for (std::uint32_t f : near) {
                const Tri& t = s.faces()[f];
                if (point_triangle_distance(c, positions[t[0]], positions[t[1]], positions[t[2]]) <= r) {
                    ++covered;
                    break;
                }
            }
        if (2 * covered >= centres.size())
            continue;
        std::size_t added = 0;
        bool ok = true;
        for (std::uint32_t f : island) {
            const Tri t = s.faces()[f];
            if (!s.can_add(t[0], t[1], t[2])) {
                ok = false;
                break;
            }
            s.add(t[0], t[1], t[2], s.face_tile()[f]);
            ++added;
        }
        if (!ok)
            s.pop_n(added);
        else {
            ++restored;
            for (std::int32_t t : island_tiles)
                restored_tiles[static_cast<std::size_t>(t)] = true;
        }
    }
    return restored;
}

// Boundary loops as vertex sequences v0 -> v1 -> ... (each step a half-edge without a face). At a
// pinched vertex the loop continues into the fan gap it came from (fans ordered counter-clockwise around
// the vertex normal), so a loop never crosses itself.
std::vector<std::vector<std::uint32_t>> boundary_loops(const Surface& s, const std::vector<Vec3>& positions)
{
    std::vector<std::uint64_t> free_halfedges;
    for (std::uint32_t f = 0; f < s.faces().size(); ++f) {
        if (!s.alive(f))
            continue;
        const Tri& t = s.faces()[f];
        for (int k = 0; k < 3; ++k)
            if (!s.has_halfedge(t[(k + 1) % 3], t[k]))
                free_halfedges.push_back(edge_key(t[(k + 1) % 3], t[k]));
    }
    std::sort(free_halfedges.begin(), free_halfedges.end());

    auto next_vertex = [&](std::uint32_t u, std::uint32_t v) { return next_boundary_vertex(s, positions, u, v); };

    std::vector<std::vector<std::uint32_t>> loops;
    std::vector<bool> used(free_halfedges.size(), false);
    auto index_of = [&](std::uint64_t key) {
        return static_cast<std::size_t>(std::lower_bound(free_halfedges.begin(), free_halfedges.end(), key) -
                                        free_halfedges.begin());
    };
    for (std::size_t i = 0; i < free_halfedges.size(); ++i) {
        if (used[i])
            continue;
        std::vector<std::uint32_t> loop;
        std::uint32_t u = static_cast<std::uint32_t>(free_halfedges[i] >> 32);
        std::uint32_t v = static_cast<std::uint32_t>(free_halfedges[i] & 0xffffffffu);
        std::size_t k = i;
        while (!used[k]) {
            used[k] = true;
            loop.push_back(u);
            const std::uint32_t w = next_vertex(u, v);
            u = v;
            v = w;
            k = index_of(edge_key(u, v));
            assert(k < free_halfedges.size() && free_halfedges[k] == edge_key(u, v));
        }
        loops.push_back(std::move(loop));
    }
    return loops;
}

// Minimum-area triangulation of a boundary loop (dynamic programming over sub-polygons), refusing
// triangles that repeat a vertex and diagonals that already are mesh edges. Faces are oriented like
// the loop's free half-edges, so they continue the surface's orientation. Empty when impossible.
std::vector<Tri> fill_triangulation(const Surface& s, const std::vector<Vec3>& positions, const std::vector<std::uint32_t>& loop,
                                    const Projection& projection)
{
    const std::size_t n = loop.size();
    if (n < 3)
        return {};
    const double inf = std::numeric_limits<double>::infinity();
    auto diagonal_ok = [&](std::size_t i, std::size_t j) {
        if (j == i + 1 || (i == 0 && j == n - 1))
            return true;
        const std::uint32_t a = loop[i], b = loop[j];
        return a != b && !s.has_halfedge(a, b) && !s.has_halfedge(b, a);
    };
    // A face of the patch must look the way the hole does as a whole (its vector area in loop order =
    // face order; the axis for height fields) or the way the surface around its corners does (for holes
    // bent around an edge or corner). Anything else is a fold that would double-cover the surface.
    std::vector<Vec3> facing(n);
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint32_t f : s.faces_at(loop[i])) {
            const Tri& t = s.faces()[f];
            facing[i] += normalized(triangle_cross(positions[t[0]], positions[t[1]], positions[t[2]]));
        }
    Vec3 up = projection.axis;
    if (!projection.used) {
        up = Vec3{};
        for (std::size_t i = 0; i < n; ++i)
            up += cross(positions[loop[i]], positions[loop[(i + 1) % n]]);
    }
    std::vector<double> cost(n * n, inf);
    std::vector<std::uint32_t> split(n * n, kNone);
    for (std::size_t i = 0; i + 1 < n; ++i)
        cost[i * n + i + 1] = 0.0;
    for (std::size_t len = 2; len < n; ++len) {
        for (std::size_t i = 0; i + len < n; ++i) {
            const std::size_t j = i + len;
            if (!diagonal_ok(i, j))
                continue;
            for (std::size_t k = i + 1; k < j; ++k) {
                const double c0 = cost[i * n + k], c1 = cost[k * n + j];
                if (c0 == inf || c1 == inf)
                    continue;
                const std::uint32_t a = loop[i], b = loop[k], c = loop[j];
                if (a == b || b == c || a == c)
                    continue;
                const Vec3 normal = triangle_cross(positions[a], positions[b], positions[c]);
                const double area = norm(normal);
                if (is_sliver(positions[a], positions[b], positions[c]) ||
                    (!(dot(normal, up) > 0.0) && !(dot(normal, facing[i] + facing[k] + facing[j]) > 0.0)))
                    continue;
                const double total = c0 + c1 + area;
                if (total < cost[i * n + j]) {
                    cost[i * n + j] = total;
                    split[i * n + j] = static_cast<std::uint32_t>(k);
                }
            }
        }
    }
    if (cost[n - 1] == inf)
        return {};
    std::vector<Tri> out;
    std::vector<std::pair<std::size_t, std::size_t>> stack{{0, n - 1}};
    while (!stack.empty()) {
        const auto [i, j] = stack.back();
        stack.pop_back();
        if (j <= i + 1)
            continue;
        const std::size_t k = split[i * n + j];
        out.push_back({loop[i], loop[k], loop[j]});
        stack.push_back({i, k});
        stack.push_back({k, j});
    }
    return out;
}

// Splits a loop at repeated vertices (a loop through a pinch twice bounds two holes that touch there).
std::vector<std::vector<std::uint32_t>> simple_loops(const std::vector<std::uint32_t>& loop)
{
    std::vector<std::vector<std::uint32_t>> out;
    std::vector<std::vector<std::uint32_t>> work{loop};
    while (!work.empty()) {
        std::vector<std::uint32_t> l = std::move(work.back());
        work.pop_back();
        bool split = false;
        for (std::size_t i = 0; i < l.size() && !split; ++i)
            for (std::size_t j = i + 1; j < l.size() && !split; ++j)
                if (l[i] == l[j]) {
                    std::vector<std::uint32_t> a(l.begin() + static_cast<std::ptrdiff_t>(i), l.begin() + static_cast<std::ptrdiff_t>(j));
                    std::vector<std::uint32_t> b(l.begin() + static_cast<std::ptrdiff_t>(j), l.end());
                    b.insert(b.end(), l.begin(), l.begin() + static_cast<std::ptrdiff_t>(i));
                    work.push_back(std::move(a));
                    work.push_back(std::move(b));
                    split = true;
                }
        if (!split)
            out.push_back(std::move(l));
    }
    return out;
}

struct FillResult
{
    std::size_t holes = 0;
    std::size_t faces = 0;
};

// A tile is interior (not on the sample's border) when its surface neighbours surround it: seen from
// its centre in its plane, the centres of its neighbours and theirs leave no empty angular sector wider
// than max_gap_degrees, or its neighbours form a closed ring around it (each meets two others of them;
// at a sharp edge the tile's own plane can hide a direction, the ring cannot). Tiles on the sample's
// border have the empty outside on one side and an open ring. The sector is also measured in the
// plane of each neighbour, and the narrowest counts: a cluster a few points wide that reaches across a
// sharp edge is flat in a plane at right angles to the surface, and in its own plane it sees its
// neighbours on a line (a box whose one face is sampled 10 times more densely has such clusters along
// that face's edges, and 16-50-edge holes stayed open beside them). A border tile's neighbours lie in
// the surface too, and their planes show the same empty outside.
std::vector<bool> interior_tiles(const std::vector<Tile>& tiles, double max_gap_degrees)
{
    std::vector<bool> out(tiles.size(), false);
    std::vector<double> widest(tiles.size(), 2.0 * kPi); // the empty sector of each tile
    std::vector<double> angles;
    std::vector<std::uint32_t> ring;
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        angles.clear();
        ring.clear();
        for (std::uint32_t n : tiles[t].neighbours) {
            ring.push_back(n);
            ring.insert(ring.end(), tiles[n].neighbours.begin(), tiles[n].neighbours.end());
        }
        const auto empty_sector = [&](const Tile& plane) {
            angles.clear();
            for (std::uint32_t n : ring) {
                if (n == t)
                    continue;
                const Vec3 d = tiles[n].centre - tiles[t].centre;
                angles.push_back(std::atan2(dot(d, plane.axis_v), dot(d, plane.axis_u)));
            }
            if (angles.size() < 3)
                return 2.0 * kPi;
            std::sort(angles.begin(), angles.end());
            double widest_gap = angles.front() + 2.0 * kPi - angles.back();
            for (std::size_t i = 1; i < angles.size(); ++i)
                widest_gap = std::max(widest_gap, angles[i] - angles[i - 1]);
            return widest_gap;
        };
        double gap = empty_sector(tiles[t]);
        // The neighbours' planes only matter where the tile's own plane sees a wide empty sector.
        if (gap > radians(max_gap_degrees))
            for (std::uint32_t n : tiles[t].neighbours)
                gap = std::min(gap, empty_sector(tiles[n]));
        if (gap >= 2.0 * kPi)
            continue;
        // Or the neighbours form a closed ring around it (each meets two others of them): on a sharp
        // edge the tile's own plane can hide a neighbour's direction, but not the ring.
        bool ring_closed = true;
        const auto& around = tiles[t].neighbours;
        for (std::uint32_t n : around) {
            std::size_t inside = 0;
            for (std::uint32_t m : tiles[n].neighbours)
                inside += std::binary_search(around.begin(), around.end(), m) ? 1 : 0;
            ring_closed = ring_closed && inside >= 2;
        }
        out[t] = gap <= radians(max_gap_degrees) || ring_closed;
        widest[t] = gap;
    }
    // A tile on a sharp edge, its plane tilted between the two faces, can see both faces' tiles on one
    // side (the 3-hole solid at 4,000 points: 174 degrees). A tile on the sample's border has its
    // border neighbours beside it, which are not interior either: a tile whose empty sector is under a
    // half-turn and whose neighbours are all interior is interior too (one pass: no creeping inward).
    // So is a tile without area whose neighbours are all interior: a cluster one point wide across a
    // sharp edge (flat, but in a plane at right angles to the surface) projects onto a line and sees
    // every neighbour at 0 or 180 degrees (a cube whose one face is sampled 10 times more densely:
    // such strips along that face's edges kept holes of 30-50 edges open).
    std::vector<bool> more = out;
    for (std::size_t t = 0; t < tiles.size(); ++t)
        if (!out[t] && (widest[t] < kPi || tiles[t].area <= 0.0) && !tiles[t].neighbours.empty() &&
            std::all_of(tiles[t].neighbours.begin(), tiles[t].neighbours.end(), [&](std::uint32_t n) { return out[n]; }))
            more[t] = true;
    return more;
}

// What the genus of the final mesh depends on near a set of vertices, counted as split_pinches will
// leave the surface (each fan of a pinched vertex its own vertex): vertex copies, and the boundary
// cycles through those vertices (in the split surface a cycle arriving at a fan leaves from that fan).
struct LocalTopology
{
    std::size_t vertex_copies = 0;
    std::size_t cycles = 0;
};

LocalTopology local_topology(const Surface& s, const std::vector<std::uint32_t>& vertices)
{
    LocalTopology out;
    std::vector<std::uint64_t> seen; // free half-edges already walked
    const auto next = [&](std::uint32_t u, std::uint32_t v) {
        const std::uint32_t w = next_in_fan(s, u, v);
        assert(w != kNone);
        return w;
    };
    for (std::uint32_t v : vertices) {
        const auto fans = s.arcs(v);
        out.vertex_copies += std::max<std::size_t>(1, fans.size());
        for (const auto& fan : fans) {
            // Free half-edge fan.first -> v; walk its cycle unless an earlier walk passed it.
            if (std::find(seen.begin(), seen.end(), edge_key(fan.first, v)) != seen.end())
                continue;
            ++out.cycles;
            std::uint32_t u = fan.first, w = v;
            do {
                seen.push_back(edge_key(u, w));
                const std::uint32_t x = next(u, w);
                u = w;
                w = x;
            } while (!(u == fan.first && w == v));
        }
    }
    return out;
}

// Whether a patch of `faces` triangles closing a simple loop of `loop_edges` edges raised the genus,
// from the local counts before and after (Euler: 2 Δg = -Δχ - Δb on a connected surface; the patch
// adds its faces and (3 faces - loop edges) / 2 inner edges, and changes vertex copies and boundary
// cycles only at the loop's vertices).
bool adds_handle(const LocalTopology& before, const LocalTopology& after, std::size_t faces, std::size_t loop_edges)
{
    const long new_edges = (3 * static_cast<long>(faces) - static_cast<long>(loop_edges)) / 2;
    const long d_chi = (static_cast<long>(after.vertex_copies) - static_cast<long>(before.vertex_copies)) - new_edges +
                       static_cast<long>(faces);
    const long d_b = static_cast<long>(after.cycles) - static_cast<long>(before.cycles);
    return -d_chi - d_b > 0;
}

// Whether the input points cover a hole: every spot of its fill patch (sampled about a spacing apart)
// has an input point within 1.5 spacings. A hole in the sample (the bunny's base) has an empty middle;
// a hole the tiles left in a sampled surface has points all over it: a tile built from a sample of
// at most TileOptions::max_points of its node's points can leave a gap wider than a point spacing (a
// uniformly sampled fandisk kept one 8 spacings wide in its flat top). Counting points inside instead
// also filled real scan holes whose loops took in some sampled surface beside them, and a tunnel of
// the 3-hole solid.
bool points_cover_hole(const Hierarchy& h, const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double spacing)
{
    if (patch.empty() || !(spacing > 0.0))
        return false;
    const double reach = 1.5 * spacing;
    // Spots: a barycentric grid on each patch triangle, its step at most a spacing along every edge.
    std::vector<Vec3> spots;
    for (const Tri& t : patch) {
        const Vec3 &a = positions[t[0]], &b = positions[t[1]], &c = positions[t[2]];
        const double longest = std::max({distance(a, b), distance(b, c), distance(c, a)});
        const int steps = std::clamp(static_cast<int>(std::ceil(longest / spacing)), 1, 64);
        for (int i = 0; i <= steps; ++i)
            for (int j = 0; i + j <= steps; ++j) {
                const double u = static_cast<double>(i) / steps, v = static_cast<double>(j) / steps;
                spots.push_back(a + (b - a) * u + (c - a) * v);
            }
    }
    BoundingBox box = bounding_box(spots);
    box.min = box.min - Vec3{reach, reach, reach};
    box.max = box.max + Vec3{reach, reach, reach};
    // The points near the patch, bucketed in cells of the reach: each spot looks at 27 cells, so a wide
    // hole in a large sample costs time in proportion to its spots and points, not their product.
    const auto cell_of = [&](const Vec3& p) {
        return std::array<std::int64_t, 3>{static_cast<std::int64_t>(std::floor((p.x - box.min.x) / reach)),
                                           static_cast<std::int64_t>(std::floor((p.y - box.min.y) / reach)),
                                           static_cast<std::int64_t>(std::floor((p.z - box.min.z) / reach))};
    };
    std::map<std::array<std::int64_t, 3>, std::vector<Vec3>> cells;
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
        const Node& node = h.nodes[static_cast<std::size_t>(stack.back())];
        stack.pop_back();
        if (!node.box.meets(box))
            continue;
        if (!node.is_leaf()) {
            stack.push_back(node.right);
            stack.push_back(node.left);
            continue;
        }
        for (std::uint32_t i = node.begin; i < node.end; ++i)
            if (box.contains(h.cloud.positions[i]))
                cells[cell_of(h.cloud.positions[i])].push_back(h.cloud.positions[i]);
    }
    const double reach2 = reach * reach;
    return std::all_of(spots.begin(), spots.end(), [&](const Vec3& spot) {
        const std::array<std::int64_t, 3> c = cell_of(spot);
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz) {
                    const auto found = cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
                    if (found != cells.end())
                        for (const Vec3& p : found->second)
                            if (dot(p - spot, p - spot) <= reach2)
                                return true;
                }
        return false;
    });
}

// Fills the holes that are gaps between tiles (see SurfaceOptions::hole_factor, interior_gap_degrees,
// max_gap_width), widening those that cannot be triangulated as they are. `before_handles`: the front
// has not yet been allowed to close handles, and a loop around a tube it still has to close looks like
// a hole among interior tiles; only holes small by perimeter, or among interior tiles with fewer edges
// than a handle closes around, are filled then.
FillResult fill_holes(const Hierarchy& h, Surface& s, const Layout& layout, const std::vector<Vec3>& positions,
                      const Projection& projection, const std::vector<bool>& interior, const SurfaceOptions& options,
                      bool before_handles)
{
    FillResult result;
    // Vertices around which gap faces were removed to open up a hole that could not be filled as it was.
    std::vector<bool> widened(positions.size(), false);
    constexpr int kPasses = 4;
    for (int pass = 0; pass < kPasses; ++pass) {
        bool changed = false;
        std::vector<std::vector<std::uint32_t>> loops;
        for (const auto& traced : boundary_loops(s, positions))
            for (auto& l : simple_loops(traced))
                loops.push_back(std::move(l));
        for (const auto& loop : loops) {
            const std::size_t n = loop.size();
            if (n > options.max_hole_edges || n < 3)
                continue;
            // Skip loops that an earlier fill or widening of this pass changed.
            bool current = true;
            for (std::size_t i = 0; i < n && current; ++i)
                current = !s.has_halfedge(loop[i], loop[(i + 1) % n]) && s.has_halfedge(loop[(i + 1) % n], loop[i]);
            if (!current)
                continue;
            std::vector<std::int32_t> loop_tiles;
            double perimeter = 0.0, largest_tile = 0.0, spacing = 0.0;
            bool was_widened = false, surrounded = true;
            for (std::size_t i = 0; i < n; ++i) {
                // A height field's holes are measured in its domain: a gap at a jump is small there.
                Vec3 d = positions[loop[(i + 1) % n]] - positions[loop[i]];
                if (projection.used)
                    d -= projection.axis * dot(d, projection.axis);
                perimeter += norm(d);
                const std::int32_t t = layout.vertices[loop[i]].tile;
                loop_tiles.push_back(t);
                surrounded = surrounded && interior[static_cast<std::size_t>(t)];
                largest_tile = std::max(largest_tile, layout.tiles[static_cast<std::size_t>(t)].perimeter);
                spacing = std::max(spacing, layout.tiles[static_cast<std::size_t>(t)].spacing);
                was_widened = was_widened || widened[loop[i]];
            }
            std::sort(loop_tiles.begin(), loop_tiles.end());
            loop_tiles.erase(std::unique(loop_tiles.begin(), loop_tiles.end()), loop_tiles.end());
            // A widened hole was small before we opened it: it may be up to three times as large.
            const double limit = options.hole_factor * largest_tile * (was_widened ? 3.0 : 1.0);
            // A hole among interior tiles is a gap whatever its size; elsewhere only small holes are.
            if (loop_tiles.size() < 2 ||
                (perimeter > limit && (!surrounded || (before_handles && n >= kMinHandleLoopEdges))))
                continue;
            const std::vector<Tri> patch = fill_triangulation(s, positions, loop, projection);
            // Every point lies in some tile, so a hole holds no points: a gap between tiles is about a
            // point spacing wide, and a hole much wider than that (mean width 2 area / perimeter) is a
            // hole in the sample itself (the bunny's base), which stays open.
            double area = 0.0;
            for (const Tri& t : patch) {
                const Vec3 c = triangle_cross(positions[t[0]], positions[t[1]], positions[t[2]]);
                area += 0.5 * (projection.used ? std::abs(dot(c, projection.axis)) : norm(c));
            }
            if (options.max_gap_width > 0.0 && spacing > 0.0 && 2.0 * area > options.max_gap_width * spacing * perimeter &&
                !points_cover_hole(h, positions, patch, spacing))
                continue;
            const bool pinched = std::any_of(loop.begin(), loop.end(), [&](std::uint32_t v) { return s.arcs(v).size() > 1; });
            const LocalTopology before = pinched ? local_topology(s, loop) : LocalTopology{};
            std::size_t added = 0;
            for (const Tri& t : patch) {
                if (!s.can_add(t[0], t[1], t[2]))
                    break;
                s.add(t[0], t[1], t[2], -1);
                ++added;
            }
            // Through a pinched vertex a fill can join two fans of one surface: a handle. Such a loop is
            // treated like one that cannot be triangulated (widened below).
            const bool complete = !patch.empty() && added == patch.size() &&
                                  !(pinched && adds_handle(before, local_topology(s, loop), patch.size(), n));
            if (complete) {
                ++result.holes;
                result.faces += patch.size();
                changed = true;
                continue;
            }
            for (; added > 0; --added)
                s.pop();
            if (pass + 1 == kPasses)
                continue;
            // The loop cannot be triangulated as it is (a diagonal it needs is already an edge, or a vertex
            // would close around it twice): remove the gap faces at its vertices and try the larger hole.
            std::vector<std::uint32_t> doomed;
            for (std::uint32_t v : loop)
                for (std::uint32_t f : s.faces_at(v))
                    if (s.face_tile()[f] < 0)
                        doomed.push_back(f);
            std::sort(doomed.begin(), doomed.end());
            doomed.erase(std::unique(doomed.begin(), doomed.end()), doomed.end());
            for (std::uint32_t f : doomed) {
                for (std::uint32_t v : s.faces()[f])
                    widened[v] = true;
                s.remove(f);
            }
            changed = changed || !doomed.empty();
        }
        if (!changed)
            break;
    }
    return result;
}

// ---------------------------------------------------------------------------------------------------
// Step 5: components, orientation, OpenMesh.


} // namespace

// ---------------------------------------------------------------------------------------------------
// Step 6: removing the loop points that carry no shape (ε-split points, then near-collinear rim points).

// Largest turn of a fan face when a loop point is collapsed away; a gap face (thin, its normal is noise)
// only has to stay within 75 degrees of the surface around the point.
constexpr double kMaxCollapseTurnDegrees = 20.0;
const double kMinGapFaceCos = std::cos(radians(75.0));


// The ε-splitting of step 1 puts points on long hull edges so that the gap triangles are well shaped
// while candidates are chosen (§4.3). Once the surface is fixed, most of them carry no shape: a split
// point lies on the straight segment between its loop neighbours, so collapsing it into one of them
// leaves its fan exactly as it was and only re-attaches the gap faces around it. Loop points that are
// input points are collapsed too when the surface moves by at most their `slack` (the rim of a large
// tile holds many nearly collinear hull points: they cost faces and carry little shape). A collapse is
// made only across a fan edge, when OpenMesh's link condition holds (the topology stays the same),
// when no face around the point turns by more than kMaxCollapseTurnDegrees or becomes a sliver, and
// when no neighbour of the point was moved by an earlier collapse of an input point (so the error
// does not add up).
// Returns the number of points removed (the caller collects the garbage).
// With `across_strips`, the edges collapsed are instead those with a gap face on both sides that join
// two rim points: the strip of gap faces between two tiles is about one point spacing wide and costs two
// faces per rim point while it carries almost no shape, so its rim points are merged pairwise (the
// shortest such edge first) and neighbouring fans meet directly.
std::size_t collapse_loop_points(Mesh& mesh, const std::vector<double>& slack, const Projection& projection,
                                 bool across_strips = false)
{
    auto tile_of_face = OpenMesh::getProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile);
    const double min_cos = std::cos(radians(kMaxCollapseTurnDegrees));
    auto point = [&](Mesh::VertexHandle v) { return to_vec3(mesh.point(v)); };
    std::size_t removed = 0;
    const std::size_t n = mesh.n_vertices();
    std::vector<bool> touched(n, false);
    for (std::size_t i = 0; i < n; ++i) {
        const Mesh::VertexHandle v(static_cast<int>(i));
        if (!(slack[i] >= 0.0) || touched[i] || mesh.status(v).deleted())
            continue;
        const Vec3 at = point(v);
        Vec3 around; // the surface normal at v, computed when a first edge qualifies
        bool have_around = false;
        std::vector<Mesh::HalfedgeHandle> outgoing;
        for (const Mesh::HalfedgeHandle h : mesh.voh_range(v))
            outgoing.push_back(h);
        if (across_strips)
            std::stable_sort(outgoing.begin(), outgoing.end(), [&](Mesh::HalfedgeHandle a, Mesh::HalfedgeHandle b) {
                return squared_distance(at, point(mesh.to_vertex_handle(a))) < squared_distance(at, point(mesh.to_vertex_handle(b)));
            });
        for (const Mesh::HalfedgeHandle h : outgoing) {
            const Mesh::VertexHandle w = mesh.to_vertex_handle(h);
            const Mesh::FaceHandle left = mesh.face_handle(h), right = mesh.opposite_face_handle(h);
            const bool left_fan = left.is_valid() && tile_of_face[left] >= 0, right_fan = right.is_valid() && tile_of_face[right] >= 0;
            // A loop edge has the fan on one side only (the edge to the apex has it on both); a strip edge
            // has gap faces on both sides and a rim point at each end.
            const bool wanted = across_strips ? left.is_valid() && right.is_valid() && !left_fan && !right_fan &&
                                                    slack[static_cast<std::size_t>(w.idx())] >= 0.0
                                              : left_fan != right_fan;
            if (!wanted || touched[static_cast<std::size_t>(w.idx())])
                continue;
            if (!have_around) {
                for (const Mesh::FaceHandle f : mesh.vf_range(v)) {
                    std::array<Vec3, 3> p;
                    int k = 0;
                    for (const Mesh::VertexHandle x : mesh.fv_range(f))
                        p[k++] = point(x);
                    around += triangle_cross(p[0], p[1], p[2]);
                }
                around = normalized(around);
                have_around = true;
            }
            bool keeps_shape = true;
            double moved = std::numeric_limits<double>::infinity();
            for (const Mesh::FaceHandle f : mesh.vf_range(v)) {
                if (f == left || f == right)
                    continue; // removed by the collapse
                std::array<Vec3, 3> before, after;
                int k = 0;
                for (const Mesh::VertexHandle x : mesh.fv_range(f)) {
                    before[k] = point(x);
                    after[k] = x == v ? point(w) : point(x);
                    ++k;
                }
                const Vec3 n0 = normalized(triangle_cross(before[0], before[1], before[2]));
                const Vec3 n1 = normalized(triangle_cross(after[0], after[1], after[2]));
                // A gap face in the one-spacing strip between tiles is thin and its normal is noise:
                // it must not fold against the surface around the point; a fan face must keep its turn.
                const bool folds = (tile_of_face[f] < 0 ? dot(n1, around) < kMinGapFaceCos : dot(n0, n1) < min_cos) ||
                                   (projection.used && !(dot(n1, projection.axis) > 0.0)); // a height field stays a graph
                if (is_sliver(after[0], after[1], after[2]) || folds) {
                    keeps_shape = false;
                    break;
                }
                moved = std::min(moved, point_triangle_distance(at, after[0], after[1], after[2]));
            }
            // The link condition last: it is the costliest test and the shape tests fail more often.
            if (!keeps_shape || !(moved <= slack[i]) || !mesh.is_collapse_ok(h))
                continue;
            if (std::isfinite(slack[i])) // a split point moves nothing: its neighbours stay free
                for (const Mesh::VertexHandle x : mesh.vv_range(v))
                    touched[static_cast<std::size_t>(x.idx())] = true;
            mesh.collapse(h);
            ++removed;
            break;
        }
    }
    return removed;
}

Mesh build_surface(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options, SurfaceStats* stats)
{
    const auto start = std::chrono::steady_clock::now();
    if (tiles.empty())
        throw InvalidInput("build_surface: the cut has no tiles");
    if (!(options.alpha >= 0.0) || !(options.alpha_factor > 0.0) || !(options.split_factor > 0.0) ||
        !(options.hole_factor >= 0.0) || !(options.step_height >= 0.0) || !(options.max_turn_degrees > 0.0) ||
        !(options.max_tilt_degrees > 0.0) || std::isnan(options.split_length) || !(options.interior_gap_degrees > 0.0) ||
        !(options.max_gap_width >= 0.0) || !(options.collapse_tolerance >= 0.0) || !(options.strip_tolerance >= 0.0))
        throw InvalidInput("SurfaceOptions: alpha, step_height, hole_factor, max_gap_width, collapse_tolerance, strip_tolerance must be >= 0 and alpha_factor, "
                           "split_factor, max_turn_degrees, max_tilt_degrees, interior_gap_degrees > 0");
    std::size_t fan_tiles = 0;
    for (const Tile& t : tiles) {
        if (t.node < 0 || static_cast<std::size_t>(t.node) >= h.nodes.size())
            throw InvalidInput("build_surface: tile of node " + std::to_string(t.node) + " is not in the hierarchy");
        for (std::uint32_t p : t.boundary)
            if (p >= h.cloud.positions.size())
                throw InvalidInput("build_surface: tile of node " + std::to_string(t.node) + " names point " +
                                   std::to_string(p) + " beyond the cloud");
        fan_tiles += t.has_fan() ? 1 : 0;
    }
    if (fan_tiles == 0) {
        // Whether any cut could do better: not when the whole cloud is a line or a point.
        const Eigen3x3& whole = h.nodes.front().frame;
        if (!(whole.values[1] > 1e-12 * whole.values[2]))
            throw InvalidInput("the points are collinear or coincident: they span no surface to mesh");
        throw InvalidInput("build_surface: no tile has three non-collinear points; choose a coarser cut");
    }

    const Layout layout = make_layout(h, tiles, options);
    const Projection projection = choose_projection(h, tiles, options);
    const double alpha = options.alpha > 0.0 ? options.alpha : options.alpha_factor * layout.mean_edge;

    // T2 input: every vertex but the fan centres. (Adding the centres as Delaunay blockers against
    // triangles spanning small tiles was tried: it gave wrong genus more often on the torus.)
    std::vector<Vec3> gap_points;
    std::vector<std::uint32_t> vertex_of;
    for (std::uint32_t v = 0; v < layout.vertices.size(); ++v) {
        if (layout.tiles[static_cast<std::size_t>(layout.vertices[v].tile)].centre == v)
            continue;
        gap_points.push_back(layout.vertices[v].position);
        vertex_of.push_back(v);
    }
    DelaunayOptions dopt;
    dopt.projected = projection.used;
    dopt.axis_u = projection.u;
    dopt.axis_v = projection.v;
    const Pruner pruner(layout, tiles, projection, alpha, options);
    Candidates candidates;
    if (pruner.know_neighbours())
        candidates = local_candidates(h, pruner, layout, tiles, options.threads);
    else
        candidates = global_candidates(pruner, delaunay_triangles(gap_points, dopt), vertex_of);

    std::vector<Vec3> positions;
    for (const SurfaceVertex& v : layout.vertices)
        positions.push_back(v.position);
    // The front runs on consensus candidates first. Where it strands tiles (at a thin feature such as
    // the tip of an ear, the planes of neighbouring tiles disagree too much for consensus, the tiles
    // are seeded one by one and end up as islands that would be dropped and covered over), it runs
    // again with the fallback candidates that touch a stranded tile.
    const std::vector<int> orientation = pruner.know_neighbours() ? orient_tiles(tiles) : std::vector<int>{};
    Surface surface(layout.vertices.size());
    Front front(layout, tiles, surface, projection, positions, candidates, options.max_turn_degrees, orientation);
    front.run();
    {
        Islands islands = find_islands(surface, tiles);
        const std::vector<bool> stranded = island_tiles(islands);
        if (std::find(stranded.begin(), stranded.end(), true) != stranded.end()) {
            remove_islands(surface, islands);
            front.rescue(stranded);
        }
    }
    // Gaps are filled before the front may close handles: a handle face can otherwise join two
    // neighbouring gaps among a few tiles (a box whose one face is sampled 10 times more densely got a
    // handle across a flat face, between loops of 39 and 17 edges), and at a thin tip the filled gaps
    // let the front join the tip's fans to the rest (the bunny's ear tip at tolerance 0.002 closed on
    // itself as a bubble and was left out: max distance 1.27% -> 0.37% of the diagonal).
    FillResult filled;
    std::size_t islands = 0, restored_islands = 0;
    std::vector<bool> restored_tiles(tiles.size(), false); // fans of islands put back (kept in step 5)
    const std::vector<bool> interior = options.fill_holes ? interior_tiles(tiles, options.interior_gap_degrees) : std::vector<bool>{};
    auto fill = [&](bool before_handles) {
        const FillResult more = fill_holes(h, surface, layout, positions, projection, interior, options, before_handles);
        filled.holes += more.holes;
        filled.faces += more.faces;
    };
    if (options.fill_holes)
        fill(true);
    front.finish();
    if (options.fill_holes) {
        fill(false);
        std::vector<std::vector<std::uint32_t>> removed; // faces of each island dropped
        const std::vector<bool> dropped = drop_islands(surface, tiles, removed);
        islands = static_cast<std::size_t>(std::count(dropped.begin(), dropped.end(), true));
        if (islands > 0) {
            // Two ways on from here; the one that leaves fewer tiles out wins, ties going to the first.
            // (a) Fill again and put back the islands the rest does not cover.
            const Surface after_drop = surface;
            const FillResult filled_after_drop = filled;
            fill(false);
            const auto restored_fans = [&] { return static_cast<std::size_t>(std::count(restored_tiles.begin(), restored_tiles.end(), true)); };
            restored_islands = restore_uncovered_islands(surface, removed, positions, layout.tiles, restored_tiles);
            const std::size_t left_out = islands - restored_fans();
            // (b) Widening can cut fans loose (the rocker arm at 0.005 lost 15 of its top face that way):
            // seed the dropped tiles again, grow the front into the widened holes, fill, drop, put back.
            // It can also break a large island into smaller ones that are not put back, hence the choice.
            if (left_out > 0) {
                Surface way_a = std::move(surface);
                const FillResult filled_a = filled;
                const std::size_t islands_a = islands, restored_a = restored_islands;
                std::vector<bool> restored_tiles_a(tiles.size(), false);
                restored_tiles_a.swap(restored_tiles);
                surface = after_drop;
                filled = filled_after_drop;
                front.regrow(dropped);
                fill(false);
                std::vector<std::vector<std::uint32_t>> removed_again;
                const std::vector<bool> dropped_again = drop_islands(surface, tiles, removed_again);
                islands = static_cast<std::size_t>(std::count(dropped_again.begin(), dropped_again.end(), true));
                restored_islands = 0;
                if (islands > 0) {
                    fill(false);
                    restored_islands = restore_uncovered_islands(surface, removed_again, positions, layout.tiles, restored_tiles);
                }
                if (!(islands - restored_fans() < left_out)) {
                    surface = std::move(way_a);
                    filled = filled_a;
                    islands = islands_a;
                    restored_islands = restored_a;
                    restored_tiles.swap(restored_tiles_a);
                }
            }
        }
    }

    // Pinched vertices become one vertex per fan.
    const std::vector<std::uint32_t> copies = surface.split_pinches();
    std::vector<std::uint32_t> origin(layout.vertices.size());
    std::iota(origin.begin(), origin.end(), 0u);
    origin.insert(origin.end(), copies.begin(), copies.end());

    std::vector<Tri> faces;
    std::vector<std::int32_t> face_tile;
    for (std::uint32_t f = 0; f < surface.faces().size(); ++f)
        if (surface.alive(f)) {
            faces.push_back(surface.faces()[f]);
            face_tile.push_back(surface.face_tile()[f]);
        }
    auto pos = [&](std::uint32_t v) { return layout.vertices[origin[v]].position; };

    // Components over shared edges.
    const auto face_count = static_cast<std::uint32_t>(faces.size());
    std::vector<std::pair<std::uint64_t, std::uint32_t>> edge_faces;
    edge_faces.reserve(3 * faces.size());
    for (std::uint32_t f = 0; f < face_count; ++f)
        for (int k = 0; k < 3; ++k)
            edge_faces.push_back({undirected_key(faces[f][k], faces[f][(k + 1) % 3]), f});
    std::sort(edge_faces.begin(), edge_faces.end());
    UnionFind components(faces.size());
    std::vector<bool> open_face(faces.size(), false);
    std::vector<std::vector<std::uint32_t>> adjacent(faces.size());
    for (std::size_t i = 0; i < edge_faces.size();) {
        std::size_t j = i;
        while (j < edge_faces.size() && edge_faces[j].first == edge_faces[i].first)
            ++j;
        assert(j - i <= 2);
        if (j - i == 1)
            open_face[edge_faces[i].second] = true;
        else {
            components.unite(edge_faces[i].second, edge_faces[i + 1].second);
            adjacent[edge_faces[i].second].push_back(edge_faces[i + 1].second);
            adjacent[edge_faces[i + 1].second].push_back(edge_faces[i].second);
        }
        i = j;
    }
    std::vector<std::uint32_t> roots;
    std::vector<double> volume(faces.size(), 0.0), up(faces.size(), 0.0), facing(faces.size(), 0.0);
    std::vector<bool> closed(faces.size(), true);
    const std::optional<Vec3>& viewpoint = h.cloud.viewpoint;
    for (std::uint32_t f = 0; f < face_count; ++f) {
        const std::uint32_t r = components.find(f);
        if (r == f)
            roots.push_back(f);
        const Vec3 a = pos(faces[f][0]), b = pos(faces[f][1]), c = pos(faces[f][2]);
        volume[r] += dot(a, cross(b, c));
        up[r] += dot(triangle_cross(a, b, c), projection.axis);
        if (viewpoint)
            facing[r] += dot(triangle_cross(a, b, c), *viewpoint - (a + b + c) / 3.0);
        if (open_face[f])
            closed[r] = false;
    }
    // A component that is one tile's fan alone, while that tile has surface neighbours and the surface
    // goes on elsewhere, was passed over by its neighbours' gap triangles (at a sharp edge, say): the
    // surface already covers it, and it would be a loose disk on top. Unless it is an island put back
    // because the rest does not cover it.
    std::vector<std::int32_t> lone_tile(faces.size(), -2); // per root: the one tile, -1 if more or a gap face
    for (std::uint32_t f = 0; f < face_count; ++f) {
        const std::uint32_t r = components.find(f);
        const std::int32_t t = face_tile[f];
        lone_tile[r] = lone_tile[r] == -2 ? t : (lone_tile[r] == t ? t : -1);
    }
    std::vector<bool> dropped(faces.size(), false);
    std::size_t dropped_components = 0;
    if (roots.size() > 1)
        for (std::uint32_t r : roots)
            if (lone_tile[r] >= 0 && !restored_tiles[static_cast<std::size_t>(lone_tile[r])] &&
                !tiles[static_cast<std::size_t>(lone_tile[r])].neighbours.empty()) {
                dropped[r] = true;
                ++dropped_components;
            }
    for (std::uint32_t f = 0; f < face_count; ++f) {
        const std::uint32_t r = components.find(f);
        // Closed surfaces face outward. Open ones face the sensor where the input tells where it stood
        // (a scan is seen from there; a height field's up axis was chosen to point to it, since the fit
        // and the sliver pass keep height-field faces facing up); otherwise height fields face up, and
        // other open surfaces outward as far as their volume tells.
        const bool flip = closed[r]          ? volume[r] < 0.0
                          : projection.used   ? up[r] < 0.0 // the axis points to the viewpoint, if any
                          : viewpoint         ? facing[r] < 0.0
                                              : volume[r] < 0.0;
        if (flip)
            std::swap(faces[f][1], faces[f][2]);
    }
    roots.erase(std::remove_if(roots.begin(), roots.end(), [&](std::uint32_t r) { return dropped[r]; }), roots.end());

    Mesh mesh;
    auto cluster = OpenMesh::getOrMakeProperty<OpenMesh::VertexHandle, int>(mesh, kVertexCluster);
    auto tile_of_face = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile);
    auto gap = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, bool>(mesh, kFaceGap);
    std::vector<Mesh::VertexHandle> handle(origin.size());
    std::vector<bool> used(origin.size(), false);
    std::size_t kept_faces = 0;
    for (std::uint32_t f = 0; f < face_count; ++f)
        if (!dropped[components.find(f)]) {
            ++kept_faces;
            for (std::uint32_t v : faces[f])
                used[v] = true;
        }
    // Reserve OpenMesh's arrays once instead of growing them face by face (an edge per 1.5 faces, plus
    // some for borders).
    mesh.reserve(static_cast<std::size_t>(std::count(used.begin(), used.end(), true)), kept_faces * 3 / 2 + 64, kept_faces);
    for (std::uint32_t v = 0; v < origin.size(); ++v) {
        if (!used[v])
            continue;
        const Vec3 p = pos(v);
        handle[v] = mesh.add_vertex(Mesh::Point(p.x, p.y, p.z));
        cluster[handle[v]] = tiles[static_cast<std::size_t>(layout.vertices[origin[v]].tile)].node;
    }
    SurfaceStats st;
    // Breadth-first per component: each face after the first shares an edge with an added one.
    std::vector<bool> queued(faces.size(), false);
    std::vector<std::uint32_t> order;
    for (std::uint32_t root : roots) {
        std::size_t head = order.size();
        order.push_back(root);
        queued[root] = true;
        for (; head < order.size(); ++head)
            for (std::uint32_t g : adjacent[order[head]])
                if (!queued[g]) {
                    queued[g] = true;
                    order.push_back(g);
                }
    }
    const QuietOpenMesh quiet; // a refused face is counted in the stats, not printed (the library never prints)
    for (std::uint32_t f : order) {
        const Tri& t = faces[f];
        const auto fh = mesh.add_face(handle[t[0]], handle[t[1]], handle[t[2]]);
        if (!fh.is_valid()) {
            ++st.refused_faces;
            continue;
        }
        const std::int32_t ti = face_tile[f];
        tile_of_face[fh] = ti >= 0 ? tiles[static_cast<std::size_t>(ti)].node : -1;
        gap[fh] = ti < 0;
    }
    if (options.collapse_split_points) {
        // Split points may go wherever the shape allows (they carry none); input points on a loop
        // within collapse_tolerance × their tile's RMS plane distance; apexes and fanless points never.
        std::vector<double> slack(mesh.n_vertices(), -1.0), strip_slack(mesh.n_vertices(), -1.0);
        for (std::uint32_t v = 0; v < origin.size(); ++v) {
            if (!used[v])
                continue;
            const SurfaceVertex& sv = layout.vertices[origin[v]];
            const auto t = static_cast<std::size_t>(sv.tile);
            const double rms = h.nodes[static_cast<std::size_t>(tiles[t].node)].rms_plane_distance;
            const auto i = static_cast<std::size_t>(handle[v].idx());
            if (sv.split)
                slack[i] = std::numeric_limits<double>::infinity();
            else if (sv.loop_pos != kNone)
                slack[i] = options.collapse_tolerance * rms;
            if (sv.split || sv.loop_pos != kNone)
                strip_slack[i] = options.strip_tolerance * rms;
        }
        mesh.request_vertex_status();
        mesh.request_edge_status();
        mesh.request_halfedge_status();
        mesh.request_face_status();
        // Split points first (they move nothing), then the input points on what is left of the loops.
        std::vector<double> split_only(slack.size(), -1.0);
        for (std::size_t i = 0; i < slack.size(); ++i)
            if (std::isinf(slack[i]))
                std::swap(split_only[i], slack[i]);
        st.collapsed_split_points = collapse_loop_points(mesh, split_only, projection);
        // Three passes, halving the slack each time (a negative slack stays negative): a point removed in
        // one pass may be moved again by the later ones, so the surface moves from it by at most
        // 1.75 × collapse_tolerance × the RMS plane distance.
        for (int pass = 0; pass < 3; ++pass) {
            st.collapsed_split_points += collapse_loop_points(mesh, slack, projection);
            for (double& x : slack)
                x *= 0.5;
        }
        // Then the strips between tiles, in the same halving passes (after the loops, so that the rim
        // points that carry no shape are gone and the strips' remaining pairs are the ones merged).
        for (int pass = 0; pass < 3 && options.strip_tolerance > 0.0; ++pass) {
            st.collapsed_split_points += collapse_loop_points(mesh, strip_slack, projection, true);
            for (double& x : strip_slack)
                x *= 0.5;
        }
        mesh.garbage_collection();
        mesh.release_face_status();
        mesh.release_halfedge_status();
        mesh.release_edge_status();
        mesh.release_vertex_status();
    }
    for (const Mesh::FaceHandle f : mesh.faces())
        ++(gap[f] ? st.gap_faces : st.fan_faces);
    mesh.update_normals();

    st.tiles = tiles.size();
    st.fan_tiles = fan_tiles;
    st.boundary_points = gap_points.size();
    st.split_points = layout.split_points;
    st.candidates = candidates.triangles.size();
    st.holes_filled = filled.holes;
    st.hole_faces = filled.faces;
    st.split_vertices = copies.size();
    st.components = roots.size();
    st.dropped_fans = islands + dropped_components;
    st.restored_islands = restored_islands;
    st.height_field_used = projection.used;
    st.height_field_axis = projection.axis;
    st.alpha = alpha;
    {
        auto visited = OpenMesh::makeTemporaryProperty<OpenMesh::HalfedgeHandle, bool>(mesh);
        for (auto heh : mesh.halfedges()) {
            if (!mesh.is_boundary(heh) || visited[heh])
                continue;
            ++st.boundary_loops;
            for (auto x = heh; !visited[x]; x = mesh.next_halfedge_handle(x))
                visited[x] = true;
        }
    }
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (stats)
        *stats = st;
    return mesh;
}

} // namespace mrt
