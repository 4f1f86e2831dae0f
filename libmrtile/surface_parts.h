#pragma once
//! \file surface_parts.h
//! \brief INTERNAL header of build_surface (surface.h), not part of the public API: what the files of the
//! gap triangulation and manifold assembly (paper §4.3) share: the surface's vertices and tile loops, the
//! manifold surface under construction and its boundary walks, the advancing front, the candidate pruner,
//! and the islands and hole filling.
//! \details Only surface.cpp, surface_parts.cpp, surface_front.cpp and surface_holes.cpp include it, and it
//! changes with them whenever they do; no public header includes it. (The install rule copies every header
//! of libmrtile/, so it is installed too, but nothing outside the library may rely on it.) The method is
//! described at the top of surface.cpp; each function's comment stands at its definition.

#include "libmrtile/gap_triangulation.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/huge_pages.h"
#include "libmrtile/surface.h"
#include "libmrtile/tiles.h"
#include "libmrtile/union_find.h"
#include "libmrtile/vec3.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <queue>
#include <unordered_map>
#include <utility>
#include <map>
#include <vector>

namespace mrt::surface_detail {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
using Tri = std::array<std::uint32_t, 3>;

inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b)
{
    return (static_cast<std::uint64_t>(a) << 32) | b;
}

inline Vec3 triangle_cross(const Vec3& a, const Vec3& b, const Vec3& c)
{
    return cross(b - a, c - a);
}

// A triangle so thin that its area vanishes against its longest edge: it would be a zero-area face.
inline bool is_sliver(const Vec3& a, const Vec3& b, const Vec3& c)
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
    // The spacing of all its node's points: smaller than `spacing` where the tile was built from a
    // sample (TileOptions::max_points), so that gaps between tiles are as wide as the sample's spacing.
    double full_spacing = 0.0;
    std::int32_t node = -1;           // the tile's hierarchy node
    Vec3 normal{0, 0, 1};             // the tile's unit normal (Tile::normal; its sign is arbitrary)
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

Layout make_layout(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options);

// ---------------------------------------------------------------------------------------------------
// Step 2a: height-field test.

struct Projection
{
    bool used = false;
    Vec3 axis{0, 0, 1}, u{1, 0, 0}, v{0, 1, 0};
    //! With `used`: per tile, whether it is steeper than SurfaceOptions::max_tilt_degrees (it gets no
    //! fan; its points join the gap triangulation).
    std::vector<bool> steep;
    //! Not used, no CRS, but the tiles would pass as an airborne scan's (axis within 10 degrees of z,
    //! walls and overhangs within the airborne allowances).
    bool looks_airborne = false;
};

// Largest share of the points on steep tiles for which HeightField::Auto still chooses a height field.
constexpr double kMaxSteepShare = 0.1;
// In an airborne scan, largest share of the tiles whose centre may lie inside another tile's outline:
// at a roof's edge a tile takes in roof and ground points on both sides of the unsampled wall and
// leans over its neighbours (QA round 32: 349 buildings, 0.6-1% of the tiles).
constexpr double kMaxOverhangShare = 0.02;

Projection choose_projection(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options);

// ---------------------------------------------------------------------------------------------------
// Step 2c: consistent tile orientation.

std::vector<int> orient_tiles(const std::vector<Tile>& tiles);

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

