// Islands and hole filling of the manifold assembly (paper §4.3, extended to always give a valid
// 2-manifold; step 4 in surface.cpp): pieces that broke off the surface are dropped, and put back where
// nothing covers their place, and the gaps left between tiles are filled while the sample's own borders
// stay open. Apart from the front because it works on the surface the front built, through its
// boundary loops.
#include "libmrtile/surface_parts.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/coverage_gap.h"
#include "libmrtile/median.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <unordered_map>
#include <vector>

namespace mrt::surface_detail {

// ---------------------------------------------------------------------------------------------------
// Step 4: boundary loops and hole filling.

// See find_islands: a closed part with at least this many tiles and this share of the points is an
// object of its own.
constexpr std::size_t kMinObjectTiles = 3;
constexpr double kMinObjectShare = 0.01;

Islands find_islands(const Surface& s, const std::vector<Tile>& tiles, const std::vector<TileLoop>& loops)
{
    const auto count = static_cast<std::uint32_t>(s.faces().size());
    UnionFind parts(count);
    std::vector<bool> open_face(count, false);
    for (std::uint32_t f = 0; f < count; ++f) {
        if (!s.alive(f))
            continue;
        const Tri& t = s.faces()[f];
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t g = s.face_of(t[(k + 1) % 3], t[k]);
            if (g != kNone)
                parts.unite(f, g);
            else
                open_face[f] = true;
        }
    }
    std::vector<std::uint32_t> size(count, 0);
    std::vector<bool> closed(count, true);
    std::vector<std::uint32_t> part_of_tile(tiles.size(), kNone);
    for (std::uint32_t f = 0; f < count; ++f)
        if (s.alive(f)) {
            ++size[parts.find(f)];
            if (open_face[f])
                closed[parts.find(f)] = false;
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
    // A closed part of a few tiles or more that holds a fair share of the points is a separate object
    // (a second sphere some ten point spacings from the first, whose facing tiles the coarse spacing of
    // their point samples makes neighbours), not a piece broken off a larger surface: a broken piece is
    // open where it broke off, and a bubble closed at a thin tip is a tile or two. (QA, session 13: of
    // two unit spheres 5 to 12 spacings apart, one was dropped whole.)
    std::vector<std::size_t> part_tiles(count, 0);
    std::vector<double> part_share(count, 0.0);
    for (std::size_t t = 0; t < tiles.size(); ++t)
        if (part_of_tile[t] != kNone) {
            ++part_tiles[part_of_tile[t]];
            part_share[part_of_tile[t]] += loops[t].share;
        }
    auto separate_object = [&](std::uint32_t p) {
        return closed[p] && part_tiles[p] >= kMinObjectTiles && part_share[p] >= kMinObjectShare;
    };
    for (std::size_t t = 0; t < tiles.size(); ++t) {
        const std::uint32_t p = part_of_tile[t];
        if (p == kNone || separate_object(p))
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
    return Islands{std::move(parts), std::move(doomed), std::move(closed), std::move(part_of_tile)};
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

// Finds and removes the islands. Returns the tiles whose fans were removed; `removed` gets each island.
std::vector<bool> drop_islands(Surface& s, const std::vector<Tile>& tiles, const std::vector<TileLoop>& loops,
                               std::vector<DroppedIsland>& removed)
{
    Islands islands = find_islands(s, tiles, loops);
    std::map<std::uint32_t, std::size_t> index_of_part;
    for (std::uint32_t f = 0; f < s.faces().size(); ++f) {
        if (!s.alive(f))
            continue;
        const std::uint32_t part = islands.parts.find(f);
        if (!islands.doomed[part])
            continue;
        const auto inserted = index_of_part.emplace(part, removed.size());
        if (inserted.second)
            removed.push_back({{}, islands.closed[part]});
        removed[inserted.first->second].faces.push_back(f);
        s.remove(f);
    }
    return island_tiles(islands);
}

// The faces of a surface on a grid of cubic cells, to find those near a fill or an island. Closing
// caps a loop whatever its shape, and the cap of a loop that is no hole (the border of a single view,
// whose surface bulges inside it) cuts through the surface: bun000 closed gained 392 crossing pairs.
class FaceGrid
{
public:
    static constexpr std::int32_t kNoTile = -2; // any_within: no tile's faces skipped (gap faces are -1)

    FaceGrid(const Surface& s, const std::vector<Vec3>& positions) : s_(s), positions_(positions), grid_(mean_edge_cell(s, positions))
    {
        for (std::uint32_t f = 0; f < s.faces().size(); ++f)
            if (s.alive(f))
                insert(f);
    }

    //! Adds face f of the surface (one added since the grid was made).
    void insert(std::uint32_t f)
    {
        ++alive_;
        grid_.insert(f, box_of(s_.faces()[f]));
    }

    //! Whether a live face of the surface, other than those of tile `skip_tile`, comes within r of c.
    bool any_within(const Vec3& c, double r, std::int32_t skip_tile = kNoTile) const
    {
        const auto near = [&](std::uint32_t f) {
            const Tri& t = s_.faces()[f];
            return s_.alive(f) && (skip_tile == kNoTile || s_.face_tile()[f] != skip_tile) &&
                   point_triangle_distance(c, positions_[t[0]], positions_[t[1]], positions_[t[2]]) <= r;
        };
        const Vec3 reach{r, r, r};
        const BoundingBox box{c - reach, c + reach};
        if (grid_.cell_count(box) > static_cast<double>(alive_)) { // a reach as large as the surface: ask every face
            for (std::uint32_t f = 0; f < s_.faces().size(); ++f)
                if (near(f))
                    return true;
            return false;
        }
        return grid_.any_candidate(box, near);
    }

    // Whether a face of `patch` meets a face of the surface with which it shares no corner.
    bool crosses(const std::vector<Tri>& patch) const
    {
        if (patch.empty())
            return false;
        BoundingBox box = box_of(patch.front());
        for (const Tri& t : patch) {
            const BoundingBox bt = box_of(t);
            box = {min(box.min, bt.min), max(box.max, bt.max)};
        }
        std::vector<std::uint32_t> near;
        if (grid_.cell_count(box) > static_cast<double>(alive_)) { // a cap as large as the surface: every face is near
            for (std::uint32_t f = 0; f < s_.faces().size(); ++f)
                if (s_.alive(f))
                    near.push_back(f);
        } else {
            grid_.for_each_candidate(box, [&](std::uint32_t f) { near.push_back(f); });
            std::sort(near.begin(), near.end());
            near.erase(std::unique(near.begin(), near.end()), near.end());
        }
        for (const Tri& t : patch) {
            const BoundingBox bt = box_of(t);
            const std::array<Vec3, 3> a{positions_[t[0]], positions_[t[1]], positions_[t[2]]};
            for (std::uint32_t f : near) {
                const Tri& u = s_.faces()[f];
                if (!s_.alive(f) || !bt.meets(box_of(u)))
                    continue;
                bool shared = false;
                for (std::uint32_t v : t)
                    shared = shared || v == u[0] || v == u[1] || v == u[2];
                if (!shared && triangles_meet(a, {positions_[u[0]], positions_[u[1]], positions_[u[2]]}))
                    return true;
            }
        }
        return false;
    }

private:
    // Cells twice the surface's mean edge: a face overlaps a few, and a query near a face a few more.
    static double mean_edge_cell(const Surface& s, const std::vector<Vec3>& positions)
    {
        double length = 0.0;
        std::size_t edges = 0;
        for (std::uint32_t f = 0; f < s.faces().size(); ++f)
            if (s.alive(f))
                for (int k = 0; k < 3; ++k, ++edges)
                    length += distance(positions[s.faces()[f][k]], positions[s.faces()[f][(k + 1) % 3]]);
        return edges > 0 && length > 0.0 ? 2.0 * length / static_cast<double>(edges) : 1.0;
    }
    BoundingBox box_of(const Tri& t) const
    {
        const Vec3 &a = positions_[t[0]], &b = positions_[t[1]], &c = positions_[t[2]];
        return {min(min(a, b), c), max(max(a, b), c)};
    }

    const Surface& s_;
    const std::vector<Vec3>& positions_;
    std::size_t alive_ = 0;
    BoxGrid grid_;
};

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
std::size_t restore_uncovered_islands(Surface& s, const std::vector<DroppedIsland>& removed,
                                      const std::vector<Vec3>& positions, const std::vector<TileLoop>& loops,
                                      std::vector<bool>& restored_tiles, double reach)
{
    std::size_t restored = 0;
    std::unique_ptr<FaceGrid> grid; // the rest's faces, made at the first island that needs it
    for (const DroppedIsland& dropped : removed) {
        const std::vector<std::uint32_t>& island = dropped.faces;
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
        if (dropped.closed)
            continue;
        // Every face within reach of a centre: a grid of the rest's faces (made once, and given the faces
        // of the islands put back) instead of a pass over all faces per island (nested spheres a few
        // spacings apart drop whole spheres as islands: 58% of the time went to those passes).
        if (!grid)
            grid = std::make_unique<FaceGrid>(s, positions);
        std::size_t covered = 0;
        for (const auto& [c, r] : centres)
            covered += grid->any_within(c, r) ? 1 : 0;
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
            for (std::size_t k = s.faces().size() - added; k < s.faces().size(); ++k)
                grid->insert(static_cast<std::uint32_t>(k));
            ++restored;
            for (std::int32_t t : island_tiles)
                restored_tiles[static_cast<std::size_t>(t)] = true;
        }
    }
    return restored;
}

std::vector<bool> lone_fans_to_keep(const Surface& s, const std::vector<Vec3>& positions,
                                    const std::vector<TileLoop>& loops, const std::vector<std::int32_t>& tiles, double reach)
{
    std::vector<bool> keep(tiles.size(), false);
    std::unique_ptr<FaceGrid> grid; // made at the first fan that needs it
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const TileLoop& tl = loops[static_cast<std::size_t>(tiles[k])];
        if (tl.centre == kNone || tl.share < kMinRestoredShare)
            continue;
        if (!grid)
            grid = std::make_unique<FaceGrid>(s, positions);
        const double r = reach * tl.spacing;
        if (grid->any_within(positions[tl.centre], r, tiles[k]))
            continue;
        // Or its rim: two hemisphere fans of a sphere cut into two tiles share their rim at the equator,
        // while their centres stand apart (fitted apexes, half a radius off the other disc).
        std::size_t rim_covered = 0;
        for (std::uint32_t v : tl.loop)
            rim_covered += grid->any_within(positions[v], r, tiles[k]) ? 1 : 0;
        keep[k] = 2 * rim_covered < tl.loop.size();
    }
    return keep;
}

namespace {

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
    std::vector<Vec3> at(n); // the loop's positions in loop order: the O(n³) loop below reads them
    for (std::size_t i = 0; i < n; ++i)
        at[i] = positions[loop[i]];
    // cost[i * n + j]: the least area of the sub-polygon i..j; by_end[j * n + i] is the same, so that
    // the inner loop reads both of its terms in memory order (a 300-edge loop: 720 KB each).
    std::vector<double> cost(n * n, inf), by_end(n * n, inf);
    std::vector<std::uint32_t> split(n * n, kNone);
    for (std::size_t i = 0; i + 1 < n; ++i)
        cost[i * n + i + 1] = by_end[(i + 1) * n + i] = 0.0;
    for (std::size_t len = 2; len < n; ++len) {
        for (std::size_t i = 0; i + len < n; ++i) {
            const std::size_t j = i + len;
            if (!diagonal_ok(i, j))
                continue;
            double& best = cost[i * n + j];
            for (std::size_t k = i + 1; k < j; ++k) {
                const double c0 = cost[i * n + k], c1 = by_end[j * n + k];
                // No worse split is ever taken, valid or not: the bound goes first, the shape tests after
                // it only for a split that would be the best so far (same result, far fewer tests).
                if (c0 == inf || c1 == inf || !(c0 + c1 < best))
                    continue;
                const std::uint32_t a = loop[i], b = loop[k], c = loop[j];
                if (a == b || b == c || a == c)
                    continue;
                const Vec3 normal = triangle_cross(at[i], at[k], at[j]);
                const double total = c0 + c1 + norm(normal);
                if (!(total < best) || is_sliver(at[i], at[k], at[j]) ||
                    (!(dot(normal, up) > 0.0) && !(dot(normal, facing[i] + facing[k] + facing[j]) > 0.0)))
                    continue;
                best = by_end[j * n + i] = total;
                split[i * n + j] = static_cast<std::uint32_t>(k);
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

// The first repeat of a loop: the smallest i whose vertex comes again, and the first j > i where it
// does; {0, 0} when none. Linear (a hash of first occurrences): the quadratic search it replaces took a
// minute over a terrain with spikes, whose loops ran to 27,000 edges through 78 pinches (QA round 61).
std::pair<std::size_t, std::size_t> first_repeat(const std::vector<std::uint32_t>& l)
{
    constexpr std::size_t kRepeated = std::numeric_limits<std::size_t>::max();
    std::unordered_map<std::uint32_t, std::size_t> first;
    first.reserve(l.size());
    std::pair<std::size_t, std::size_t> best{0, 0};
    for (std::size_t j = 0; j < l.size(); ++j) {
        const auto [it, added] = first.emplace(l[j], j);
        // A vertex's first repeat is its first j; of the repeats, the one whose vertex came first wins.
        if (!added && it->second != kRepeated && (best.second == 0 || it->second < best.first))
            best = {it->second, j};
        if (!added)
            it->second = kRepeated; // later repeats of this vertex are not its first
    }
    return best;
}

// Splits a loop at repeated vertices (a loop through a pinch twice bounds two holes that touch there).
std::vector<std::vector<std::uint32_t>> simple_loops(const std::vector<std::uint32_t>& loop)
{
    // Most loops repeat no vertex: tell so in O(n log n) before the search for the first repeat
    // (thin walls leave loops of thousands of edges, traced again on every pass).
    std::vector<std::uint32_t> sorted = loop;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end())
        return {loop};
    std::vector<std::vector<std::uint32_t>> out;
    std::vector<std::vector<std::uint32_t>> work{loop};
    while (!work.empty()) {
        std::vector<std::uint32_t> l = std::move(work.back());
        work.pop_back();
        const auto [i, j] = first_repeat(l);
        if (j == 0) {
            out.push_back(std::move(l));
            continue;
        }
        std::vector<std::uint32_t> a(l.begin() + static_cast<std::ptrdiff_t>(i), l.begin() + static_cast<std::ptrdiff_t>(j));
        std::vector<std::uint32_t> b(l.begin() + static_cast<std::ptrdiff_t>(j), l.end());
        b.insert(b.end(), l.begin(), l.begin() + static_cast<std::ptrdiff_t>(i));
        work.push_back(std::move(a));
        work.push_back(std::move(b));
    }
    return out;
}

} // namespace

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

namespace {

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

// Spots of a patch: a barycentric grid on each triangle, its step at most `step` along every edge.
std::vector<Vec3> patch_spots(const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double step)
{
    std::vector<Vec3> spots;
    for (const Tri& t : patch) {
        all_triangle_spots(positions[t[0]], positions[t[1]], positions[t[2]], step, 64, [&](const Vec3& spot) {
            spots.push_back(spot);
            return true;
        });
    }
    return spots;
}

} // namespace

// Whether the input points cover a hole: every spot of its fill patch (sampled about reach / 1.5
// apart) has an input point within `reach` (1.5 spacings of the tiles). A hole in the sample (the bunny's base) has an empty middle;
// a hole the tiles left in a sampled surface has points all over it: a tile built from a sample of
// at most TileOptions::max_points of its node's points can leave a gap wider than a point spacing (a
// uniformly sampled fandisk kept one 8 spacings wide in its flat top). Counting points inside instead
// also filled real scan holes whose loops took in some sampled surface beside them, and a tunnel of
// the 3-hole solid.
bool points_cover_hole(const Hierarchy& h, const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double reach)
{
    if (patch.empty() || !(reach > 0.0))
        return false;
    const std::vector<Vec3> spots = patch_spots(positions, patch, reach / 1.5);
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
    for (const std::uint32_t i : points_in_box(h, box))
        cells[cell_of(h.cloud.positions[i])].push_back(h.cloud.positions[i]);
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

namespace {

// Whether the hierarchy saw a hole where these tiles are: the coverage gap of one of their nodes or of
// an ancestor up to 4 levels above (whose tile covers theirs) is at least `radius` and dominates its
// error (gap_dominates: a curved node's gap is no hole). The judgement by density at node scale
// (coverage_gap.h) is what tells a hole from a sparse patch; the surface stage only asks where a hole
// it was told of lies.
bool hole_among(const Hierarchy& h, const Layout& layout, const std::int32_t* tiles, std::size_t count, double radius)
{
    // Up to kLevels above each tile: a node at most about 2^kLevels tiles large (its stored gap is the
    // largest of its subtree, so a node much higher up would answer for holes anywhere under it).
    constexpr int kLevels = 4;
    for (std::size_t i = 0; i < count; ++i) {
        std::int32_t id = layout.tiles[static_cast<std::size_t>(tiles[i])].node;
        for (int level = 0; level <= kLevels && id >= 0; ++level) {
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            if (n.coverage_gap >= radius && gap_dominates(n))
                return true;
            id = n.parent;
        }
    }
    return false;
}

// The point spacing of the sparser side of a density step around the disc at `centre` of `radius` (in the plane of the unit
// vectors u and v): where two samples of different density meet (a dense scan of half a surface merged
// with a sparse scan of all of it), the tiles and the points around a gap take the dense one's spacing,
// and the sparse sample's own gaps beside the dense part look like holes. Judged on the points from
// `radius` to 3 × `radius` away (in space, so that a curved surface keeps its points and a sheet far
// above, a roof over the ground, is left out), in 8 sectors around the disc, each of about the disc's
// own area; the 4 emptiest are its sparser half. A step is found when
//  - at most one sector is empty: the border of a scan or a shadow beside a hole empties 3 or more, and
//    then nothing tells the density of the sparse side;
//  - the sparser half's points lie at least kMinStep times farther from their nearest neighbours
//    (medians) than the denser half's: a sparse sample, not the frayed edge of a dense one (a roof's
//    edge beside the ground of an airborne scan, whose few points in the sparse sectors have neighbours
//    at the roof's spacing).
// The spacing is that of the sparser half's points over its 4 sectors' area; 0 when no step is found,
// and when it is not looked for: the sparser half's fullest sector holds `max_sector_points` or more,
// or `worth` (if given) says no to that spacing (the nearest-neighbour medians cost 64 searches of every
// point around, and asked of every hole of a uniform sample they made meshing a 230k-point chair 4x
// slower, QA round 35).
double sparse_side_spacing(const Hierarchy& h, const Vec3& centre, double radius, const Vec3& u, const Vec3& v,
                           std::size_t max_sector_points, const std::function<bool(double)>& worth = {})
{
    constexpr int kSectors = 8;
    constexpr int kSparseSectors = 4; // the sparser half
    constexpr double kOuter = 3.0;    // a sector's area is π (3² - 1) r² / 8 = π r², the disc's own
    // A density step of 4:1 or more. Measured: 3.4-7.6 at the 1:50 step of QA round 32's torus; 1.1-1.4
    // at the roof edges of an airborne scan (1 point/m², QA terrain_1M), which the two rules before it
    // would have filled.
    constexpr double kMinStep = 2.0;
    constexpr std::size_t kMaxJudged = 64; // points per half whose neighbours are looked for (a median)
    if (!(radius > 0.0))
        return 0.0;
    const double outer = kOuter * radius;
    // Out to a radius beyond the annulus, so that the annulus's points have their neighbours.
    const double reach = outer + radius;
    const BoundingBox box{centre - Vec3{reach, reach, reach}, centre + Vec3{reach, reach, reach}};
    std::vector<Vec3> near;
    std::vector<int> sector_of; // per point near: its sector of the annulus, -1 outside it
    std::array<std::size_t, kSectors> counts{};
    for (const std::uint32_t i : points_in_box(h, box)) {
        const Vec3 d = h.cloud.positions[i] - centre;
        const double r2 = dot(d, d);
        if (r2 > reach * reach)
            continue;
        int sector = -1;
        if (r2 > radius * radius && r2 <= outer * outer) {
            sector = std::clamp(static_cast<int>(std::floor((std::atan2(dot(d, v), dot(d, u)) + kPi) / (2.0 * kPi) * kSectors)), 0,
                                kSectors - 1);
            ++counts[static_cast<std::size_t>(sector)];
        }
        near.push_back(h.cloud.positions[i]);
        sector_of.push_back(sector);
    }
    std::array<int, kSectors> order{};
    for (int k = 0; k < kSectors; ++k)
        order[static_cast<std::size_t>(k)] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return counts[static_cast<std::size_t>(a)] < counts[static_cast<std::size_t>(b)]; });
    if (counts[static_cast<std::size_t>(order[1])] == 0 || counts[static_cast<std::size_t>(order[kSparseSectors - 1])] >= max_sector_points)
        return 0.0;
    std::size_t sparse_count = 0;
    for (int k = 0; k < kSparseSectors; ++k)
        sparse_count += counts[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])];
    const double sparse_area = kSparseSectors * kPi * radius * radius; // a sector's area is the disc's
    const double spacing = std::sqrt(sparse_area / static_cast<double>(std::max<std::size_t>(1, sparse_count)));
    if (worth && !worth(spacing))
        return 0.0;
    // The median distance to the nearest other point of the annulus's points in the sparser or denser
    // half (every k-th of them, at most kMaxJudged). Neighbours within a hundredth of the radius count as
    // the same point: clumps of near-equal points (repeated frames) would make every distance 0.
    const double same2 = 1e-4 * radius * radius;
    const auto median_nearest = [&](bool sparser) {
        std::vector<std::size_t> members;
        for (std::size_t i = 0; i < near.size(); ++i)
            if (sector_of[i] >= 0 &&
                (std::find(order.begin(), order.begin() + kSparseSectors, sector_of[i]) != order.begin() + kSparseSectors) == sparser)
                members.push_back(i);
        const std::size_t stride = members.size() / kMaxJudged + 1;
        std::vector<double> nearest;
        for (std::size_t m = 0; m < members.size(); m += stride) {
            double best = std::numeric_limits<double>::infinity();
            for (const Vec3& q : near) {
                const double d2 = squared_distance(near[members[m]], q);
                if (d2 > same2)
                    best = std::min(best, d2);
            }
            nearest.push_back(best);
        }
        return std::sqrt(upper_median_in_place(nearest));
    };
    const double sparse_nearest = median_nearest(true), dense_nearest = median_nearest(false);
    const bool step = std::isfinite(sparse_nearest) && dense_nearest > 0.0 && sparse_nearest >= kMinStep * dense_nearest;
    return step ? spacing : 0.0;
}

// Whether the empty disc at `centre` of `radius` is a chance gap of the sparser side of a density step
// (sparse_side_spacing), not a hole of the sample: at that side's density (its 4th-emptiest sector) the disc
// would hold fewer points than an empty region must miss to count as a hole
// (CoverageOptions::min_missing_points).
bool explained_by_sparse_side(const Hierarchy& h, const Vec3& centre, double radius, const Vec3& u, const Vec3& v)
{
    const auto min_missing = static_cast<std::size_t>(std::ceil(CoverageOptions{}.min_missing_points));
    return sparse_side_spacing(h, centre, radius, u, v, min_missing) > 0.0;
}

// Whether the points cover a hole too wide for the mean-width test (fill_holes) at the spacing of the
// sparser side of a density step around it (sparse_side_spacing; the disc about the fill patch's centre, in its
// plane, of radius its mean width, 2 area / perimeter: a disc's radius). The test's spacing is the
// largest of the tiles around the hole, which at a density step are the dense side's or mixed: a 1:6
// step (half a torus scanned densely, all of it sparsely, with noise) kept 3 holes of 15-23 edges open
// along the seam, whose sparse points lie farther apart than 1.5 of those spacings; at the sparse
// side's spacing (1.7-2.4 times theirs) all three are covered.
bool covered_at_sparse_side(const Hierarchy& h, const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double area,
                            double perimeter, double spacing)
{
    Vec3 centre{0, 0, 0}, normal{0, 0, 0};
    double weight = 0.0;
    for (const Tri& t : patch) {
        const Vec3 c = triangle_cross(positions[t[0]], positions[t[1]], positions[t[2]]);
        const double a = norm(c);
        normal += c;
        centre += (positions[t[0]] + positions[t[1]] + positions[t[2]]) * (a / 3.0);
        weight += a;
    }
    // A chance gap of the sparser side is at most about 2.3 of its spacings in radius: at steps up to
    // 80:1 in density (9:1 in spacing) that is within kMaxRadiusSpacings of the tiles' spacing. Wider
    // holes are not judged (the sector counts cost a search of every point within 4 radii).
    constexpr double kMaxRadiusSpacings = 20.0;
    const double radius = perimeter > 0.0 ? 2.0 * area / perimeter : 0.0;
    if (!(weight > 0.0) || !(norm(normal) > 0.0) || !(radius > 0.0) || radius > kMaxRadiusSpacings * spacing)
        return false;
    normal = normalized(normal);
    const Vec3 u = perpendicular_axis(normal), v = cross(normal, u);
    // Covered: no spot of the patch is farther from the points than the radius of an empty disc that
    // holds min_missing_points at the sparser side's density (coverage_gap.h: emptier discs are chance).
    // Asked first (the sparser side's spacing from the sector counts must exceed the tiles'), since
    // both are cheap beside the medians.
    const auto reach = [](double sparse_spacing) { return std::sqrt(CoverageOptions{}.min_missing_points / kPi) * sparse_spacing; };
    const auto worth = [&](double sparse_spacing) {
        return sparse_spacing > spacing && points_cover_hole(h, positions, patch, reach(sparse_spacing));
    };
    return sparse_side_spacing(h, centre / weight, radius, u, v, std::numeric_limits<std::size_t>::max(), worth) > 0.0;
}

// Removes the candidates for which drop(triangle) holds, keeping the others' order. Judged in parallel
// blocks, each candidate on its own: the result does not depend on the thread count.
template <typename Drop>
void drop_candidates_if(Candidates& candidates, std::size_t threads, const Drop& drop)
{
    const std::size_t count = candidates.triangles.size();
    std::vector<char> dropped(count, 0);
    run_parallel_ranges(count, 64, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            dropped[i] = drop(candidates.triangles[i]) ? 1 : 0;
    });
    Candidates kept;
    for (std::size_t i = 0; i < count; ++i)
        if (!dropped[i]) {
            kept.triangles.push_back(candidates.triangles[i]);
            kept.relative_radius.push_back(candidates.relative_radius[i]);
            kept.fallback.push_back(candidates.fallback[i]);
        }
    candidates = std::move(kept);
}

} // namespace

