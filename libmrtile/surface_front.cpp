// The advancing front of the manifold assembly (paper §4.3, made to always give an oriented 2-manifold;
// step 3 in surface.cpp) and the candidate triangles it chooses from: the Delaunay triangles of the gap
// triangulation pruned by §4.3's rules (step 2b). Apart from the rest because the front is the largest
// and most intricate stage, and the candidates are made for it alone.
#include "libmrtile/surface_parts.h"

#include "libmrtile/gap_triangulation.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace mrt::surface_detail {

// ---------------------------------------------------------------------------------------------------
// Step 3: advancing front over the candidate triangles.

// Largest angle between a gap face and its tiles' oriented normals (a 90-degree edge bends a gap face by
// about 45 degrees from either tile).
constexpr double kMaxTileDeviationDegrees = 80.0;

// Fallback candidates (proposed by some but not all of their tiles) rank after every consensus one:
// consensus priorities are relative radius (<= 1) times (2 - turn) (<= 3).
constexpr double kFallbackRank = 4.0;

//! `relative_radius[i]`: radius of candidate i divided by its local alpha radius b (<= 1).
//! `fallback[i]`: candidate i lacks consensus and is taken only where no consensus one fits.
//! `orientation`: +1/-1 per tile (orient_tiles), or empty to orient each fan from the face reaching it.
Front::Front(const Layout& layout, const std::vector<Tile>& tiles, Surface& surface, const Projection& projection,
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
    edges_.reserve(3 * (2 * layout.vertices.size() + 16));
    face_normals_.reserve(2 * layout.vertices.size() + 16);
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
void Front::rescue(const std::vector<bool>& stranded)
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
void Front::regrow(const std::vector<bool>& dropped)
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

//! Last: the faces held back because they add a handle, or for a single view (no handles: a depth image
//! is a disc with holes) those of them that add none now. Then a handle is what the surface as
//! split_pinches will leave it says it is (split_view_verdict): a face that joins two fans touching at
//! a pinched vertex only joins two pieces. makes_handle, which sees one piece there, is asked only where
//! that walk cannot tell (QA round 35: a box's wall, pinched to the ground, came out as its own piece).
void Front::finish(bool handles)
{
    reset_pieces();
    allow_handles_ = handles;
    precise_handles_ = !handles;
    if (!handles)
        std::fill(held_.begin(), held_.end(), false);
    edges_.clear(); // cached candidates predate the new rule
    grow_whole_front();
}

//! Grows from every tile in seed order until no candidate can be added.
void Front::run()
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

Vec3 Front::face_normal(std::uint32_t a, std::uint32_t b, std::uint32_t c) const
{
    return normalized(triangle_cross(position(a), position(b), position(c)));
}

// face_normal of surface face f, computed once (faces are never removed while the front runs).
const Vec3& Front::surface_normal(std::uint32_t f) const
{
    const auto& faces = surface_.faces();
    for (std::size_t g = face_normals_.size(); g < faces.size(); ++g)
        face_normals_.push_back(face_normal(faces[g][0], faces[g][1], faces[g][2]));
    return face_normals_[f];
}

// The normalized sum of the face normals at v, remembered until v's faces change (it reads every
// face at v and their corners' positions: many cache misses for a value asked for again and again).
Vec3 Front::vertex_normal(std::uint32_t v) const
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
int Front::seed_orientation(std::uint32_t t) const
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

void Front::place(std::uint32_t t, int orientation)
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
Candidate Front::best(std::uint32_t a, std::uint32_t b) const
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
bool Front::faces_like_tiles(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& nt) const
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
bool Front::merge_in_order(std::uint32_t v, std::uint32_t x, std::uint32_t y) const
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
bool Front::folds_ok(std::uint32_t x, std::uint32_t y, const Vec3& nt) const
{
    const std::uint32_t g = surface_.face_of(y, x);
    if (g == kNone)
        return true;
    return dot(surface_normal(g), nt) >= min_cos_;
}

// Pieces of the surface as split_pinches will leave it: faces joined across shared edges (a pinched
// vertex joins nothing). A union-find over face ids, grown and synced lazily with the faces added.
void Front::sync_pieces()
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

void Front::reset_pieces()
{
    pieces_ = UnionFind();
    pieces_synced_ = 0;
}

// Whether face (b, a, c) joins two boundary cycles of one piece as the surface will be once pinched
// vertices are split (makes_handle walks loops through a pinched vertex from whichever fan it
// arrives by, and sees one piece where the fans may lie in two). The face is glued along the free
// half-edge b -> a and along a -> c and c -> b where those are free; a handle needs two glued
// half-edges on different cycles of one piece. Unknown where the walk meets no plain cycle.
Front::Verdict Front::split_view_verdict(std::uint32_t a, std::uint32_t b, std::uint32_t c)
{
    if (!surface_.on_surface(c))
        return Verdict::no;
    const std::uint32_t fac = surface_.face_of(c, a), fcb = surface_.face_of(b, c);
    if (fac == kNone && fcb == kNone)
        return Verdict::no;
    const std::uint32_t fab = surface_.face_of(a, b);
    if (fab == kNone)
        return Verdict::unknown; // not a front edge (cannot happen: the front runs along faces' half-edges)
    // Glued half-edges of another piece join two pieces: no handle.
    sync_pieces();
    const std::uint32_t mine = pieces_.find(fab);
    const bool ac = fac != kNone && pieces_.find(fac) == mine, cb = fcb != kNone && pieces_.find(fcb) == mine;
    if (!ac && !cb)
        return Verdict::no;
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
            return Verdict::unknown; // not a plain cycle here: leave it to makes_handle
        u = v;
        v = w;
        if (see(u, v))
            return Verdict::no; // every glued half-edge of this piece on this cycle: it splits or shortens
        if (u == x && v == y)
            return Verdict::yes; // the whole cycle seen: a glued half-edge on another cycle of the same piece
        const std::uint32_t z = previous_in_fan(surface_, x, y);
        if (z == kNone)
            return Verdict::unknown;
        y = x;
        x = z;
        if (see(x, y))
            return Verdict::no;
        if (u == x && v == y)
            return Verdict::yes;
    }
    assert(false); // a boundary cycle has at most 3 F half-edges
    return Verdict::unknown;
}