//! The oriented manifold-in-progress the front grows: faces, and per vertex its corners. Not for
//! concurrent use, not even const: queries of large links keep sorted copies (link_index).
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
        if (link.size() > kLargeLink)
            return large_link_arcs(v);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
        for (const Corner& e : link)
            if (!has_link_edge_into(link, e.first))
                out.push_back({e.first, arc_end(v, e.first)});
        return out;
    }

    //! The last vertex of the arc of v that starts at `first` (the arcs(v) entry (first, last)), or kNone
    //! when no arc starts there. The boundary walks take one step per call: without building every arc.
    std::uint32_t arc_end(std::uint32_t v, std::uint32_t first) const
    {
        const CornerList& link = corners_[v];
        if (link.size() > kLargeLink) { // its arcs are kept (large_link_arcs): look it up
            for (const auto& [arc_first, arc_last] : large_link_arcs(v))
                if (arc_first == first)
                    return arc_last;
            return kNone;
        }
        if (has_link_edge_into(link, first))
            return kNone;
        std::uint32_t end = kNone;
        for (const Corner& e : link)
            if (e.first == first) {
                end = e.second;
                break;
            }
        // Links are simple paths (can_add), so the walk ends; the bound only guards that invariant.
        for (std::size_t steps = 0; end != kNone && steps < link.size(); ++steps) {
            const Corner* next = nullptr;
            for (const Corner& o : link)
                if (o.first == end) {
                    next = &o;
                    break;
                }
            if (!next)
                break;
            end = next->second;
        }
        return end;
    }

    //! The first vertex of the arc of v that ends at `last`, or kNone when no arc ends there (the inverse
    //! of arc_end).
    std::uint32_t arc_start(std::uint32_t v, std::uint32_t last) const
    {
        const CornerList& link = corners_[v];
        if (link.size() > kLargeLink) {
            for (const auto& [arc_first, arc_last] : large_link_arcs(v))
                if (arc_last == last)
                    return arc_first;
            return kNone;
        }
        std::uint32_t start = kNone;
        for (const Corner& e : link)
            if (e.second == last) {
                start = e.first;
                break;
            }
        if (start == kNone || has_link_edge_out_of(link, last))
            return kNone;
        for (std::size_t steps = 0; steps < link.size(); ++steps) {
            const Corner* previous = nullptr;
            for (const Corner& o : link)
                if (o.second == start) {
                    previous = &o;
                    break;
                }
            if (!previous)
                break;
            start = previous->first;
        }
        return start;
    }

    //! Whether a link edge of v ends at x (a face (v, ?, x)): then half-edge v -> x has its twin.
    bool link_enters(std::uint32_t v, std::uint32_t x) const
    {
        const CornerList& link = corners_[v];
        if (link.size() > kLargeLink) {
            const LinkIndex& index = link_index(v);
            return std::binary_search(index.into.begin(), index.into.end(), x);
        }
        return has_link_edge_into(link, x);
    }
    //! Whether a link edge of v starts at x (a face (v, x, ?)): then half-edge x -> v has its twin.
    bool link_leaves(std::uint32_t v, std::uint32_t x) const
    {
        const CornerList& link = corners_[v];
        if (link.size() > kLargeLink)
            return link_step(link_index(v).next, x) != kNone;
        return has_link_edge_out_of(link, x);
    }

    //! arcs(v).size() without building them.
    std::size_t arc_count(std::uint32_t v) const
    {
        const CornerList& link = corners_[v];
        if (link.size() > kLargeLink)
            return large_link_arcs(v).size();
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
        for (std::uint32_t w : faces_[f]) // these links change without a clock tick
            link_index_.erase(w);
        link_index_.erase(to);
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
    // Links longer than this are searched through sorted copies, not scanned per corner: the scans
    // are quadratic, and a terrain with spikes made vertices of 256-512 faces, where they took a
    // quarter of the meshing (QA round 61).
    static constexpr std::size_t kLargeLink = 24;

    // A large link's edges sorted two ways, and its arcs, kept until the vertex's faces change (clock:
    // when they were sorted): the front asks about one spike vertex for each candidate around it, and
    // sorting its link on every question was half of meshing a spiky terrain at tolerance 0.
    struct LinkIndex
    {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> next;     // (first, second), by first
        std::vector<std::uint32_t> into;                               // the seconds, sorted
        std::vector<std::pair<std::uint32_t, std::uint32_t>> arcs;     // arcs(), once asked for
        bool arcs_known = false;
        std::uint64_t clock = 0;
    };
    LinkIndex& link_index(std::uint32_t v) const
    {
        LinkIndex& index = link_index_[v];
        if (index.clock != 0 && changed_[v] <= index.clock)
            return index;
        const CornerList& link = corners_[v];
        index.next.clear();
        index.into.clear();
        for (const Corner& e : link) {
            index.next.push_back({e.first, e.second});
            index.into.push_back(e.second);
        }
        std::sort(index.next.begin(), index.next.end());
        std::sort(index.into.begin(), index.into.end());
        index.arcs.clear();
        index.arcs_known = false;
        index.clock = std::max<std::uint64_t>(clock_, 1);
        return index;
    }
    //! The link vertex after x (the second of the link edge from x in `steps`, LinkIndex::next), or
    //! kNone. At most one link edge leaves a vertex (half-edge uniqueness).
    static std::uint32_t link_step(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& steps, std::uint32_t x)
    {
        const auto it = std::lower_bound(steps.begin(), steps.end(), std::pair<std::uint32_t, std::uint32_t>{x, 0});
        return it != steps.end() && it->first == x ? it->second : kNone;
    }

    // arcs() of a large link, in the same order (the link's), in O(d log d): each link vertex starts
    // at most one link edge and ends at most one (links are simple paths, can_add). An arc starts at a
    // link vertex that no link edge ends at.
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& large_link_arcs(std::uint32_t v) const
    {
        const CornerList& link = corners_[v];
        LinkIndex& index = link_index(v);
        if (index.arcs_known)
            return index.arcs;
        std::vector<std::pair<std::uint32_t, std::uint32_t>>& out = index.arcs;
        for (const Corner& e : link) {
            if (std::binary_search(index.into.begin(), index.into.end(), e.first))
                continue;
            std::uint32_t end = link_step(index.next, e.first);
            for (std::size_t steps = 0; end != kNone && steps < link.size(); ++steps) {
                const std::uint32_t after = link_step(index.next, end);
                if (after == kNone)
                    break;
                end = after;
            }
            out.push_back({e.first, end});
        }
        index.arcs_known = true;
        return out;
    }

    static bool has_link_edge_into(const CornerList& link, std::uint32_t x)
    {
        for (const Corner& o : link)
            if (o.second == x)
                return true;
        return false;
    }
    static bool has_link_edge_out_of(const CornerList& link, std::uint32_t x)
    {
        for (const Corner& o : link)
            if (o.first == x)
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
        if (link.size() > kLargeLink)
            return large_link_ok(v, x, y);
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

    // link_ok of a large link, the same tests through its index (O(log d) a step, not O(d)): the
    // spike vertices of a 40:1 scan-line terrain at tolerance 0 gathered thousands of faces on the way.
    bool large_link_ok(std::uint32_t v, std::uint32_t x, std::uint32_t y) const
    {
        const CornerList& link = corners_[v];
        if (large_link_arcs(v).empty())
            return false; // closed (is_closed): every link vertex has a link edge into it
        const LinkIndex& index = link_index(v);
        std::uint32_t end = y;
        std::size_t steps = 1;
        // As link_ok's walk, which takes the first corner leaving `end` (the only one).
        while (end != x && steps <= link.size()) { // the bound only guards the invariant (links are paths)
            const std::uint32_t after = link_step(index.next, end);
            if (after == kNone)
                break;
            end = after;
            ++steps;
        }
        if (end != x)
            return true;
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
    // Large links only, see link_index. Const queries fill it: a Surface serves one thread at a time.
    mutable std::unordered_map<std::uint32_t, LinkIndex> link_index_;
};

// Angles of points around a centre, counter-clockwise about a normal, from a fixed zero direction:
// orders the fans of a pinched vertex.
class AngleAround
{
public:
    AngleAround(const Vec3& centre, const Vec3& normal) : centre_(centre)
    {
        e1_ = perpendicular_axis(normal);
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

// Walks along the boundary loops of a Surface (surface_parts.cpp).
std::uint32_t next_boundary_vertex(const Surface& s, const std::vector<Vec3>& positions, std::uint32_t u, std::uint32_t v);
std::uint32_t previous_boundary_vertex(const Surface& s, const std::vector<Vec3>& positions, std::uint32_t u, std::uint32_t v);
std::uint32_t next_in_fan(const Surface& s, std::uint32_t u, std::uint32_t v);
std::uint32_t previous_in_fan(const Surface& s, std::uint32_t u, std::uint32_t v);

// ---------------------------------------------------------------------------------------------------
// Step 3: advancing front over the candidate triangles.

struct Candidates
{
    std::vector<Tri> triangles;
    std::vector<double> relative_radius; // radius / local b, in (0, 1]
    std::vector<bool> fallback;          // proposed by some of its tiles but not all (local candidates)
};

// Circumradius of a triangle (infinite when degenerate).
double circumradius(const Vec3& a, const Vec3& b, const Vec3& c);

// Whether the input points cover the triangles of `patch` (over `positions`): every spot of it, about
// reach / 1.5 apart, has an input point within `reach`.
bool points_cover_hole(const Hierarchy& h, const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double reach);

// A hole between tiles counts when a disc of this many of their points' spacings (TileLoop::
// full_spacing, measured over whole tiles) fits in it: a remeshed part's flat faces leave empty strips
// that are wide against the dense rims beside them but not against its tiles (the rocker arm, a
// closed part, got 4 holes at 4 spacings).
constexpr double kMinHoleSpacings = 5.0;

// Whether a fill of `patch` (triangles over `positions`) would cover a hole of the sample: the input
// points around it, projected into its plane, leave an empty region under it that their own density
// says should hold points (coverage_gap.h), at least kMinHoleSpacings × `spacing` wide (the points'
// spacing at the patch, TileLoop::full_spacing); only patches with a triangle wider than 2.5 spacings
// are judged, and only where the hierarchy saw a hole that wide among the tiles (a node of one of
// them, or up to 4 levels above, whose gap dominates its error): on its own the density test finds
// holes in real scans that are sparse patches.
// The points are projected into the plane of the tiles `tiles`; where their normals differ by more
// than 30 degrees (a fill across a sharp edge or the rim of a thin part) the patch is not judged. An
// empty region beside a density step whose sparser side would leave it empty by chance (a dense scan
// of half a surface merged with a sparse scan of all of it) is no hole (surface_holes.cpp,
// explained_by_sparse_side).
bool covers_sample_hole(const Hierarchy& h, const Layout& layout, const std::int32_t* tiles, std::size_t count,
                        const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double spacing);

// Drops the candidates that would cover a hole of the sample (covers_sample_hole) between tiles built
// from samples (TileOptions::max_points): such tiles leave gaps as wide as their sample's spacing, and
// the alpha test, which follows the tiles' sizes, keeps triangles across holes narrower than that.
void drop_uncovered_candidates(const Hierarchy& h, const Layout& layout, const std::vector<Vec3>& positions,
                               std::size_t threads, Candidates& candidates);

// Drops the candidates the scanner saw through: with the cloud's viewpoint known, at least three input
// points lie behind one, along their rays from the viewpoint, deeper than 0.75 × its longest edge, 4
// point spacings and 4 × its tiles' RMS plane distance (a noisy scan's spread). A gap face across a
// concave corner has the corner's points behind it, at most half its longest edge deep; a face with
// points deeper behind it spans space the scan saw empty: across a depth jump (a ball above the floor
// joined to the floor behind it), not between neighbouring tiles of one surface.
void drop_seen_through_candidates(const Hierarchy& h, const Layout& layout, const std::vector<Vec3>& positions,
                                  std::size_t threads, Candidates& candidates);

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

// The member functions, with their comments, are in surface_front.cpp.
class Front
{
public:
    Front(const Layout& layout, const std::vector<Tile>& tiles, Surface& surface, const Projection& projection,
          const std::vector<Vec3>& positions, const Candidates& candidates, double max_turn_degrees,
          const std::vector<int>& orientation);
    void rescue(const std::vector<bool>& stranded);
    void regrow(const std::vector<bool>& dropped);
    void finish(bool handles);
    void run();

private:
    Vec3 position(std::uint32_t v) const { return layout_.vertices[v].position; }
    Vec3 face_normal(std::uint32_t a, std::uint32_t b, std::uint32_t c) const;
    const Vec3& surface_normal(std::uint32_t f) const;
    Vec3 vertex_normal(std::uint32_t v) const;
    int seed_orientation(std::uint32_t t) const;
    void place(std::uint32_t t, int orientation);
    Candidate best(std::uint32_t a, std::uint32_t b) const;
    bool faces_like_tiles(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& nt) const;
    bool merge_in_order(std::uint32_t v, std::uint32_t x, std::uint32_t y) const;
    bool folds_ok(std::uint32_t x, std::uint32_t y, const Vec3& nt) const;
    void sync_pieces();
    void reset_pieces();
    enum class Verdict { no, yes, unknown };
    Verdict split_view_verdict(std::uint32_t a, std::uint32_t b, std::uint32_t c);
    bool makes_handle(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::size_t* loop_edges = nullptr);
    void recount_parts();
    void grow_whole_front();
    bool unchanged_since(const Candidate& c) const;

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

    EdgeState* edge_state(std::uint32_t a, std::uint32_t b);
    Candidate cached_best(EdgeState& e, std::uint32_t a, std::uint32_t b) const;
    void enqueue(EdgeState& e, const Candidate& c);
    void push_best(std::uint32_t a, std::uint32_t b);
    void refresh(std::uint32_t v);
    void grow();

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
    std::vector<std::pair<std::uint32_t, std::uint32_t>, HugePageAllocator<std::pair<std::uint32_t, std::uint32_t>>> rows_; // {other vertex, candidate}
    std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> queue_;
    std::vector<bool> banned_;   // fallback candidates found to add a handle
    std::vector<bool> held_;     // consensus candidates found to add a handle (wait for finish)
    bool allow_handles_ = false;
    bool precise_handles_ = false; // finish(false): split_view_verdict decides, makes_handle where it cannot
    std::vector<bool> rescuing_; // fallback candidates in use (they touch a stranded tile)
    UnionFind pieces_;                  // see sync_pieces
    std::uint32_t pieces_synced_ = 0;
    UnionFind parts_;          // connected pieces of the surface, over vertices
    // By face and edge, see edge_state. Reserved for the faces a closed surface over the layout's
    // vertices has (about 2 per vertex), on huge pages: grown by doubling, it was a quarter of the page
    // faults of a fine cut (each doubling a fresh block, huge_pages.h).
    std::vector<EdgeState, HugePageAllocator<EdgeState>> edges_;
    mutable std::vector<Vec3, HugePageAllocator<Vec3>> face_normals_; // see surface_normal (grows with the faces)
    struct CachedNormal
    {
        Vec3 normal;
        std::uint64_t clock = 0;
        bool valid = false;
    };
    mutable std::vector<CachedNormal, HugePageAllocator<CachedNormal>> vertex_normals_; // see vertex_normal
};

// ---------------------------------------------------------------------------------------------------
// Step 2b: pruning of the Delaunay triangles (paper §4.3's removal rules, plus chords).

// The removal rules of paper §4.3 (one-tile triangles, local alpha radius b) plus chords across a
// fan, slivers, and triangles joining tiles that do not meet on the surface.
class Pruner
{
public:
    Pruner(const Layout& layout, const std::vector<Tile>& tiles, const Projection& projection, double alpha,
           const SurfaceOptions& options);
    bool know_neighbours() const { return know_neighbours_; }
    double relative_radius(const Tri& t) const;

private:
    bool apart(std::int32_t a, std::int32_t b) const;
    bool chord(std::uint32_t a, std::uint32_t b) const;
    double scale(std::uint32_t v) const;
    Vec3 flat(const Vec3& p) const;

    const Layout& layout_;
    const std::vector<Tile>& tiles_;
    const Projection& projection_;
    double alpha_;
    const SurfaceOptions& options_;
    bool know_neighbours_ = false;
};

Candidates global_candidates(const Pruner& pruner, const DelaunayTriangles& dt, const std::vector<std::uint32_t>& vertex_of);

Candidates local_candidates(const Hierarchy& h, const Pruner& pruner, const Layout& layout, const std::vector<Tile>& tiles,
                            std::size_t threads);

// ---------------------------------------------------------------------------------------------------
// Step 4: boundary loops and hole filling.

// The pieces of the surface that broke off a larger one: a part with a tile whose surface neighbour
// lies in a larger part, a small part (under 5% of the largest) with a tile whose neighbour lies
// outside it, and a part of gap faces only. Such an island meets the rest of the surface in the
// sampled data but failed to join it (typically at a thin or sharp feature), and the larger surface
// around it then has a hole with the island inside that no disk can fill. Parts whose tiles have no
// neighbours elsewhere, or closed parts of a few tiles holding a fair share of the points (separate
// objects), are not islands.
struct Islands
{
    UnionFind parts{0};                      // faces -> part
    std::vector<bool> doomed;                // per part root: an island
    std::vector<bool> closed;                // per part root: no face of the part has a free edge
    std::vector<std::uint32_t> part_of_tile; // kNone for tiles without faces
};

// An island taken out of the surface: its (now dead) faces, in face order, and whether it was closed.
struct DroppedIsland
{
    std::vector<std::uint32_t> faces;
    bool closed = false;
};

Islands find_islands(const Surface& s, const std::vector<Tile>& tiles, const std::vector<TileLoop>& loops);
std::vector<bool> island_tiles(const Islands& islands);
void remove_islands(Surface& s, Islands& islands);
std::vector<bool> drop_islands(Surface& s, const std::vector<Tile>& tiles, const std::vector<TileLoop>& loops,
                               std::vector<DroppedIsland>& removed);

std::size_t restore_uncovered_islands(Surface& s, const std::vector<DroppedIsland>& removed,
                                      const std::vector<Vec3>& positions, const std::vector<TileLoop>& loops,
                                      std::vector<bool>& restored_tiles, double reach = 2.0);

//! Of `tiles` (each a fan standing alone as a component, which step 5 drops as passed over by its
//! neighbours' gap triangles), those to keep: the rest of the surface does not cover them (neither the
//! fan's centre, the terms on which restore_uncovered_islands counts an island as covered, nor half its
//! rim lie within `reach` × the tile's spacing of a live face of another tile), and they hold a share of
//! the points an island that small needs to be put back. `positions` covers every vertex of `s`.
std::vector<bool> lone_fans_to_keep(const Surface& s, const std::vector<Vec3>& positions,
                                    const std::vector<TileLoop>& loops, const std::vector<std::int32_t>& tiles,
                                    double reach = 2.0);

struct FillResult
{
    std::size_t holes = 0;
    std::size_t faces = 0;
    std::size_t crossing = 0; //!< FillMode::Close: holes left open because their cap would cross the surface
};

std::vector<bool> interior_tiles(const std::vector<Tile>& tiles, double max_gap_degrees);

// Which holes fill_holes fills.
enum class FillMode
{
    BeforeHandles, //!< gaps between tiles, before the front may close handles (small ones only)
    Gaps,          //!< gaps between tiles (SurfaceOptions::hole_factor, interior_gap_degrees, max_gap_width)
    Close,         //!< every hole of at most SurfaceOptions::close_holes edges, the sample's own too
};

// Patches fill_triangulation made, by loop, with the faces around the loop's vertices they were made
// among: fill_holes meets most loops again in its later passes and modes unchanged (a coarse cut's
// 300-edge gaps cost an O(n³) triangulation each time), and a patch depends on nothing else.
struct FillCache
{
    struct Entry
    {
        std::vector<Tri> around; // the faces at each loop vertex in the surface's order, vertex by vertex
        std::vector<Tri> patch;
        signed char sparse_cover = -1; // covered_at_sparse_side of the patch: -1 not asked yet, else 0 or 1
    };
    std::map<std::vector<std::uint32_t>, Entry> by_loop;
};

FillResult fill_holes(const Hierarchy& h, Surface& s, const Layout& layout, const std::vector<Vec3>& positions,
                      const Projection& projection, const std::vector<bool>& interior, const SurfaceOptions& options,
                      FillMode mode, FillCache* cache = nullptr);

} // namespace mrt::surface_detail