bool covers_sample_hole(const Hierarchy& h, const Layout& layout, const std::int32_t* tiles, std::size_t count,
                        const std::vector<Vec3>& positions, const std::vector<Tri>& patch, double spacing)
{
    // A hole of the kind the tiles miss lies in a nearly flat stretch: judge it in the tiles' plane.
    const double min_cos = std::cos(radians(30.0));
    Vec3 normal{0, 0, 0};
    for (std::size_t i = 0; i < count; ++i) {
        const Vec3& n = layout.tiles[static_cast<std::size_t>(tiles[i])].normal;
        const Vec3& first = layout.tiles[static_cast<std::size_t>(tiles[0])].normal;
        if (std::abs(dot(n, first)) < min_cos)
            return false;
        normal += dot(n, first) < 0 ? -n : n;
    }
    // A spot of a counted empty region lies at least min_radius_spacings (4) local spacings, less a
    // grid cell, from every point, the patch's corners included: narrower patches cannot reach one.
    constexpr double kMinCircumradius = 2.5;
    constexpr double kMaxThickness = 0.1; // RMS distance to the plane over the margin
    const double min_radius = kMinHoleSpacings * spacing;
    if (patch.empty() || !(spacing > 0.0) || !hole_among(h, layout, tiles, count, min_radius))
        return false;
    const bool wide = std::any_of(patch.begin(), patch.end(), [&](const Tri& t) {
        return circumradius(positions[t[0]], positions[t[1]], positions[t[2]]) > kMinCircumradius * spacing;
    });
    if (!wide || !(norm(normal) > 0.0))
        return false;
    const std::vector<Vec3> spots = patch_spots(positions, patch, spacing);
    normal = normalized(normal);
    const Vec3 axis_u = -perpendicular_axis(normal); // normal × helper: the frame this map has always had
    const Vec3 axis_v = cross(normal, axis_u);
    // The points around the patch, far enough out to see a hole whole and the density around it.
    BoundingBox box = bounding_box(spots);
    Vec3 centre{0, 0, 0};
    for (const Vec3& p : spots)
        centre += p;
    centre = centre / static_cast<double>(spots.size());
    const double margin = std::max(0.5 * box.diagonal(), 8.0 * spacing);
    box.min = box.min - Vec3{margin, margin, margin};
    box.max = box.max + Vec3{margin, margin, margin};
    std::vector<Vec3> points;
    for (const std::uint32_t i : points_in_box(h, box))
        if (std::abs(dot(h.cloud.positions[i] - centre, normal)) <= margin)
            points.push_back(h.cloud.positions[i]);
    // Only where the surface around is flat: a curved stretch (the tip of an ear) projected into one
    // plane leaves empty regions that are no holes.
    double sum2 = 0.0;
    for (const Vec3& p : points)
        sum2 += dot(p - centre, normal) * dot(p - centre, normal);
    if (points.empty() || std::sqrt(sum2 / static_cast<double>(points.size())) > kMaxThickness * margin)
        return false;
    const CoverageMap map(points, axis_u, axis_v);
    if (!(map.gap() >= min_radius))
        return false;
    // The map judges an empty region by the density of all the points around it, which the denser side
    // dominates at a density step: each region under the patch is judged once more by the sparser half
    // of its surroundings. A region at least min_radius (5 spacings) in radius that this explains has a
    // sparser half whose spacing is over twice `spacing` (π (5 s)² / s'² < 16): only a density step
    // of 4:1 or more changes the answer, not a uniform sample's variation.
    std::vector<Vec3> judged; // the regions' centres, each judged once
    return std::any_of(spots.begin(), spots.end(), [&](const Vec3& p) {
        Vec3 hole_centre;
        double hole_radius = 0.0;
        if (!map.gap_disc(p, min_radius, hole_centre, hole_radius))
            return false;
        for (const Vec3& c : judged) {
            // The same cell, up to rounding (the spots' heights above the plane differ).
            const Vec3 d = c - hole_centre;
            if (std::abs(dot(d, axis_u)) < 1e-6 * hole_radius && std::abs(dot(d, axis_v)) < 1e-6 * hole_radius)
                return false;
        }
        judged.push_back(hole_centre);
        return !explained_by_sparse_side(h, hole_centre, hole_radius, axis_u, axis_v);
    });
}