// Whether face (b, a, c) on the front half-edge a -> b would join two different boundary loops of
// one connected piece: that adds a handle (Euler: the face changes V - E + F by -1 and the loop count
// by -1, so the genus grows by 1). Joining another piece, or a vertex of the same loop (which splits
// it in two), keeps the genus. Consensus faces may make the handles a torus needs; fallback faces,
// taken where the tiles' planes disagree, must not.
// When it does, `loop_edges` (if given) gets the length of the loop of a -> b.
bool Front::makes_handle(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::size_t* loop_edges)
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
void Front::recount_parts()
{
    parts_ = UnionFind(layout_.vertices.size());
    for (std::uint32_t f = 0; f < surface_.faces().size(); ++f)
        if (surface_.alive(f)) {
            const Tri& t = surface_.faces()[f];
            parts_.unite(t[0], t[1]);
            parts_.unite(t[0], t[2]);
        }
}

void Front::grow_whole_front()
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
bool Front::unchanged_since(const Candidate& c) const
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

// The state of front half-edge a -> b, or nullptr when no face has that half-edge.
Front::EdgeState* Front::edge_state(std::uint32_t a, std::uint32_t b)
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
Candidate Front::cached_best(EdgeState& e, std::uint32_t a, std::uint32_t b) const
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
void Front::enqueue(EdgeState& e, const Candidate& c)
{
    if (e.queued && e.queued_priority == c.priority && e.queued_c == c.c)
        return;
    e.queued = true;
    e.queued_priority = c.priority;
    e.queued_c = c.c;
    queue_.push(c);
}

void Front::push_best(std::uint32_t a, std::uint32_t b)
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
void Front::refresh(std::uint32_t v)
{
    const CornerList& corners = surface_.corners_at(v); // push_best leaves the surface as it is
    for (const Corner& c : corners) {
        const bool out_twin = surface_.link_enters(v, c.first), in_twin = surface_.link_leaves(v, c.second);
        if (!out_twin)
            push_best(v, c.first);
        if (!in_twin)
            push_best(c.second, v);
    }
}

