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
// Files: build_surface, with steps 5 and 6, is here; steps 1, 2a and 2c and the walks along boundary loops
// are in surface_parts.cpp, steps 2b and 3 in surface_front.cpp, step 4 in surface_holes.cpp, and what
// they share is declared in surface_parts.h (internal).
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
#include "libmrtile/pca.h"
#include "libmrtile/surface_parts.h"
#include "libmrtile/union_find.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <utility>

namespace mrt {

// The stages defined in the other surface*.cpp files are used here as they were when they shared one
// anonymous namespace with build_surface.
using namespace surface_detail;

namespace {

std::uint64_t undirected_key(std::uint32_t a, std::uint32_t b)
{
    return a < b ? edge_key(a, b) : edge_key(b, a);
}

// ---------------------------------------------------------------------------------------------------
// Step 5: components, orientation, OpenMesh.

// ---------------------------------------------------------------------------------------------------
// Step 6: removing the loop points that carry no shape (ε-split points, then near-collinear rim points).

// Largest turn of a fan face when a loop point is collapsed away; a gap face (thin, its normal is noise)
// only has to stay within 75 degrees of the surface around the point.
constexpr double kMaxCollapseTurnDegrees = 20.0;
// How far (in point spacings of its tile) a collapse may move the mesh's border.
constexpr double kBorderSlackSpacings = 1.0;
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
// The border points collapsed away so far, per border edge (from, to: vertex indices, in the border's
// direction): every later collapse that changes the edge keeps them within its slack too. Without it,
// each collapse is judged against the border as the last one left it, and the moves add up: chords
// that grow pass after pass across a hole of the sample (QA round 56: a sphere with holes at tolerance
// 0.02, the mesh up to 0.028 of the diagonal from the points over a hole; 0.017 with it).
using BorderHistory = std::map<std::pair<int, int>, std::vector<Vec3>>;

// Whether collapsing the border point v into w keeps the border within `slack` of where it was: the
// border path p, v, q becomes p, w, q (p, q when w is one of them), and v, the border points collapsed
// into p-v and v-q before (`history`), and the old path must lie within slack of the new one, and the
// new one (w and its segments' midpoints) within slack of the old. Both ways: v can lie on the new path
// while w is far from the old one (a rim point next to p collapsed across a strip into a point well
// inside: the new border passes by v but cuts a corner off the sample, QA round 54's trimmed last ring
// of a cylinder). A slack of 0 still allows a billionth of the segments' length (rounding).
bool border_keeps_shape(const Mesh& mesh, Mesh::VertexHandle v, Mesh::VertexHandle w, double slack, const BorderHistory& history)
{
    const Mesh::HalfedgeHandle out = mesh.halfedge_handle(v); // a border halfedge for a border vertex
    if (!mesh.is_boundary(out))
        return false;
    const Mesh::VertexHandle next = mesh.to_vertex_handle(out), previous = mesh.from_vertex_handle(mesh.prev_halfedge_handle(out));
    const Vec3 at = to_vec3(mesh.point(v)), q = to_vec3(mesh.point(next)), p = to_vec3(mesh.point(previous));
    const Vec3 m = to_vec3(mesh.point(w));
    const auto segment_distance = [](const Vec3& x, const Vec3& a, const Vec3& b) {
        const Vec3 d = b - a;
        const double len2 = dot(d, d);
        const double t = len2 > 0.0 ? std::clamp(dot(x - a, d) / len2, 0.0, 1.0) : 0.0;
        return distance(x, a + d * t);
    };
    const bool along = w == next || w == previous;
    const auto new_path_distance = [&](const Vec3& x) {
        return along ? segment_distance(x, p, q) : std::min(segment_distance(x, p, m), segment_distance(x, m, q));
    };
    const double bound = std::max(slack, 1e-9 * (distance(at, p) + distance(at, q)));
    if (new_path_distance(at) > bound)
        return false;
    for (const auto& edge : {std::make_pair(previous.idx(), v.idx()), std::make_pair(v.idx(), next.idx())})
        if (const auto it = history.find(edge); it != history.end())
            for (const Vec3& x : it->second)
                if (new_path_distance(x) > bound)
                    return false;
    if (along)
        return true; // the old path's farthest point from p, q is v
    const auto old_path_distance = [&](const Vec3& x) { return std::min(segment_distance(x, p, at), segment_distance(x, at, q)); };
    return std::max({old_path_distance(m), old_path_distance((p + m) * 0.5), old_path_distance((m + q) * 0.5)}) <= bound;
}

// Records the collapse of the border point v into w (before it is made): the new border edges keep v
// and what the old ones kept.
void remember_border_collapse(const Mesh& mesh, Mesh::VertexHandle v, Mesh::VertexHandle w, BorderHistory& history)
{
    const Mesh::HalfedgeHandle out = mesh.halfedge_handle(v);
    const int next = mesh.to_vertex_handle(out).idx(), previous = mesh.from_vertex_handle(mesh.prev_halfedge_handle(out)).idx();
    std::vector<Vec3> before, after;
    if (const auto it = history.find({previous, v.idx()}); it != history.end()) {
        before = std::move(it->second);
        history.erase(it);
    }
    if (const auto it = history.find({v.idx(), next}); it != history.end()) {
        after = std::move(it->second);
        history.erase(it);
    }
    const Vec3 at = to_vec3(mesh.point(v));
    if (w.idx() == next || w.idx() == previous) { // one edge, previous -> next
        std::vector<Vec3>& kept = history[{previous, next}];
        kept = std::move(before);
        kept.push_back(at);
        kept.insert(kept.end(), after.begin(), after.end());
        return;
    }
    before.push_back(at); // v lies between both new edges' ends: each keeps it
    after.push_back(at);
    history[{previous, w.idx()}] = std::move(before);
    history[{w.idx(), next}] = std::move(after);
}

std::size_t collapse_loop_points(Mesh& mesh, const std::vector<double>& slack, const std::vector<double>& border_slack,
                                 const Projection& projection, BorderHistory& history, bool across_strips = false)
{
    auto tile_of_face = OpenMesh::getProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile);
    const double min_cos = std::cos(radians(kMaxCollapseTurnDegrees));
    auto point = [&](Mesh::VertexHandle v) { return to_vec3(mesh.point(v)); };
    std::size_t removed = 0;
    const std::size_t n = mesh.n_vertices();
    std::vector<bool> touched(n, false);
    std::vector<Mesh::HalfedgeHandle> outgoing; // v's, refilled per vertex (one allocation per pass)
    for (std::size_t i = 0; i < n; ++i) {
        const Mesh::VertexHandle v(static_cast<int>(i));
        if (!(slack[i] >= 0.0) || touched[i] || mesh.status(v).deleted())
            continue;
        const Vec3 at = point(v);
        Vec3 around; // the surface normal at v, computed when a first edge qualifies
        bool have_around = false;
        outgoing.clear();
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
            if (!keeps_shape || !(moved <= slack[i]))
                continue;
            // On the mesh's border the distance to the surface says nothing of the border itself: the
            // faces around a border point may grow over the hole beside it (on a flat plate every
            // collapse keeps the surface where it was, and rim points collapsed into a window). The
            // border may move by border_slack alone (about a point spacing of its tile: the strip
            // between a tile's hull and the sample's own border is that wide), not by the collapse's
            // slack, a multiple of the tile's RMS plane distance, which is large on curved tiles.
            const bool on_border = mesh.is_boundary(v);
            if (on_border && !border_keeps_shape(mesh, v, w, border_slack[i], history))
                continue;
            // The link condition last: it is the costliest test and the shape tests fail more often.
            if (!mesh.is_collapse_ok(h))
                continue;
            if (on_border)
                remember_border_collapse(mesh, v, w, history);
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

} // namespace

Mesh build_surface(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options, SurfaceStats* stats)
{
    Mesh mesh;
    build_surface(h, tiles, mesh, options, stats);
    return mesh;
}

namespace {

// Tiles built by a caller index the hierarchy (node, boundary points; when `h` is given) and each other
// (neighbours): an index out of range was read out of bounds (QA round 51: a neighbour 99999).
void check_tiles(const Hierarchy* h, const std::vector<Tile>& tiles, const char* function)
{
    for (const Tile& t : tiles) {
        if (h && (t.node < 0 || static_cast<std::size_t>(t.node) >= h->nodes.size()))
            throw InvalidInput(std::string(function) + ": tile of node " + std::to_string(t.node) + " is not in the hierarchy");
        if (h)
            for (const std::uint32_t p : t.boundary)
                if (p >= h->cloud.positions.size())
                    throw InvalidInput(std::string(function) + ": tile of node " + std::to_string(t.node) + " names point " +
                                       std::to_string(p) + " beyond the cloud");
        for (const std::uint32_t n : t.neighbours)
            if (n >= tiles.size())
                throw InvalidInput(std::string(function) + ": tile of node " + std::to_string(t.node) + " names neighbour " +
                                   std::to_string(n) + " beyond the " + std::to_string(tiles.size()) + " tiles");
    }
}

} // namespace

std::vector<bool> surrounded_tiles(const std::vector<Tile>& tiles, const SurfaceOptions& options)
{
    check_surface_options(options);
    check_tiles(nullptr, tiles, "surrounded_tiles");
    return interior_tiles(tiles, options.interior_gap_degrees);
}

HeightFieldChoice choose_height_field(const Hierarchy& h, const std::vector<Tile>& tiles, const SurfaceOptions& options)
{
    check_surface_options(options);
    check_tiles(&h, tiles, "choose_height_field");
    const Projection p = choose_projection(h, tiles, options);
    HeightFieldChoice choice;
    choice.used = p.used;
    choice.axis = p.axis;
    choice.steep = p.steep;
    return choice;
}

void check_surface_options(const SurfaceOptions& options)
{
    if (!(options.alpha >= 0.0) || !(options.alpha_factor > 0.0) || !(options.split_factor > 0.0) ||
        !(options.hole_factor >= 0.0) || !(options.step_height >= 0.0) || std::isnan(options.split_length) ||
        !(options.max_gap_width >= 0.0) || !(options.collapse_tolerance >= 0.0) || !(options.strip_tolerance >= 0.0))
        throw InvalidInput("SurfaceOptions: alpha, step_height, hole_factor, max_gap_width, collapse_tolerance, strip_tolerance must be >= 0 and alpha_factor, "
                           "split_factor > 0");
    // Angles above what they measure (a tilt of 200 degrees, a turn of 1000) were taken, meaning "no
    // limit" or, through the cosine, another limit than the one written.
    const auto check_angle = [](double degrees, int most, const char* name) {
        if (!(degrees > 0.0 && degrees <= most)) {
            char got[32];
            std::snprintf(got, sizeof got, "%g", degrees);
            throw InvalidInput(std::string("SurfaceOptions::") + name + " must be in (0, " + std::to_string(most) +
                               "] degrees, got " + got);
        }
    };
    check_angle(options.max_tilt_degrees, 90, "max_tilt_degrees");
    check_angle(options.max_turn_degrees, 180, "max_turn_degrees");
    check_angle(options.interior_gap_degrees, 360, "interior_gap_degrees");
    // An enum cast from an integer (static_cast<HeightField>(42)) was taken for Auto.
    if (options.height_field != HeightField::Auto && options.height_field != HeightField::On &&
        options.height_field != HeightField::Off)
        throw InvalidInput("SurfaceOptions::height_field " + std::to_string(static_cast<int>(options.height_field)) +
                           " is none of Auto, On, Off");
    if (options.close_holes > kMaxCloseHoles)
        throw InvalidInput("SurfaceOptions::close_holes: at most " + std::to_string(kMaxCloseHoles) +
                           " edges (a hole's fill costs the cube of its edges)");
}

void build_surface(const Hierarchy& h, const std::vector<Tile>& given, Mesh& mesh, const SurfaceOptions& options,
                   SurfaceStats* stats)
{
    if (mesh.n_vertices() > 0)
        throw InvalidInput("build_surface: the mesh to build into must be empty");
    const auto start = std::chrono::steady_clock::now();
    if (given.empty())
        throw InvalidInput("build_surface: the cut has no tiles");
    check_surface_options(options);
    // A line or a point spans no surface whatever tiles its cut has: points on a line stored as floats
    // are off it by their rounding, enough for a fan of zero-area faces (QA, session 17: 225 of them).
    // The spread across the line is judged against the scale, which far strays do not set (a stray
    // at 1e8 beside a unit sphere made the largest spread 1e16 times the sphere's: QA, session 19).
    const Eigen3x3& whole = h.nodes.front().frame; // values: sums of squares over the points
    const double points = static_cast<double>(std::max<std::size_t>(1, h.nodes.front().count()));
    const double least_spread = 1e-6 * (h.scale > 0 ? h.scale : std::sqrt(whole.values[2] / points));
    if (!(whole.values[1] / points > least_spread * least_spread)) {
        // Say how close to a line: objects a million times their size apart fail the same test (QA round
        // qa-adv: two unit spheres 1e6 apart were called collinear, which left the user guessing).
        char scale[32];
        std::snprintf(scale, sizeof scale, "%.6g", h.scale);
        throw InvalidInput(std::string("the points are collinear or coincident within a millionth of their extent (") +
                           scale + "): they span no surface to mesh (objects farther apart than a million times "
                           "their size are meshed one at a time)");
    }
    check_tiles(&h, given, "build_surface");
    std::size_t fan_tiles = 0;
    for (const Tile& t : given)
        fan_tiles += t.has_fan() ? 1 : 0;
    if (fan_tiles == 0)
        throw InvalidInput("build_surface: no tile has three non-collinear points; choose a coarser cut");

    // A height field's steep tiles get no fan (see choose_height_field): tiles made for one come so
    // (mesh_cut), others are marked here.
    const Projection projection = choose_projection(h, given, options);
    std::vector<Tile> marked;
    const std::size_t steep_fans = projection.used ? static_cast<std::size_t>(std::count(projection.steep.begin(), projection.steep.end(), true)) : 0;
    if (steep_fans > 0 && steep_fans < fan_tiles) {
        marked = given;
        for (std::size_t k = 0; k < marked.size(); ++k)
            if (projection.steep[k]) {
                marked[k].fanless = true;
                marked[k].boundary.clear(); // no points either: see make_tiles' fanless tiles
            }
        fan_tiles -= steep_fans;
    }
    const std::vector<Tile>& tiles = marked.empty() ? given : marked;
    const Layout layout = make_layout(h, tiles, options);
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
    if (options.max_gap_width > 0.0)
        drop_uncovered_candidates(h, layout, positions, options.threads, candidates);
    if (!projection.used) // a height field bridges its steps on purpose (SurfaceOptions::bridge_steps)
        drop_seen_through_candidates(h, layout, positions, options.threads, candidates);
    // The front runs on consensus candidates first. Where it strands tiles (at a thin feature such as
    // the tip of an ear, the planes of neighbouring tiles disagree too much for consensus, the tiles
    // are seeded one by one and end up as islands that would be dropped and covered over), it runs
    // again with the fallback candidates that touch a stranded tile.
    const std::vector<int> orientation = pruner.know_neighbours() ? orient_tiles(tiles) : std::vector<int>{};
    Surface surface(layout.vertices.size());
    Front front(layout, tiles, surface, projection, positions, candidates, options.max_turn_degrees, orientation);
    front.run();
    {
        Islands islands = find_islands(surface, tiles, layout.tiles);
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
    FillCache fill_cache;
    auto fill = [&](FillMode mode) {
        const FillResult more = fill_holes(h, surface, layout, positions, projection, interior, options, mode, &fill_cache);
        filled.holes += more.holes;
        filled.crossing += more.crossing;
        filled.faces += more.faces;
    };
    if (options.fill_holes)
        fill(FillMode::BeforeHandles);
    // A single view is a depth image: a disc with holes, or several, and no handles. A face that would
    // add one joins two borders of what the scanner saw (its outline, the shadows behind objects) over
    // space it did not see: terrestrial scans got genus 1-4, bridging the shadows of boxes. Only where
    // the viewpoint is where every point was seen from (single_view.h): PCL keeps a sensor origin through
    // merges, and a torus sampled all round lost its handle to one (QA round 35).
    front.finish(!(h.view && h.view->single_view));
    if (options.fill_holes) {
        fill(FillMode::Gaps);
        std::vector<DroppedIsland> removed; // the islands dropped
        const std::vector<bool> dropped = drop_islands(surface, tiles, layout.tiles, removed);
        islands = static_cast<std::size_t>(std::count(dropped.begin(), dropped.end(), true));
        if (islands > 0) {
            // Two ways on from here; the one that leaves fewer tiles out wins, ties going to the first.
            // (a) Fill again and put back the islands the rest does not cover.
            const Surface after_drop = surface;
            const FillResult filled_after_drop = filled;
            fill(FillMode::Gaps);
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
                fill(FillMode::Gaps);
                std::vector<DroppedIsland> removed_again;
                const std::vector<bool> dropped_again = drop_islands(surface, tiles, layout.tiles, removed_again);
                islands = static_cast<std::size_t>(std::count(dropped_again.begin(), dropped_again.end(), true));
                restored_islands = 0;
                if (islands > 0) {
                    fill(FillMode::Gaps);
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

    // On request, last: the holes that are the sample's own (a scan's unseen base), for watertight output.
    if (options.close_holes > 0)
        fill(FillMode::Close);

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
    // because the rest does not cover it, or a leaf's that the rest does not cover now and that holds as
    // many points as a small island put back must (lone_fans_to_keep): a flat L-shaped sample cut into
    // two tiles, leaves, along a diagonal, their hulls a sliver apart, was two lone fans, and the one
    // that drop_islands had not taken for the island was dropped here, half the sample with it (QA
    // round 40). Other tiles' fans are dropped: mesh_cut refines a dropped tile and meshes again
    // (MeshOptions::dropped_rounds), which does better than a loose disc (QA round 44: a cube's two-tile
    // cut kept a disc reaching a diagonal past the points).
    std::vector<std::int32_t> lone_tile(faces.size(), -2); // per root: the one tile, -1 if more or a gap face
    for (std::uint32_t f = 0; f < face_count; ++f) {
        const std::uint32_t r = components.find(f);
        const std::int32_t t = face_tile[f];
        lone_tile[r] = lone_tile[r] == -2 ? t : (lone_tile[r] == t ? t : -1);
    }
    std::vector<bool> dropped(faces.size(), false);
    std::size_t dropped_components = 0;
    if (roots.size() > 1) {
        std::vector<std::uint32_t> lone_roots;
        std::vector<std::int32_t> lone_tiles;
        for (std::uint32_t r : roots)
            if (lone_tile[r] >= 0 && !restored_tiles[static_cast<std::size_t>(lone_tile[r])] &&
                !tiles[static_cast<std::size_t>(lone_tile[r])].neighbours.empty()) {
                if (h.nodes[static_cast<std::size_t>(tiles[static_cast<std::size_t>(lone_tile[r])].node)].is_leaf()) {
                    lone_roots.push_back(r);
                    lone_tiles.push_back(lone_tile[r]);
                } else {
                    dropped[r] = true;
                    ++dropped_components;
                }
            }
        if (!lone_roots.empty()) {
            std::vector<Vec3> vertex_positions(origin.size());
            for (std::size_t v = 0; v < origin.size(); ++v)
                vertex_positions[v] = pos(static_cast<std::uint32_t>(v));
            const std::vector<bool> keep = lone_fans_to_keep(surface, vertex_positions, layout.tiles, lone_tiles);
            for (std::size_t k = 0; k < lone_roots.size(); ++k)
                if (!keep[k]) {
                    dropped[lone_roots[k]] = true;
                    ++dropped_components;
                }
        }
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
        std::vector<double> border_slack(mesh.n_vertices(), 0.0);
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
            border_slack[i] = kBorderSlackSpacings * tiles[t].spacing();
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
        BorderHistory history;
        st.collapsed_split_points = collapse_loop_points(mesh, split_only, border_slack, projection, history);
        // Three passes, halving the slack each time (a negative slack stays negative): a point removed in
        // one pass may be moved again by the later ones, so the surface moves from it by at most
        // 1.75 × collapse_tolerance × the RMS plane distance.
        for (int pass = 0; pass < 3; ++pass) {
            st.collapsed_split_points += collapse_loop_points(mesh, slack, border_slack, projection, history);
            for (double& x : slack)
                x *= 0.5;
        }
        // Then the strips between tiles, in the same halving passes (after the loops, so that the rim
        // points that carry no shape are gone and the strips' remaining pairs are the ones merged).
        for (int pass = 0; pass < 3 && options.strip_tolerance > 0.0; ++pass) {
            st.collapsed_split_points += collapse_loop_points(mesh, strip_slack, border_slack, projection, history, true);
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
    st.closings_refused = filled.crossing;
    st.split_vertices = copies.size();
    st.components = roots.size();
    st.dropped_fans = islands + dropped_components;
    st.restored_islands = restored_islands;
    st.height_field_used = projection.used;
    st.height_field_axis = projection.axis;
    st.looks_airborne = projection.looks_airborne;
    st.alpha = alpha;
    st.view = h.view;
    if (mesh.n_faces() == 0) {
        // Every piece was a small detached island (see SurfaceOptions): the tiles never joined.
        char why[200];
        std::snprintf(why, sizeof why, "%s the automatic alpha is %.3g",
                      options.alpha > 0.0 ? "the given alpha is far below the tiles' spacing;" : "", options.alpha_factor * layout.mean_edge);
        throw InvalidInput(std::string("build_surface: no surface is left: every piece of the cut is a small detached "
                                       "island (") + why + ")");
    }
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
}

} // namespace mrt