void drop_uncovered_candidates(const Hierarchy& h, const Layout& layout, const std::vector<Vec3>& positions,
                               std::size_t threads, Candidates& candidates)
{
    drop_candidates_if(candidates, threads, [&](const Tri& t) {
        double spacing = 0.0, full_spacing = 0.0;
        for (std::uint32_t v : t) {
            const TileLoop& tile = layout.tiles[static_cast<std::size_t>(layout.vertices[v].tile)];
            spacing = std::max(spacing, tile.spacing);
            full_spacing = std::max(full_spacing, tile.full_spacing);
        }
        const std::array<std::int32_t, 3> tiles{layout.vertices[t[0]].tile, layout.vertices[t[1]].tile, layout.vertices[t[2]].tile};
        return full_spacing > 0.0 && full_spacing < spacing &&
               covers_sample_hole(h, layout, tiles.data(), 3, positions, {t}, full_spacing);
    });
}

void drop_seen_through_candidates(const Hierarchy& h, const Layout& layout, const std::vector<Vec3>& positions,
                                  std::size_t threads, Candidates& candidates)
{
    if (!h.cloud.viewpoint)
        return;
    const Vec3 eye = *h.cloud.viewpoint;
    // A gap triangle may cut across a concave corner: the corner's points lie behind it by up to half
    // its longest edge (a right angle), so only points deeper than that, and than a few spacings of
    // noise, count; and three of them, against stray points.
    constexpr double kDepthPerEdge = 0.75;
    constexpr double kDepthSpacings = 4.0;
    constexpr double kDepthNoise = 4.0; // × the tiles' RMS plane distance: a noisy scan's spread
    constexpr std::size_t kMinHits = 3;
    drop_candidates_if(candidates, threads, [&](const Tri& t) {
        const Vec3 a = positions[t[0]], b = positions[t[1]], c = positions[t[2]];
        double spacing = 0.0, noise = 0.0;
        for (std::uint32_t v : t) {
            const TileLoop& tile = layout.tiles[static_cast<std::size_t>(layout.vertices[v].tile)];
            spacing = std::max(spacing, tile.full_spacing);
            if (tile.node >= 0)
                noise = std::max(noise, h.nodes[static_cast<std::size_t>(tile.node)].rms_plane_distance);
        }
        const double longest = std::max({distance(a, b), distance(b, c), distance(c, a)});
        const double margin = std::max({kDepthPerEdge * longest, kDepthSpacings * spacing, kDepthNoise * noise});
        const Vec3 n = cross(b - a, c - a);
        if (!(norm(n) > 0.0) || std::abs(dot(eye - a, n)) < 1e-12 * norm(n) * norm(eye - a))
            return false; // degenerate, or seen edge-on: nothing is seen through it
        const Vec3 unit_n = normalized(n);
        const double eye_side = dot(eye - a, unit_n);
        // The part of its view cone behind it, as deep as the margin's reach and then some.
        const double depth = 4.0 * margin;
        BoundingBox box{min(min(a, b), c), max(max(a, b), c)};
        for (const Vec3& p : {a, b, c}) {
            const Vec3 beyond = p + normalized(p - eye) * depth;
            box.min = min(box.min, beyond);
            box.max = max(box.max, beyond);
        }
        std::size_t hits = 0;
        for (const std::uint32_t j : points_in_box(h, box)) {
            const Vec3& p = h.cloud.positions[j];
            const double side = dot(p - a, unit_n);
            if (std::abs(side) <= margin || (side > 0.0) == (eye_side > 0.0))
                continue; // near its plane, or on the eye's side
            // Does the ray from the eye to p pass through the triangle? (The plane test above puts the
            // eye and p on opposite sides, so the crossing lies between them.)
            const Vec3 x = eye + (p - eye) * (eye_side / (eye_side - side));
            const double wa = dot(cross(b - x, c - x), n), wb = dot(cross(c - x, a - x), n), wc = dot(cross(a - x, b - x), n);
            if (wa >= 0.0 && wb >= 0.0 && wc >= 0.0 && ++hits >= kMinHits)
                return true;
        }
        return false;
    });
}