void Front::grow()
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
        const auto adds_handle = [&] {
            if (precise_handles_) {
                const Verdict v = split_view_verdict(a, b, c);
                return v == Verdict::yes || (v == Verdict::unknown && makes_handle(a, b, c));
            }
            return makes_handle(a, b, c) || split_view_verdict(a, b, c) == Verdict::yes;
        };
        if (!allow_handles_ && adds_handle()) {
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
            const int facing = dot(nt, tiles_[t].normal) >= 0 ? 1 : -1;
            // A height field's fans face up the axis, but a face bridging a wall is nearly vertical and
            // its normal can point away from a tile normal that also looks up: placed as that face
            // had it, the fan was upside down (a ground tile beside a building with unsampled walls
            // came out as a downward flap, cut off by a second loop). Such a face does not reach the
            // tile: its neighbours on the ground do, or it is seeded facing up.
            if (projection_.used && facing != seed_orientation(static_cast<std::uint32_t>(ct))) {
                banned_[top.index] = true;
                e.evaluated = false;
                push_best(a, b);
                continue;
            }
            place(static_cast<std::uint32_t>(ct), !orientation_.empty() && !projection_.used ? orientation_[t] : facing);
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

// ---------------------------------------------------------------------------------------------------
// Step 2b: pruning of the Delaunay triangles (paper §4.3's removal rules, plus chords).

double circumradius(const Vec3& a, const Vec3& b, const Vec3& c)
{
    const double la = distance(b, c), lb = distance(a, c), lc = distance(a, b);
    const double twice_area = norm(triangle_cross(a, b, c));
    if (!(twice_area > 0.0))
        return std::numeric_limits<double>::infinity();
    return la * lb * lc / (2.0 * twice_area);
}

Pruner::Pruner(const Layout& layout, const std::vector<Tile>& tiles, const Projection& projection, double alpha,
               const SurfaceOptions& options)
    : layout_(layout), tiles_(tiles), projection_(projection), alpha_(alpha), options_(options)
{
    // A height field is triangulated in its domain (paper §4.3): tiles across a jump are not
    // neighbours in space but are joined when steps are bridged.
    know_neighbours_ = !projection.used &&
                       std::any_of(tiles.begin(), tiles.end(), [](const Tile& t) { return !t.neighbours.empty(); });
}

//! Radius of t over its local alpha radius b, in (0, 1], or -1 when t is removed.
double Pruner::relative_radius(const Tri& t) const
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

bool Pruner::apart(std::int32_t a, std::int32_t b) const
{
    if (!know_neighbours_ || a == b)
        return false;
    const auto& n = tiles_[static_cast<std::size_t>(a)].neighbours;
    return !std::binary_search(n.begin(), n.end(), static_cast<std::uint32_t>(b));
}

// An edge joining two non-adjacent points of one tile's loop would cross its fan.
bool Pruner::chord(std::uint32_t a, std::uint32_t b) const
{
    const SurfaceVertex& va = layout_.vertices[a];
    const SurfaceVertex& vb = layout_.vertices[b];
    if (va.tile != vb.tile || va.loop_pos == kNone || vb.loop_pos == kNone)
        return false;
    const auto n = static_cast<std::uint32_t>(layout_.tiles[static_cast<std::size_t>(va.tile)].loop.size());
    const std::uint32_t d = va.loop_pos > vb.loop_pos ? va.loop_pos - vb.loop_pos : vb.loop_pos - va.loop_pos;
    return d != 1 && d != n - 1;
}

double Pruner::scale(std::uint32_t v) const
{
    const double e = layout_.tiles[static_cast<std::size_t>(layout_.vertices[v].tile)].edge_length;
    return e > 0.0 ? e : layout_.mean_edge;
}

Vec3 Pruner::flat(const Vec3& p) const
{
    return projection_.used ? Vec3{dot(p, projection_.u), dot(p, projection_.v), 0.0} : p;
}

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

namespace {

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

} // namespace

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

} // namespace mrt::surface_detail