// Fills the holes that are gaps between tiles (see SurfaceOptions::hole_factor, interior_gap_degrees,
// max_gap_width), or in FillMode::Close every hole up to SurfaceOptions::close_holes edges, widening those
// that cannot be triangulated as they are. FillMode::BeforeHandles: the front
// has not yet been allowed to close handles, and a loop around a tube it still has to close looks like
// a hole among interior tiles; only holes small by perimeter, or among interior tiles with fewer edges
// than a handle closes around, are filled then.
FillResult fill_holes(const Hierarchy& h, Surface& s, const Layout& layout, const std::vector<Vec3>& positions,
                      const Projection& projection, const std::vector<bool>& interior, const SurfaceOptions& options,
                      FillMode mode, FillCache* cache)
{
    const bool before_handles = mode == FillMode::BeforeHandles;
    const bool closing = mode == FillMode::Close;
    const std::size_t max_edges = closing ? options.close_holes : options.max_hole_edges;
    FillResult result;
    // Vertices around which gap faces were removed to open up a hole that could not be filled as it was.
    std::vector<bool> widened(positions.size(), false);
    std::unique_ptr<FaceGrid> grid; // closing only: the surface before the caps
    constexpr int kPasses = 4;
    for (int pass = 0; pass < kPasses; ++pass) {
        bool changed = false;
        std::vector<std::vector<std::uint32_t>> loops;
        for (const auto& traced : boundary_loops(s, positions))
            for (auto& l : simple_loops(traced))
                loops.push_back(std::move(l));
        for (const auto& loop : loops) {
            const std::size_t n = loop.size();
            if (n > max_edges || n < 3)
                continue;
            // Skip loops that an earlier fill or widening of this pass changed.
            bool current = true;
            for (std::size_t i = 0; i < n && current; ++i)
                current = !s.has_halfedge(loop[i], loop[(i + 1) % n]) && s.has_halfedge(loop[(i + 1) % n], loop[i]);
            if (!current)
                continue;
            std::vector<std::int32_t> loop_tiles;
            double perimeter = 0.0, largest_tile = 0.0, spacing = 0.0, full_spacing = 0.0;
            bool was_widened = false, surrounded = true;
            for (std::size_t i = 0; i < n; ++i) {
                // A height field's holes are measured in its domain: a gap at a jump is small there.
                Vec3 d = positions[loop[(i + 1) % n]] - positions[loop[i]];
                if (projection.used)
                    d -= projection.axis * dot(d, projection.axis);
                perimeter += norm(d);
                const std::int32_t t = layout.vertices[loop[i]].tile;
                loop_tiles.push_back(t);
                surrounded = surrounded && !closing && interior[static_cast<std::size_t>(t)]; // unused when closing
                largest_tile = std::max(largest_tile, layout.tiles[static_cast<std::size_t>(t)].perimeter);
                spacing = std::max(spacing, layout.tiles[static_cast<std::size_t>(t)].spacing);
                full_spacing = std::max(full_spacing, layout.tiles[static_cast<std::size_t>(t)].full_spacing);
                was_widened = was_widened || widened[loop[i]];
            }
            std::sort(loop_tiles.begin(), loop_tiles.end());
            loop_tiles.erase(std::unique(loop_tiles.begin(), loop_tiles.end()), loop_tiles.end());
            // A widened hole was small before we opened it: it may be up to three times as large.
            const double limit = options.hole_factor * largest_tile * (was_widened ? 3.0 : 1.0);
            // A hole among interior tiles is a gap whatever its size; elsewhere only small holes are.
            if (!closing && (loop_tiles.size() < 2 ||
                             (perimeter > limit && (!surrounded || (before_handles && n >= kMinHandleLoopEdges)))))
                continue;
            std::vector<Tri> around;
            if (cache)
                for (const std::uint32_t v : loop) {
                    for (const std::uint32_t f : s.faces_at(v))
                        around.push_back(s.faces()[f]);
                    around.push_back({kNone, kNone, kNone}); // ends the vertex's faces
                }
            FillCache::Entry* known = nullptr;
            if (cache)
                if (const auto it = cache->by_loop.find(loop); it != cache->by_loop.end() && it->second.around == around)
                    known = &it->second;
            const std::vector<Tri> patch = known ? known->patch : fill_triangulation(s, positions, loop, projection);
            if (cache && !known)
                known = &(cache->by_loop[loop] = FillCache::Entry{std::move(around), patch});
            // The loop and its patch decide covered_at_sparse_side: asked once per patch, not once per pass.
            const auto sparse_cover = [&](double area, double perimeter, double spacing) {
                if (known && known->sparse_cover >= 0)
                    return known->sparse_cover == 1;
                const bool covered = covered_at_sparse_side(h, positions, patch, area, perimeter, spacing);
                if (known)
                    known->sparse_cover = covered ? 1 : 0;
                return covered;
            };
            // Every point lies in some tile, so a hole holds no points: a gap between tiles is about a
            // point spacing wide, and a hole much wider than that (mean width 2 area / perimeter) is a
            // hole in the sample itself (the bunny's base), which stays open.
            double area = 0.0;
            for (const Tri& t : patch) {
                const Vec3 c = triangle_cross(positions[t[0]], positions[t[1]], positions[t[2]]);
                area += 0.5 * (projection.used ? std::abs(dot(c, projection.axis)) : norm(c));
            }
            if (!closing && options.max_gap_width > 0.0 && spacing > 0.0 &&
                2.0 * area > options.max_gap_width * spacing * perimeter && !points_cover_hole(h, positions, patch, 1.5 * spacing) &&
                !sparse_cover(area, perimeter, spacing))
                continue;
            // Tiles built from a sample leave gaps as wide as the sample's spacing, so the test above
            // misses holes narrower than that but wider than the points' own spacing (a hole in a flat
            // plate among coarse tiles): ask the points around the patch (a gap between tiles has
            // points all over it).
            if (!closing && options.max_gap_width > 0.0 && full_spacing > 0.0 && full_spacing < spacing &&
                covers_sample_hole(h, layout, loop_tiles.data(), loop_tiles.size(), positions, patch, full_spacing))
                continue;
            // A cap that cuts through the surface is no closing: the hole stays open (and is counted).
            if (closing) {
                if (!grid)
                    grid = std::make_unique<FaceGrid>(s, positions);
                if (grid->crosses(patch)) {
                    ++result.crossing;
                    continue;
                }
            }
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
            // Closing widens nothing: a loop it cannot fill may be where the sample ends, not a gap, and
            // opening it up would only cut faces off the surface there.
            if (pass + 1 == kPasses || closing)
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

} // namespace mrt::surface_detail
