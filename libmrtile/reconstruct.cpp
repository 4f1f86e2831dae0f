// Glue of the method's stages (paper Fig. 1: clustering → tiles → reconstruction) and the error
// measures of paper §5 (eq. 4-6), so the CLI, the demo and the benchmarks all run the same pipeline.
// Steps between the stages go beyond the paper: a separate object that a cut gives one to three tiles
// cannot close, and a tile reaching over a hole covers it, so those tiles are refined before meshing;
// a tile the surface left out although its points lie away from it is refined after (and its points
// are not fitted to); a height field with walls gets its tiles in its own plane, the walls left out.
// And a cloud too small to split (one leaf) that is no piece of plane gets its convex hull.
#include "libmrtile/reconstruct.h"

#include "libmrtile/cluster_tree.h"
#include "libmrtile/errors.h"
#include "libmrtile/gap_triangulation.h"
#include "libmrtile/median.h"
#include "libmrtile/parallel.h"
#include "libmrtile/pca.h"
#include "libmrtile/union_find.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cassert>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <tuple>
#include <unordered_map>

namespace mrt {

namespace {

// Per tile of `cut`: true when its piece of the tile adjacency has at most kSmallObjectTiles tiles while
// other pieces exist, and its node can be refined (see MeshOptions::small_object_rounds). Three: two
// fans make a flat pillow, and of 50 spheres refined from two tiles to three or four, one kept a hole.
constexpr std::size_t kSmallObjectTiles = 3;

std::vector<bool> small_object_tiles(const Hierarchy& h, const Cut& cut, const std::vector<Tile>& tiles)
{
    const std::size_t n = tiles.size();
    UnionFind pieces(n);
    for (std::uint32_t k = 0; k < n; ++k)
        for (std::uint32_t j : tiles[k].neighbours)
            pieces.unite(k, j);
    std::vector<std::size_t> size(n, 0);
    for (std::uint32_t k = 0; k < n; ++k)
        ++size[pieces.find(k)];
    std::vector<bool> small(n, false);
    for (std::uint32_t k = 0; k < n; ++k) {
        const std::size_t piece = size[pieces.find(k)];
        // A height field's wall (a fanless tile) has no neighbours, and is no object either.
        small[k] = piece <= kSmallObjectTiles && piece < n && !tiles[k].fanless &&
                   !h.nodes[static_cast<std::size_t>(cut[k])].is_leaf();
    }
    return small;
}

// A leaf is a "solid" when its points spread in all three directions: λ_min of M at least this share of
// λ_mid (RMS spread across its plane at least a third of the spread along its second axis). Points
// around a solid give 1/3 to 1 (a tetrahedron's or a cube's corners 1, a half sphere 1/4, four or five
// random points of a sphere 0.15-0.35); a plane or a gently curved patch far less.
constexpr double kSolidEigenvalueRatio = 0.1;

// The whole cloud in one leaf (under BuildOptions::min_cluster points) that is no piece of plane: its
// pseudo tile is no piece of the surface either, and the fan of one stood 1.0 diagonal off ten points
// of a sphere (its apex, fitted towards points all round). So few points show no concavity to keep,
// and their convex hull is the closed surface through all of them (a cube's corners give the cube).
bool is_tiny_solid(const Hierarchy& h, const Cut& cut)
{
    if (cut.size() != 1)
        return false;
    const Node& node = h.nodes[static_cast<std::size_t>(cut[0])];
    // Only clouds too small to split: a large cloud in one leaf is flat at the build's tolerance (a
    // noisy line, two far objects), and its hull would join what the sample keeps apart.
    const std::size_t too_small = h.info.min_cluster > 0 ? h.info.min_cluster : BuildOptions{}.min_cluster;
    return node.is_leaf() && node.parent < 0 && node.count() >= 4 && node.count() <= too_small &&
           node.frame.values[0] >= kSolidEigenvalueRatio * node.frame.values[1] &&
           node.frame.values[1] >= kSolidEigenvalueRatio * node.frame.values[2]; // not a line either
}

// The convex hull of the one leaf's points as the mesh: one tile, every face a fan face of it. Empty
// when the points span no volume (the caller then meshes the usual way).
Mesh hull_mesh(const Hierarchy& h, std::int32_t node_id)
{
    const Node& node = h.nodes[static_cast<std::size_t>(node_id)];
    const std::vector<Vec3> points(h.cloud.positions.begin() + node.begin, h.cloud.positions.begin() + node.end);
    Mesh mesh;
    const auto triangles = convex_hull_triangles(points);
    if (triangles.empty())
        return mesh;
    auto cluster = OpenMesh::getOrMakeProperty<OpenMesh::VertexHandle, int>(mesh, kVertexCluster);
    auto tile_of_face = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile);
    auto gap = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, bool>(mesh, kFaceGap);
    std::vector<Mesh::VertexHandle> handle(points.size());
    for (const auto& t : triangles)
        for (std::uint32_t i : t)
            if (!handle[i].is_valid()) {
                handle[i] = mesh.add_vertex(to_point(points[i]));
                cluster[handle[i]] = node_id;
            }
    for (const auto& t : triangles) {
        const auto f = mesh.add_face(handle[t[0]], handle[t[1]], handle[t[2]]);
        assert(f.is_valid()); // a convex hull is a closed 2-manifold
        tile_of_face[f] = node_id;
        gap[f] = false;
    }
    mesh.update_normals();
    return mesh;
}

// Per tile of `cut`: true for a fan tile the surface left out whose points lie away from the mesh
// (their median distance over up to 16 of them above 3 of the tile's spacings). Such points sample
// surface the mesh does not have: a small detached piece left out, a strip that failed to join at a
// coarse cut, or the other half of a 2-tile sphere whose surface kept one fan. A fan covered by its
// neighbours' gap faces (at a sharp edge) has its points on the mesh and is not away. A tile without a
// fan (too few points, or in a line) whose points are no vertex of the mesh is judged the same way,
// by the typical (median) spacing of the fan tiles: stray points far off, which the hierarchy puts in
// clusters of their own (QA round 57: a unit sphere with five strays 24-50 away had its side facing
// one stray pulled out by the fit, the points there 0.03-0.04 from the mesh at tolerance 0.00158, and
// the mean distance of the sphere's points twice the clean sphere's at every finer cut). Empty when no
// tile is (the usual case: no closest-point queries at all when every fan is in the mesh and every
// tile without one has a vertex).
std::vector<bool> away_tiles(const Hierarchy& h, const Cut& cut, const std::vector<Tile>& tiles, const Mesh& mesh,
                             std::size_t threads)
{
    OpenMesh::FPropHandleT<int> tile_of_face;
    if (!mesh.get_property_handle(tile_of_face, kFaceTile) || mesh.n_faces() == 0)
        return {};
    std::vector<std::int32_t> meshed;
    for (const auto f : mesh.faces())
        if (mesh.property(tile_of_face, f) >= 0)
            meshed.push_back(mesh.property(tile_of_face, f));
    std::sort(meshed.begin(), meshed.end());
    meshed.erase(std::unique(meshed.begin(), meshed.end()), meshed.end());
    constexpr std::size_t kProbes = 16;
    constexpr double kAwaySpacings = 3.0;
    std::vector<std::size_t> unmeshed; // cut positions of fan tiles without a fan face, fanless ones without a vertex
    std::vector<Vec3> probes;
    std::vector<char> shown;       // nodes_in_mesh, found when a fanless tile asks
    double typical_spacing = 0.0;  // the fan tiles' median spacing, found with it
    for (std::size_t k = 0; k < cut.size(); ++k) {
        bool candidate = false;
        if (tiles[k].has_fan()) {
            candidate = !std::binary_search(meshed.begin(), meshed.end(), cut[k]);
        } else {
            if (shown.empty()) {
                shown = nodes_in_mesh(h, mesh);
                std::vector<double> spacings;
                for (const Tile& t : tiles)
                    if (t.has_fan() && t.spacing() > 0.0)
                        spacings.push_back(t.spacing());
                typical_spacing = upper_median_in_place(spacings);
            }
            candidate = typical_spacing > 0.0 && !shown[static_cast<std::size_t>(cut[k])];
        }
        if (candidate) {
            unmeshed.push_back(k);
            const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
            const std::size_t step = std::max<std::size_t>(1, n.count() / kProbes);
            for (std::size_t i = 0; i < kProbes; ++i)
                probes.push_back(h.cloud.positions[std::min<std::size_t>(n.end - 1, n.begin + i * step)]);
        }
    }
    if (unmeshed.empty())
        return {};
    const std::vector<ClosestPoint> closest = closest_points(probes, mesh, threads);
    std::vector<bool> away(cut.size(), false);
    bool any = false;
    for (std::size_t u = 0; u < unmeshed.size(); ++u) {
        std::array<double, kProbes> d{};
        for (std::size_t i = 0; i < kProbes; ++i)
            d[i] = distance(probes[u * kProbes + i], closest[u * kProbes + i].point);
        std::nth_element(d.begin(), d.begin() + kProbes / 2, d.end());
        const std::size_t k = unmeshed[u];
        away[k] = d[kProbes / 2] > kAwaySpacings * (tiles[k].has_fan() ? tiles[k].spacing() : typical_spacing);
        any = any || away[k];
    }
    return any ? away : std::vector<bool>{};
}

// The points the vertex fit follows: all of them but those of the tiles away from the mesh
// (away_tiles). Fitted to them, the faces nearest them were pulled toward surface the mesh does not
// have (a plate's rim rose 4% of its width toward a dropped island of 50 points; a 2-tile sphere's fan
// apex went 2.8 radii out). Empty = every point (no copy).
std::vector<Vec3> fit_points(const Hierarchy& h, const Cut& cut, const std::vector<bool>& away)
{
    if (away.empty())
        return {};
    std::vector<Vec3> kept;
    for (std::size_t k = 0; k < cut.size(); ++k)
        if (!away[k]) {
            const Node& n = h.nodes[static_cast<std::size_t>(cut[k])];
            kept.insert(kept.end(), h.cloud.positions.begin() + n.begin, h.cloud.positions.begin() + n.end);
        }
    return kept;
}

// The cut with the marked nodes replaced by their children (in place: still in point order).
Cut refine_marked(const Hierarchy& h, const Cut& cut, const std::vector<bool>& marked)
{
    Cut refined;
    refined.reserve(cut.size());
    for (std::size_t k = 0; k < cut.size(); ++k) {
        const Node& node = h.nodes[static_cast<std::size_t>(cut[k])];
        if (marked[k] && !node.is_leaf()) {
            refined.push_back(node.left);
            refined.push_back(node.right);
        } else {
            refined.push_back(cut[k]);
        }
    }
    return refined;
}

// The tiles of `cut`. A height field with walls (steep tiles, choose_height_field: an airborne scan's
// buildings) gets tiles in the height field's plane, partitioned there, the walls left out: every fan
// is a graph over the plane, the roofs' and the ground's cells meet at the walls without taking in
// their points, and the gap triangulation bridges each wall as a step (paper Fig. 9c). The surface
// stage is told the choice (`surface`), which tiles built in one plane could not show it. A height
// field without walls keeps its tiles as they are.
std::vector<Tile> tiles_for(const Hierarchy& h, const Cut& cut, const MeshOptions& options, SurfaceOptions& surface)
{
    std::vector<Tile> pca = make_tiles(h, cut, options.tiles);
    surface = options.surface;
    if (options.surface.height_field == HeightField::Off)
        return pca;
    const HeightFieldChoice choice = choose_height_field(h, pca, options.surface);
    if (!choice.used || std::none_of(choice.steep.begin(), choice.steep.end(), [](bool b) { return b; }))
        return pca;
    TileOptions in_plane = options.tiles;
    in_plane.plane_axis = choice.axis;
    std::vector<Tile> graph = make_tiles(h, cut, in_plane, choice.steep);
    surface.height_field = HeightField::On;
    return graph;
}

// The tiles of `cut` after refining, before any meshing, the tiles of small separate objects
// (MeshOptions::small_object_rounds) and those whose outline reaches over a hole farther than their
// node's error (gap_rounds). `cut` becomes the cut meshed.
std::vector<Tile> refine_before_meshing(const Hierarchy& h, const MeshOptions& options, Cut& cut, SurfaceOptions& surface)
{
    std::vector<Tile> tiles = tiles_for(h, cut, options, surface);
    const int rounds = std::max(options.small_object_rounds, options.gap_rounds);
    for (int round = 0; round < rounds && options.tiles.voronoi_trim; ++round) {
        std::vector<bool> marked = round < options.small_object_rounds ? small_object_tiles(h, cut, tiles)
                                                                       : std::vector<bool>(tiles.size(), false);
        if (round < options.gap_rounds)
            for (std::size_t k = 0; k < tiles.size(); ++k) {
                const Node& node = h.nodes[static_cast<std::size_t>(cut[k])];
                if (!node.is_leaf() && tiles[k].coverage_gap > node_error(node))
                    marked[k] = true;
            }
        if (std::none_of(marked.begin(), marked.end(), [](bool b) { return b; }))
            break;
        cut = refine_marked(h, cut, marked);
        tiles = tiles_for(h, cut, options, surface);
    }
    return tiles;
}

// Each node of `cut` to its index in it (the mesh's vertices name their tile by its node).
std::unordered_map<std::int32_t, std::size_t> positions_in(const Cut& cut)
{
    std::unordered_map<std::int32_t, std::size_t> index;
    for (std::size_t k = 0; k < cut.size(); ++k)
        index.emplace(cut[k], k);
    return index;
}

// A boundary loop of the mesh: the tiles (indices into `cut`) its vertices name (v:cluster), and its
// border half-edges.
struct LoopTiles
{
    std::vector<std::size_t> tiles;
    std::vector<Mesh::HalfedgeHandle> border; //!< its half-edges, in order
};

std::vector<LoopTiles> tiles_of_loops(const Cut& cut, const Mesh& mesh)
{
    std::vector<LoopTiles> loops;
    OpenMesh::VPropHandleT<int> cluster;
    if (!mesh.get_property_handle(cluster, kVertexCluster))
        return loops;
    const std::unordered_map<std::int32_t, std::size_t> index = positions_in(cut);
    std::vector<bool> seen(mesh.n_halfedges(), false);
    for (const Mesh::HalfedgeHandle start : mesh.halfedges()) {
        if (!mesh.is_boundary(start) || seen[static_cast<std::size_t>(start.idx())])
            continue;
        LoopTiles loop;
        Mesh::HalfedgeHandle he = start;
        do {
            seen[static_cast<std::size_t>(he.idx())] = true;
            if (const auto it = index.find(mesh.property(cluster, mesh.to_vertex_handle(he))); it != index.end())
                loop.tiles.push_back(it->second);
            loop.border.push_back(he);
            he = mesh.next_halfedge_handle(he);
        } while (he != start && !seen[static_cast<std::size_t>(he.idx())]);
        std::sort(loop.tiles.begin(), loop.tiles.end());
        loop.tiles.erase(std::unique(loop.tiles.begin(), loop.tiles.end()), loop.tiles.end());
        loops.push_back(std::move(loop));
    }
    return loops;
}

// The median point spacing of the tiles (indices into `tiles`); 0 when none has one.
double median_spacing(const std::vector<Tile>& tiles, const std::vector<std::size_t>& which)
{
    std::vector<double> spacings;
    for (const std::size_t k : which)
        if (tiles[k].spacing() > 0.0)
            spacings.push_back(tiles[k].spacing());
    return upper_median_in_place(spacings);
}

constexpr double kMinSurroundedShare = 0.9; // of a loop's tiles, for refine_broken_pieces to refine them

// The spacing of the sample under a tile: sqrt(its area / its node's points). A tile is built from a
// sample of its node's points (TileOptions::max_points), whose spacing (Tile::spacing) is coarser at
// coarse cuts.
double sample_spacing(const Hierarchy& h, const Tile& tile)
{
    return std::sqrt(tile.area / static_cast<double>(std::max<std::uint32_t>(1, h.nodes[static_cast<std::size_t>(tile.node)].count())));
}

// The same for every tile, by its node: what the notches and the caps judge their covers by.
std::unordered_map<std::int32_t, double> sample_spacings(const Hierarchy& h, const std::vector<Tile>& tiles)
{
    std::unordered_map<std::int32_t, double> spacing_of;
    for (const Tile& t : tiles)
        spacing_of[t.node] = sample_spacing(h, t);
    return spacing_of;
}

// A border edge by its corners' positions, from -> to (meshes that share corners share these).
using EdgeCorners = std::pair<std::array<double, 3>, std::array<double, 3>>;

EdgeCorners corners_of(const Mesh& mesh, Mesh::HalfedgeHandle he)
{
    const Mesh::Point a = mesh.point(mesh.from_vertex_handle(he)), b = mesh.point(mesh.to_vertex_handle(he));
    return {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}};
}

// The border edges of `mesh` still open once the caps from the points (close_covered_holes, which
// mesh_cut puts on after the fit) are put on a copy of it. A loop none of whose edges is left is one
// the caps close, and crack rounds leave it to them: a round had taken such a loop on a 1M-point
// fandisk sample, with 14 crossing pairs left in the end instead of the caps' 11 (QA round 47).
std::set<EdgeCorners> open_after_caps(const Hierarchy& h, const std::vector<Tile>& tiles, const Mesh& mesh,
                                      const CoveredHoleOptions& options)
{
    Mesh copy = mesh;
    close_covered_holes(copy, h, sample_spacings(h, tiles), options);
    std::set<EdgeCorners> open;
    for (const Mesh::HalfedgeHandle he : copy.halfedges())
        if (copy.is_boundary(he))
            open.insert(corners_of(copy, he));
    return open;
}

// A crack lies over sampled surface: the mesh at it, and what mends it, stays within this many of its
// sample's spacings of the points (judged as area_off_the_sample judges). A hole's rim can pass for a
// crack when the rest of the hole lies under a neighbour's fan (QA round 46: spheres with holes 12-35
// spacings wide closed by crack rounds at coarse cuts, faces 4-16 spacings off the points).
constexpr double kCrackReach = 3.0;

// kCrackReach spacings of the sample under the tiles `which` (the median of their sample_spacing; 0
// when none has one): how far from the points the mesh a round changes may lie.
double crack_reach(const Hierarchy& h, const std::vector<Tile>& tiles, const std::vector<std::size_t>& which)
{
    std::vector<double> spacings;
    for (const std::size_t k : which)
        if (const double s = sample_spacing(h, tiles[k]); s > 0.0)
            spacings.push_back(s);
    return kCrackReach * upper_median_in_place(spacings);
}

// A boundary loop that a crack round would mend, judged against the points: before the round, the
// faces at its corners; after it, the mesh over its tiles.
class CrackWatch
{
public:
    CrackWatch(const Hierarchy& h, const Cut& cut, const std::vector<Tile>& tiles, const LoopTiles& loop,
               const Mesh& mesh)
    {
        std::vector<Vec3> corners;
        for (const std::size_t k : loop.tiles) {
            corners.push_back(tiles[k].centre);
            for (const std::uint32_t i : tiles[k].boundary)
                corners.push_back(h.cloud.positions[i]);
            nodes_.push_back(cut[k]);
        }
        reach_ = crack_reach(h, tiles, loop.tiles);
        if (!(reach_ > 0.0))
            return; // no spacing: never at a rim, never spanning
        // Faces at a hole's rim span the rest of the hole: spots twice the reach from every point, over
        // more than a reach-wide square (about one spot of that grid; the faces at a tetrahedron's
        // cracks had half of one, those at the holes' rims on QA 46's spheres 1-38).
        std::vector<Mesh::FaceHandle> at_corners;
        for (const Mesh::HalfedgeHandle he : loop.border)
            for (const Mesh::FaceHandle f : mesh.vf_range(mesh.to_vertex_handle(he)))
                at_corners.push_back(f);
        std::sort(at_corners.begin(), at_corners.end());
        at_corners.erase(std::unique(at_corners.begin(), at_corners.end()), at_corners.end());
        at_rim_ = area_off_the_sample(mesh, h, at_corners, 2.0 * reach_) > reach_ * reach_;
        if (at_rim_)
            return;
        box_ = bounding_box(corners);
        off_before_ = area_off_the_sample(mesh, h, box_, reach_);
    }

    // Whether the faces at the loop's corners span a hole of the sample: the loop is a hole's rim.
    bool at_a_holes_rim() const { return at_rim_; }

    // Whether `mesh` (the cut meshed again) spans more of a hole of the sample over the loop's tiles
    // than the mesh before (by more than half a reach-wide square: the spots' rounding). For watches
    // not at a hole's rim (those start no round).
    bool spans_a_hole(const Hierarchy& h, const Mesh& mesh) const
    {
        return area_off_the_sample(mesh, h, box_, reach_) > off_before_ + 0.5 * reach_ * reach_;
    }

    // The loop's tiles' cut nodes.
    const std::vector<std::int32_t>& nodes() const { return nodes_; }
    double reach() const { return reach_; }

private:
    std::vector<std::int32_t> nodes_;
    double reach_ = 0.0;
    bool at_rim_ = false;
    BoundingBox box_;        // of the loop's tiles' outlines and centres
    double off_before_ = 0.0; // the mesh's area over a hole of the sample in box_, before the round
};

// A regular sample of the points of h, at most about this many: the points a crack round must leave no
// farther from the mesh than they were.
constexpr std::size_t kFarSample = 20000;

// The step of that sample: every this many points.
std::size_t far_sample_step(const Hierarchy& h) { return std::max<std::size_t>(1, h.cloud.size() / kFarSample); }

// The distances from that sample (points 0, step, 2 step, ...) to `mesh`.
std::vector<double> sample_distances(const Hierarchy& h, const Mesh& mesh, std::size_t threads)
{
    std::vector<Vec3> sample;
    const std::size_t step = far_sample_step(h);
    for (std::size_t i = 0; i < h.cloud.size(); i += step)
        sample.push_back(h.cloud.positions[i]);
    const std::vector<ClosestPoint> closest = closest_points(sample, mesh, threads);
    std::vector<double> distances(sample.size());
    for (std::size_t i = 0; i < sample.size(); ++i)
        distances[i] = distance(sample[i], closest[i].point);
    return distances;
}

// The largest distance from a regular sample of h's points to `mesh`.
double farthest_sample_point(const Hierarchy& h, const Mesh& mesh, std::size_t threads)
{
    const std::vector<double> distances = sample_distances(h, mesh, threads);
    return distances.empty() ? 0.0 : *std::max_element(distances.begin(), distances.end());
}

// The median reach of the watches (0 for none).
double median_reach(const std::vector<CrackWatch>& watches)
{
    std::vector<double> reaches;
    for (const CrackWatch& watch : watches)
        reaches.push_back(watch.reach());
    return upper_median_in_place(reaches);
}

// Whether the points lie farther from `again` (a crack round's mesh) than from `mesh`, the one before:
// the farthest of a regular sample, by more than a spacing (a third of `reach`). The surface is meshed
// anew everywhere, and a round that mended its cracks made a hole's rim elsewhere recede by 5
// spacings (QA 46's sphere with holes of 8-40 spacings, at tolerance 0.01: the gap triangulation's
// alpha follows the tiles' mean edge).
bool leaves_points(const Hierarchy& h, const Mesh& mesh, const Mesh& again, double reach, std::size_t threads)
{
    return farthest_sample_point(h, again, threads) > farthest_sample_point(h, mesh, threads) + reach / kCrackReach;
}

// The faces of `mesh` with no face of `other` on the same three corner positions: what a meshing
// changed, seen from one of the two meshes (untouched tiles keep their points, so their faces match).
std::vector<Mesh::FaceHandle> faces_not_in(const Mesh& mesh, const Mesh& other)
{
    using Corners = std::array<double, 9>;
    const auto key = [](const Mesh& m, Mesh::FaceHandle f) {
        std::array<Vec3, 3> t = face_corners(m, f);
        std::sort(t.begin(), t.end(), [](const Vec3& a, const Vec3& b) {
            return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
        });
        return Corners{t[0].x, t[0].y, t[0].z, t[1].x, t[1].y, t[1].z, t[2].x, t[2].y, t[2].z};
    };
    std::vector<Corners> theirs;
    for (const Mesh::FaceHandle f : other.faces())
        theirs.push_back(key(other, f));
    std::sort(theirs.begin(), theirs.end());
    std::vector<Mesh::FaceHandle> changed;
    for (const Mesh::FaceHandle f : mesh.faces())
        if (!std::binary_search(theirs.begin(), theirs.end(), key(mesh, f)))
            changed.push_back(f);
    return changed;
}

// Whether `again` (a crack round's mesh) spans more of the sample's holes than `mesh`, the one before,
// anywhere: the area farther than `reach` from every point of the faces only it has, against that of
// the faces only the one before has, by more than half a reach-wide square. The surface is meshed anew
// everywhere: mending one loop on a sphere with holes grew the faces spanning a 40-spacing hole 30
// spacings away by 56 square spacings (QA round 47), which no watch over the loops' tiles sees.
bool spans_more_holes(const Hierarchy& h, const Mesh& mesh, const Mesh& again, double reach)
{
    const double removed = area_off_the_sample(mesh, h, faces_not_in(mesh, again), reach);
    const double added = area_off_the_sample(again, h, faces_not_in(again, mesh), reach);
    return added > removed + 0.5 * reach * reach;
}

// Whether a crack round's surface crosses itself more than the one before: by more than 5% of its
// pairs (before the untangling). Their count moves by a few percent with any change of the cut (a
// tetrahedron at tolerance 0.01: 547 -> 553 pairs in the round that closed 7 of its 8 loops), while a
// round that folds tiles over an acute edge multiplies it (a 5-point star prism: 16 -> 172 after the
// untangling).
bool crossings_grow(std::size_t before, std::size_t after)
{
    return 20 * after > 21 * before;
}

// Whether a marked tile of `cut` is no leaf: a round has something to refine.
bool any_refinable(const Hierarchy& h, const Cut& cut, const std::vector<bool>& marked)
{
    for (std::size_t k = 0; k < marked.size(); ++k)
        if (marked[k] && !h.nodes[static_cast<std::size_t>(cut[k])].is_leaf())
            return true;
    return false;
}

// A cut meshed again by a refinement round: its tiles, the surface options they chose, its surface.
struct Remeshed
{
    Cut cut;
    std::vector<Tile> tiles;
    SurfaceOptions options;
    SurfaceStats stats;
    Mesh mesh;
};

// The surface of `cut` for a round (tiles_for, build_surface), its tiles counted in `result`; false
// when the refined cut cannot be meshed (no surface left): the caller keeps the mesh it has.
bool remesh(const Hierarchy& h, const MeshOptions& options, Cut cut, Remeshed& out, MeshResult& result)
{
    out.cut = std::move(cut);
    out.tiles = tiles_for(h, out.cut, options, out.options);
    out.stats = SurfaceStats{};
    out.mesh = Mesh();
    try {
        build_surface(h, out.tiles, out.mesh, out.options, &out.stats);
    } catch (const InvalidInput&) {
        return false;
    }
    result.meshed_tiles += out.tiles.size();
    return true;
}

// The round's surface becomes the result's.
void keep_round(Remeshed& again, MeshResult& result, std::vector<Tile>& tiles, SurfaceOptions& surface)
{
    result.cut = std::move(again.cut);
    result.mesh = again.mesh;
    result.surface = again.stats;
    tiles = std::move(again.tiles);
    surface = again.options;
}

// After the surface: boundary loops along tiles that their neighbours surround are cracks, not the
// sample's borders (a scan's outline runs along tiles that face the empty outside: bun045, most of its
// loop tiles). Three kinds are mended by refining those tiles and meshing the cut again, up to
// MeshOptions::piece_rounds times (the first two) or crack_rounds times (the third):
//  - a mesh in several pieces, a closed thin part at a coarse cut broken where its tiles straddle it
//    (the rocker arm at tolerance 0.02: 11 pieces, 12 loops; fine cuts are closed), when at least 90%
//    of the tiles on all its loops are surrounded; a round is kept when it has fewer pieces and no
//    more loops;
//  - a height field with loops inside its outline whose tiles are surrounded: slits where two tilted
//    tiles overlap seen along the axis, so that no face between them looks up (a 3M-point terrain at
//    tolerance 0.002: a 20-edge slit between two tiles); a round is kept when it has fewer loops and
//    no more pieces;
//  - a surface in 3D, in one piece, with loops whose tiles are surrounded, that no cap closes
//    (open_after_caps) and that are no hole's rim (is_sample_hole, CrackWatch): cracks where coarse
//    tiles straddle an acute edge of a closed solid (a tetrahedron at tolerance 0.01: 8-10 slits
//    along its edges; session 37's battery of 83 sampled solids: 59 -> 46 loops). A round is kept
//    when it has fewer loops, no more pieces, no higher genus, no more fans left out (their points
//    would lie far from the mesh: a tetrahedron at 0.002 had its maximum distance 3.4 times higher),
//    no more crossing pairs but a few percent (crossings_grow), no more of the
//    mesh over the sample's holes (CrackWatch::spans_a_hole, spans_more_holes) and no points left
//    farther from it (leaves_points).
// Separate objects and a scan's own borders do not improve and are left as they were.
void refine_broken_pieces(const Hierarchy& h, const MeshOptions& options, SurfaceOptions& surface, MeshResult& result,
                          std::vector<Tile>& tiles)
{
    // Cut nodes on loops whose mending spanned a hole of the sample: a hole's rim, which later crack
    // rounds leave as it is.
    std::vector<std::int32_t> rims;
    bool retried = false; // this round was tried again without the loops whose mending spanned a hole
    for (int round = 0; round < std::max(options.piece_rounds, options.crack_rounds);) {
        const TopologyStats now = topology_stats(result.mesh);
        const bool pieces = round < options.piece_rounds && now.components >= 2 && now.boundary_loops > 0;
        const bool slits = round < options.piece_rounds && result.surface.height_field_used && now.components == 1 &&
                           now.boundary_loops >= 2;
        // (The three exclude each other: pieces have 2 components or more, slits a height field.)
        const bool cracks = round < options.crack_rounds && !result.surface.height_field_used && now.components == 1 &&
                            now.boundary_loops >= 1;
        if (!pieces && !slits && !cracks)
            return;
        const std::vector<bool> surrounded = surrounded_tiles(tiles, surface);
        assert(surrounded.size() == result.cut.size()); // one tile per cut node, in order
        std::vector<bool> marked(result.cut.size(), false);
        std::vector<CrackWatch> mended;
        std::size_t on_loops = 0, inner = 0;
        std::optional<std::set<EdgeCorners>> open; // after the caps, put on a copy once a loop asks
        for (const LoopTiles& found : tiles_of_loops(result.cut, result.mesh)) {
            const std::vector<std::size_t>& loop = found.tiles;
            std::size_t loop_inner = 0;
            for (std::size_t k : loop)
                loop_inner += surrounded[k] ? 1 : 0;
            on_loops += loop.size();
            inner += loop_inner;
            if (!pieces && static_cast<double>(loop_inner) < kMinSurroundedShare * static_cast<double>(loop.size()))
                continue;
            // A crack lies over sampled surface; a hole of the sample (the bunny's base, whose tiles can
            // all be surrounded) is left without a meshing spent on it (the bunny at 0.001: 0.6 -> 1.0 s).
            if (cracks) {
                if (std::any_of(loop.begin(), loop.end(), [&](std::size_t k) {
                        return std::find(rims.begin(), rims.end(), result.cut[k]) != rims.end();
                    }) ||
                    is_sample_hole(result.mesh, h, found.border, median_spacing(tiles, loop)))
                    continue;
                if (!open)
                    open = open_after_caps(h, tiles, result.mesh, options.covered_holes);
                if (std::none_of(found.border.begin(), found.border.end(), [&](Mesh::HalfedgeHandle he) {
                        return open->count(corners_of(result.mesh, he)) > 0;
                    }))
                    continue;
                CrackWatch watch(h, result.cut, tiles, found, result.mesh);
                if (watch.at_a_holes_rim())
                    continue;
                mended.push_back(std::move(watch));
            }
            for (std::size_t k : loop)
                marked[k] = true;
        }
        if (pieces && static_cast<double>(inner) < kMinSurroundedShare * static_cast<double>(on_loops))
            return;
        if (!any_refinable(h, result.cut, marked))
            return;
        Remeshed again;
        if (!remesh(h, options, refine_marked(h, result.cut, marked), again, result))
            return;
        const TopologyStats then = topology_stats(again.mesh);
        bool better = pieces ? then.components < now.components && then.boundary_loops <= now.boundary_loops
                             : then.boundary_loops < now.boundary_loops && then.components <= now.components &&
                                   (slits || then.genus <= now.genus);
        if (better && cracks) {
            // Where mending a loop spanned a hole of the sample, the round is tried once more without
            // that loop (the others may be cracks), and the loop is left to later rounds as well.
            std::vector<const CrackWatch*> spanning;
            for (const CrackWatch& watch : mended)
                if (watch.spans_a_hole(h, again.mesh))
                    spanning.push_back(&watch);
            if (!spanning.empty()) {
                for (const CrackWatch* watch : spanning)
                    rims.insert(rims.end(), watch->nodes().begin(), watch->nodes().end());
                if (retried || spanning.size() == mended.size())
                    return;
                retried = true;
                continue;
            }
            const double reach = median_reach(mended);
            better = again.stats.dropped_fans <= result.surface.dropped_fans &&
                     !crossings_grow(self_intersecting_faces(result.mesh).size(), self_intersecting_faces(again.mesh).size()) &&
                     !spans_more_holes(h, result.mesh, again.mesh, reach) &&
                     !leaves_points(h, result.mesh, again.mesh, reach, options.fit.threads);
        }
        if (!better)
            return;
        keep_round(again, result, tiles, surface);
        ++round;
        retried = false;
    }
}

// Options of a stage after the surface (fit, slivers, untangling), vertical along the height field's
// axis when the surface is one: a height field stays a graph, every face they change facing up its axis.
template <typename Options>
Options along_height_field(Options options, const SurfaceStats& surface)
{
    if (surface.height_field_used) {
        options.vertical = true;
        options.axis = surface.height_field_axis;
    }
    return options;
}

// Crossing pairs of `mesh` that the untangling (untangle.h, as mesh_cut runs it last) leaves, on a copy.
std::size_t crossings_left(const Mesh& mesh, const SurfaceStats& surface, const UntangleOptions& options)
{
    if (options.max_rounds == 0)
        return self_intersecting_faces(mesh).size();
    Mesh copy = mesh;
    return untangle(copy, along_height_field(options, surface)).pairs_after;
}

// A dropped-tile round may leave, after the untangling, one more crossing pair than the cut before
// for every this many fans it brings back: a crossing pair is two faces, a fan left out a tile's
// points. The denoised noisy bunny's ear tips at tolerance 0.002: 58 -> 32 fans left out, 0 -> 2 pairs
// left (1.4 cm of an ear was given up for them); a cube with a rod 2.5 spacings thick: 38 -> 4 fans,
// 4 -> 15 pairs, its refined tiles folded into the rod's others.
constexpr std::size_t kFansPerCrossing = 10;

// After the surface: tiles whose fans it left out although their points lie away from it are refined
// and the cut meshed again (MeshOptions::dropped_rounds), into `result` and `tiles`. A round whose
// surface crosses itself more than the one before, by more than the untangling undoes (judged on
// copies of both; kFansPerCrossing), is not kept and ends the rounds: where refined tiles fold into each
// other or into their neighbours (a roof tile that is half wall in a height field, a thin rod's
// tiles), the untangling cannot undo it, and a piece left out is the smaller harm.
// Returns the tiles still away from the mesh (away_tiles), whose points the fit leaves out.
std::vector<bool> refine_dropped_tiles(const Hierarchy& h, const MeshOptions& options, SurfaceOptions& surface,
                                       MeshResult& result, std::vector<Tile>& tiles)
{
    std::vector<bool> away = away_tiles(h, result.cut, tiles, result.mesh, options.fit.threads);
    std::size_t crossings = 0; // self-intersecting pairs of the surface, counted once a round starts
    for (int round = 0; round < options.dropped_rounds && !away.empty(); ++round) {
        if (!any_refinable(h, result.cut, away))
            break;
        if (round == 0)
            crossings = self_intersecting_faces(result.mesh).size();
        // A refined cut that cannot be meshed (no surface left) ends the rounds as the other rounds do.
        Remeshed again;
        if (!remesh(h, options, refine_marked(h, result.cut, away), again, result))
            break;
        const std::size_t now = self_intersecting_faces(again.mesh).size();
        const std::size_t regained = result.surface.dropped_fans > again.stats.dropped_fans
                                         ? result.surface.dropped_fans - again.stats.dropped_fans : 0;
        if (now > crossings && (regained == 0 || crossings_left(again.mesh, again.stats, options.untangle) >
                                                     crossings_left(result.mesh, result.surface, options.untangle) + regained / kFansPerCrossing))
            break;
        keep_round(again, result, tiles, surface);
        crossings = now;
        away = away_tiles(h, result.cut, tiles, result.mesh, options.fit.threads);
    }
    return away;
}

// A face of the surface lies over a hole of the sample when a spot of it (its centre, its edges'
// midpoints) has no input point within its reach: the larger of its tiles' geometric error
// (node_error: a coarse tile's fan may lie that far from the points anyway) and kHoleSpacings of
// their sample spacing (the fill keeps holes of a mean width of SurfaceOptions::max_gap_width = 4
// spacings open). No tile's own coverage gap sees a hole that lies between tiles: three tiles around
// it, each hull over a rim of it under 4 spacings deep, and gap triangles within the local alpha
// radius across the rest (a sphere with a hole 11 spacings wide at tolerance 0.01: covered, the mesh
// 0.13 from every point over it).
constexpr double kHoleSpacings = 4.0;
// In a height field, faces at least this steep (60 degrees) are bridged steps (see faces_over_holes).
constexpr double kMinHoleFaceCos = 0.5;
// A face over a hole turns from its tiles' planes by at most 45 degrees (see faces_over_holes).
constexpr double kMinHoleTileCos = 0.7071;

struct FacesOverHoles
{
    std::vector<bool> tiles; //!< per tile of the cut: a corner of such a face
    double area = 0.0;       //!< of those faces
};

// Whether an input point lies within `reach` of q: down the tree by the nodes' boxes, first found ends it.
bool point_within(const Hierarchy& h, const Vec3& q, double reach, std::vector<std::int32_t>& stack)
{
    const double reach2 = reach * reach;
    stack.assign(1, 0);
    while (!stack.empty()) {
        const Node& n = h.nodes[static_cast<std::size_t>(stack.back())];
        stack.pop_back();
        if (!(n.box.squared_distance_to(q) <= reach2))
            continue;
        if (!n.is_leaf()) {
            stack.push_back(n.left);
            stack.push_back(n.right);
            continue;
        }
        for (std::uint32_t i = n.begin; i < n.end; ++i)
            if (squared_distance(h.cloud.positions[i], q) <= reach2)
                return true;
    }
    return false;
}

FacesOverHoles faces_over_holes(const Hierarchy& h, const Cut& cut, const std::vector<Tile>& tiles, const Mesh& mesh,
                                const SurfaceStats& surface, std::size_t threads)
{
    FacesOverHoles out;
    out.tiles.assign(cut.size(), false);
    OpenMesh::VPropHandleT<int> cluster;
    if (!mesh.get_property_handle(cluster, kVertexCluster) || tiles.size() != cut.size())
        return out;
    const std::unordered_map<std::int32_t, std::size_t> index = positions_in(cut);
    std::vector<double> reach(cut.size());
    for (std::size_t k = 0; k < cut.size(); ++k)
        reach[k] = std::max(node_error(h.nodes[static_cast<std::size_t>(cut[k])]), kHoleSpacings * sample_spacing(h, tiles[k]));
    std::vector<char> over(mesh.n_faces(), 0);
    run_parallel_ranges(mesh.n_faces(), 256, threads, [&](std::size_t begin, std::size_t end) {
        std::vector<std::int32_t> stack;
        for (std::size_t f = begin; f < end; ++f) {
            std::array<Vec3, 3> c{};
            std::array<std::size_t, 3> tile{cut.size(), cut.size(), cut.size()};
            double r = 0.0;
            int k = 0;
            for (const Mesh::VertexHandle v : mesh.fv_range(Mesh::FaceHandle(static_cast<int>(f)))) {
                if (const auto it = index.find(mesh.property(cluster, v)); it != index.end()) {
                    r = std::max(r, reach[it->second]);
                    tile[static_cast<std::size_t>(k)] = it->second;
                }
                c[static_cast<std::size_t>(k++)] = to_vec3(mesh.point(v));
            }
            // A face no longer than half its reach has every spot within that of a corner, and its
            // corners are on the sample (rim points, or split points between them).
            const double longest = std::max({distance(c[0], c[1]), distance(c[1], c[2]), distance(c[2], c[0])});
            if (!(r > 0.0) || longest <= 0.5 * r)
                continue;
            // A height field bridges its steps on purpose (SurfaceOptions::bridge_steps): a face
            // standing steep over the plane is a wall no scan saw from above, not a hole.
            const Vec3 n = cross(c[1] - c[0], c[2] - c[0]);
            if (surface.height_field_used && !(std::abs(dot(n, surface.height_field_axis)) >= kMinHoleFaceCos * norm(n)))
                continue;
            // A face across a hole lies in the surface around it, as its tiles do; one that turns
            // from a tile's plane by more than 45 degrees joins tiles across an edge (the folds and
            // cracks of coarse tiles at an acute edge, the crack and crossing rounds' business).
            bool in_surface = true;
            for (const std::size_t t : tile)
                in_surface = in_surface && t < cut.size() && std::abs(dot(n, tiles[t].normal)) >= kMinHoleTileCos * norm(n);
            if (!in_surface)
                continue;
            for (const Vec3& spot : {(c[0] + c[1] + c[2]) / 3.0, (c[0] + c[1]) * 0.5, (c[1] + c[2]) * 0.5, (c[2] + c[0]) * 0.5})
                if (!point_within(h, spot, r, stack)) {
                    over[f] = 1;
                    break;
                }
        }
    });
    for (const Mesh::FaceHandle f : mesh.faces()) {
        if (!over[static_cast<std::size_t>(f.idx())])
            continue;
        out.area += mesh.calc_face_area(f);
        for (const Mesh::VertexHandle v : mesh.fv_range(f))
            if (const auto it = index.find(mesh.property(cluster, v)); it != index.end())
                out.tiles[it->second] = true;
    }
    return out;
}

// Rim steps of a hole round (refine_over_holes).
constexpr int kRimSteps = 2;

// The indices of the marked entries.
std::vector<std::size_t> marked_tiles(const std::vector<bool>& marked)
{
    std::vector<std::size_t> which;
    for (std::size_t k = 0; k < marked.size(); ++k)
        if (marked[k])
            which.push_back(k);
    return which;
}

// The tiles (indices into `cut`, which is in point order) holding a point of the regular sample
// (sample_distances) farther than `limit` from the mesh.
std::vector<bool> tiles_of_far_points(const Hierarchy& h, const Cut& cut, const std::vector<double>& distances, double limit)
{
    assert(in_point_order(h, cut));
    std::vector<bool> far(cut.size(), false);
    const std::size_t step = far_sample_step(h);
    for (std::size_t s = 0; s < distances.size(); ++s) {
        if (!(distances[s] > limit))
            continue;
        const auto i = static_cast<std::uint32_t>(s * step);
        const auto it = std::upper_bound(cut.begin(), cut.end(), i, [&](std::uint32_t point, std::int32_t node) {
            return point < h.nodes[static_cast<std::size_t>(node)].begin;
        });
        if (it != cut.begin())
            far[static_cast<std::size_t>(it - cut.begin() - 1)] = true;
    }
    return far;
}

// Where faces of the surface lie over a hole of the sample (faces_over_holes), the tiles of their
// corners that are not leaves are refined and the cut meshed again (MeshOptions::hole_rounds): finer
// tiles reach less far over the hole and their gap triangles are narrower, so that the hole opens and
// the fill (its width test) keeps it open. A round is kept only when less of the surface lies over
// holes, with no more pieces and no more fans left out.
void refine_over_holes(const Hierarchy& h, const MeshOptions& options, SurfaceOptions& surface, MeshResult& result,
                       std::vector<Tile>& tiles)
{
    if (options.hole_rounds == 0)
        return;
    FacesOverHoles over = faces_over_holes(h, result.cut, tiles, result.mesh, result.surface, options.fit.threads);
    std::vector<double> distances; // of the regular sample to result.mesh, once needed
    for (int round = 0; round < options.hole_rounds && over.area > 0.0; ++round) {
        if (!any_refinable(h, result.cut, over.tiles))
            return;
        Remeshed again;
        if (!remesh(h, options, refine_marked(h, result.cut, over.tiles), again, result))
            return;
        FacesOverHoles over_again;
        const TopologyStats now = topology_stats(result.mesh);
        const auto better = [&] {
            over_again = faces_over_holes(h, again.cut, again.tiles, again.mesh, again.stats, options.fit.threads);
            const TopologyStats then = topology_stats(again.mesh);
            // No fewer loops: refining beside one hole can cover another (QA round 58: terrains at
            // 0.005 lost a 16-spacing hole that was open while the area over holes fell elsewhere).
            return over_again.area < over.area && then.components <= now.components &&
                   then.boundary_loops >= now.boundary_loops && again.stats.dropped_fans <= result.surface.dropped_fans;
        };
        if (!better())
            return;
        // An opened hole's rim runs along the outlines of its tiles, which a tile built from a sample of
        // its points (TileOptions::max_points) draws up to a sample spacing inside the points there (a
        // terrain's lakes at tolerance 0.02: the rim 0.03 inside the sample). The tiles of the sample
        // points that the new mesh leaves farther than the old one left any, by a spacing, are refined
        // (fewer points, a finer sample) and meshed again, up to kRimSteps times; the round is kept only
        // once none is left.
        // (The sample's distances to the mesh kept are those found for it as the round before's new mesh.)
        if (distances.empty())
            distances = sample_distances(h, result.mesh, options.fit.threads);
        const double limit = (distances.empty() ? 0.0 : *std::max_element(distances.begin(), distances.end())) +
                             crack_reach(h, tiles, marked_tiles(over.tiles)) / kCrackReach;
        std::vector<double> again_distances;
        for (int step = 0;; ++step) {
            again_distances = sample_distances(h, again.mesh, options.fit.threads);
            const std::vector<bool> far = tiles_of_far_points(h, again.cut, again_distances, limit);
            if (std::none_of(far.begin(), far.end(), [](bool b) { return b; }))
                break;
            if (step == kRimSteps || !remesh(h, options, refine_marked(h, again.cut, far), again, result) || !better())
                return;
        }
        keep_round(again, result, tiles, surface);
        over = std::move(over_again);
        distances = std::move(again_distances);
    }
}

// The tiles (indices into the cut) of the faces that cross another face: a fan face's own tile, a gap
// face's corners' tiles.
std::vector<bool> tiles_of_crossings(const Cut& cut, const Mesh& mesh, const std::vector<std::pair<int, int>>& pairs)
{
    std::vector<bool> marked(cut.size(), false);
    OpenMesh::FPropHandleT<int> tile;
    OpenMesh::VPropHandleT<int> cluster;
    if (!mesh.get_property_handle(tile, kFaceTile) || !mesh.get_property_handle(cluster, kVertexCluster))
        return marked;
    const std::unordered_map<std::int32_t, std::size_t> index = positions_in(cut);
    const auto mark = [&](std::int32_t node) {
        if (const auto it = index.find(node); it != index.end())
            marked[it->second] = true;
    };
    for (const auto& [a, b] : pairs)
        for (const int f : {a, b}) {
            const Mesh::FaceHandle fh(f);
            if (const int t = mesh.property(tile, fh); t >= 0)
                mark(t);
            else
                for (const Mesh::VertexHandle v : mesh.fv_range(fh))
                    mark(mesh.property(cluster, v));
        }
    return marked;
}

// The stages after the surface, on `result` (its cut meshed into `tiles`; `away`: refine_dropped_tiles):
// tubes across empty space cut, points inserted into fans, notches and small covered holes closed,
// slivers, the vertex fit and the untangling.
void finish_mesh(const Hierarchy& h, const MeshOptions& options, MeshResult& result, const std::vector<Tile>& tiles,
                 const std::vector<bool>& away)
{
    result.tiles = tiles.size();
    const std::unordered_map<std::int32_t, double> spacing_of = sample_spacings(h, tiles);
    // A height field is one layer over its plane: no two of its surfaces face each other (and the
    // faces over its unsampled walls, long and off the sample, made the test 1.5-2.7 times the meshing).
    if (!result.surface.height_field_used)
        result.bridges = remove_bridges(result.mesh, h, spacing_of, options.bridges);
    result.refined_points = refine_fans(result.mesh, h, options.refine);
    result.notches = fill_notches(result.mesh, h, spacing_of, options.notches);
    result.covered_holes = close_covered_holes(result.mesh, h, spacing_of, along_height_field(options.covered_holes, result.surface));
    const FitOptions fit = along_height_field(options.fit, result.surface);
    const SliverOptions slivers = along_height_field(options.slivers, result.surface);
    const FoldOptions folds = along_height_field(options.folds, result.surface);
    const UntangleOptions untangle_options = along_height_field(options.untangle, result.surface);
    // Before the fit, which then places the vertices for the cleaned connectivity (and its flips make
    // no new caps: FitOptions::max_flip_angle_degrees).
    result.slivers = remove_slivers(result.mesh, slivers);
    {
        const std::vector<Vec3> kept = fit_points(h, result.cut, away);
        result.fit = fit_vertices(result.mesh, kept.empty() ? h.cloud.positions : kept, fit);
    }
    // After the fit, whose moves make most of the folds at sharp edges; the crossing pairs it found stay
    // as they are for the untangling (the flips leave their faces alone and add none).
    result.folds = remove_folds(result.mesh, folds, result.fit.pairs_known ? &result.fit.intersecting_pairs : nullptr, &h);
    // Last of the geometry: the fit's flips can also cross a thin part (it reverts only its moves).
    if (untangle_options.max_rounds > 0)
        result.untangle = result.fit.pairs_known ? untangle(result.mesh, untangle_options, std::move(result.fit.intersecting_pairs))
                                                 : untangle(result.mesh, untangle_options);
    result.fit.intersecting_pairs.clear(); // handed on (or not needed): the stats keep the counts
    result.fit.pairs_known = false;
}

// The points of the tiles that lie away from the mesh (away_tiles), which the fit leaves out.
std::size_t points_away(const Hierarchy& h, const Cut& cut, const std::vector<bool>& away)
{
    std::size_t points = 0;
    for (std::size_t k = 0; k < away.size() && k < cut.size(); ++k)
        if (away[k])
            points += h.nodes[static_cast<std::size_t>(cut[k])].count();
    return points;
}

// After the whole meshing: where faces of the finished mesh still cross each other, the tiles of those
// faces are refined and the cut meshed and finished again, up to MeshOptions::crossing_rounds times.
// Coarse tiles that straddle an acute edge of a solid fan from inside it and fold into their
// neighbours (a tetrahedron at tolerance 0.01: 379 crossing pairs left after the untangling; at
// 0.005, 2); finer tiles there follow the two faces. Only a mesh in one piece is refined (where tiles
// straddle two sheets a few spacings apart, a plate 3 spacings thick, the mesh is in 14-108 pieces
// with thousands of crossing pairs, a round mends nothing and costs a meshing that is slow there:
// 36 -> 64 s), and a round is kept when its finished mesh crosses itself less and is still one piece,
// with no more loops or handles, no more fans left out or no more points in the tiles left out away
// from it (a fan left out where its neighbours cover its points does no harm: the tetrahedron sampled
// as text, 414 -> 0 pairs, one more such fan), no more of it over the sample's holes
// (spans_more_holes) and no point of a regular sample farther from it (leaves_points). Crossings at
// leaves (the bunny's ear tip at 0.002) cost nothing. `tiles` and `away` follow the cut kept.
void refine_crossings(const Hierarchy& h, const MeshOptions& options, MeshResult& result, std::vector<Tile>& tiles,
                      std::vector<bool>& away)
{
    // What the rounds mend is what the untangling leaves: with the untangling off, nothing.
    if (options.untangle.max_rounds == 0)
        return;
    if (options.crossing_rounds == 0 || result.untangle.pairs_after == 0)
        return;
    TopologyStats now = topology_stats(result.mesh); // of result.mesh, round after round
    for (int round = 0; round < options.crossing_rounds; ++round) {
        const std::size_t crossings = result.untangle.pairs_after;
        if (crossings == 0 || now.components != 1)
            return;
        // The tile ids follow the fit's flips (faces across two tiles become gap faces, whose corners
        // name their tiles) and the untangling's collapses.
        const std::vector<bool> marked = tiles_of_crossings(result.cut, result.mesh, self_intersecting_faces(result.mesh));
        std::vector<std::size_t> which;
        for (std::size_t k = 0; k < marked.size(); ++k)
            if (marked[k] && !h.nodes[static_cast<std::size_t>(result.cut[k])].is_leaf())
                which.push_back(k);
        if (which.empty())
            return;
        MeshResult again;
        again.cut = refine_marked(h, result.cut, marked);
        SurfaceOptions again_options;
        std::vector<Tile> again_tiles = tiles_for(h, again.cut, options, again_options);
        try {
            build_surface(h, again_tiles, again.mesh, again_options, &again.surface);
        } catch (const InvalidInput&) {
            return;
        }
        again.meshed_tiles = result.meshed_tiles + again_tiles.size();
        std::vector<bool> again_away = refine_dropped_tiles(h, options, again_options, again, again_tiles);
        finish_mesh(h, options, again, again_tiles, again_away);
        const TopologyStats then = topology_stats(again.mesh);
        const bool fewer_left_out = again.surface.dropped_fans <= result.surface.dropped_fans ||
                                    points_away(h, again.cut, again_away) <= points_away(h, result.cut, away);
        if (again.untangle.pairs_after >= crossings || then.boundary_loops > now.boundary_loops || then.components != 1 ||
            then.genus > now.genus || !fewer_left_out)
            return;
        const double reach = crack_reach(h, tiles, which);
        if (reach > 0.0 && (spans_more_holes(h, result.mesh, again.mesh, reach) ||
                            leaves_points(h, result.mesh, again.mesh, reach, options.fit.threads)))
            return;
        result = std::move(again);
        tiles = std::move(again_tiles);
        away = std::move(again_away);
        now = then;
    }
}

} // namespace

void check_mesh_options(const MeshOptions& options)
{
    for (const int rounds : {options.small_object_rounds, options.gap_rounds, options.hole_rounds, options.dropped_rounds, options.piece_rounds,
                             options.crack_rounds, options.crossing_rounds})
        if (rounds < 0 || rounds > kMaxRefineRounds)
            throw InvalidInput("MeshOptions: small_object_rounds, gap_rounds, hole_rounds, dropped_rounds, piece_rounds, crack_rounds and crossing_rounds must be in [0, " +
                               std::to_string(kMaxRefineRounds) + "]");
    // Before any work: mesh_cut untangles only when max_rounds > 0 and the mesh crosses itself, so bad
    // untangling options were otherwise taken without a word; the fit and slivers' options were checked
    // only once the surface was built.
    check_untangle_options(options.untangle);
    check_surface_options(options.surface);
    check_tile_options(options.tiles);
    check_fit_options(options.fit);
    check_sliver_options(options.slivers);
    check_fold_options(options.folds);
    check_bridge_options(options.bridges);
}

MeshResult mesh_cut(const Hierarchy& h, const Cut& given, const MeshOptions& options)
{
    // A default-constructed hierarchy is a partition by every empty cut, and build_surface then spoke of
    // its own stage (QA round 37).
    if (h.nodes.empty() || h.cloud.size() == 0)
        throw InvalidInput("mesh: the hierarchy is empty (no points); build it from a point cloud first (build_hierarchy)");
    if (const std::string problem = cut_problem(h, given); !problem.empty())
        throw InvalidInput("mesh: the cut is not a partition of the model's points: " + problem);
    // A cut is a set of nodes: meshed in point order (the order every cut of cut.h comes in), so that
    // the same nodes in another order give the same mesh and result.cut. The tiles' order steers the
    // surface's ties: the 0.02 cut of a sphere reversed made 338 faces instead of 322.
    Cut cut = given;
    sort_in_point_order(h, cut);
    check_mesh_options(options);
    const auto start = std::chrono::steady_clock::now();
    MeshResult result;
    result.cut = cut;
    if (is_tiny_solid(h, cut)) {
        result.mesh = hull_mesh(h, cut[0]);
        if (result.mesh.n_faces() > 0) {
            result.tiles = result.meshed_tiles = 1;
            result.surface.tiles = result.surface.fan_tiles = result.surface.components = 1;
            result.surface.fan_faces = result.mesh.n_faces();
            color_vertices(result.mesh, h.cloud, options.colors);
            result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            return result;
        }
        result.mesh = Mesh(); // no hull: the tiles below build the mesh afresh
    }
    SurfaceOptions surface_options = options.surface;
    std::vector<Tile> tiles = refine_before_meshing(h, options, result.cut, surface_options);
    build_surface(h, tiles, result.mesh, surface_options, &result.surface);
    result.meshed_tiles = tiles.size();
    refine_broken_pieces(h, options, surface_options, result, tiles);
    refine_over_holes(h, options, surface_options, result, tiles);
    std::vector<bool> away = refine_dropped_tiles(h, options, surface_options, result, tiles);
    finish_mesh(h, options, result, tiles, away);
    refine_crossings(h, options, result, tiles, away);
    color_vertices(result.mesh, h.cloud, options.colors);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

namespace {

constexpr double kJoinSpacings = 3.0; // of their point spacings: two tiles' points this close are joined
constexpr std::size_t kCheapMendTiles = 1000; // mesh_mended goes past a finer cut no better up to this many tiles meshed
constexpr std::size_t kMinSplitShare = 20; // a finer cut of a large cut is tried when it adds 1 tile in this many
constexpr std::size_t kJoinSample = 256; // points of a node compared by broken_into_pieces

// Whether a mesh is in pieces where its sample is not: two pieces hold tiles that are neighbours on
// the surface (Tile::neighbours: the sampled surface runs from one to the other). Separate objects and
// a scan's separate fragments have no such tiles, and cost nothing more. mesh_mended's test.
bool broken_into_pieces(const Hierarchy& h, const MeshResult& r, const TopologyStats& t, const MeshOptions& options)
{
    if (t.components < 2 || t.boundary_loops == 0)
        return false;
    OpenMesh::VPropHandleT<int> cluster;
    if (!r.mesh.get_property_handle(cluster, kVertexCluster))
        return false;
    // The piece of every vertex (a flood over the edges), then of every tile with a vertex.
    std::vector<int> piece(r.mesh.n_vertices(), -1);
    int pieces = 0;
    for (const Mesh::VertexHandle seed : r.mesh.vertices()) {
        if (piece[static_cast<std::size_t>(seed.idx())] >= 0 || r.mesh.is_isolated(seed))
            continue;
        std::vector<Mesh::VertexHandle> stack{seed};
        piece[static_cast<std::size_t>(seed.idx())] = pieces;
        while (!stack.empty()) {
            const Mesh::VertexHandle v = stack.back();
            stack.pop_back();
            for (const Mesh::VertexHandle w : r.mesh.vv_range(v))
                if (piece[static_cast<std::size_t>(w.idx())] < 0) {
                    piece[static_cast<std::size_t>(w.idx())] = pieces;
                    stack.push_back(w);
                }
        }
        ++pieces;
    }
    const std::unordered_map<std::int32_t, std::size_t> index = positions_in(r.cut);
    std::vector<int> tile_piece(r.cut.size(), -1);
    for (const Mesh::VertexHandle v : r.mesh.vertices())
        if (const auto it = index.find(r.mesh.property(cluster, v)); it != index.end() && piece[static_cast<std::size_t>(v.idx())] >= 0)
            tile_piece[it->second] = piece[static_cast<std::size_t>(v.idx())];
    // Neighbours in two pieces whose points come within kJoinSpacings point spacings: the sample is
    // continuous there. Neighbours are judged by the bisector plane, which a scan's fragment across a
    // gap in the sample can also come near (bun000 at 0.001: three finer meshings, none joined). At
    // most kJoinSample points of each node are compared (every k-th: their spacing grows by sqrt(k)).
    const std::vector<Tile> tiles = make_tiles(h, r.cut, options.tiles);
    const auto& p = h.cloud.positions;
    const auto stride = [&](std::size_t k) {
        return std::max<std::size_t>(1, (h.nodes[static_cast<std::size_t>(r.cut[k])].count() + kJoinSample - 1) / kJoinSample);
    };
    for (std::size_t k = 0; k < tiles.size(); ++k)
        for (const std::uint32_t n : tiles[k].neighbours) {
            if (tile_piece[k] < 0 || tile_piece[n] < 0 || tile_piece[k] == tile_piece[n] || n < k)
                continue;
            const Node& a = h.nodes[static_cast<std::size_t>(r.cut[k])];
            const Node& b = h.nodes[static_cast<std::size_t>(r.cut[n])];
            const std::size_t sa = stride(k), sb = stride(n);
            const double reach = kJoinSpacings * std::max(tiles[k].spacing() * std::sqrt(static_cast<double>(sa)),
                                                          tiles[n].spacing() * std::sqrt(static_cast<double>(sb)));
            for (std::uint32_t i = a.begin; i < a.end; i += static_cast<std::uint32_t>(sa))
                for (std::uint32_t j = b.begin; j < b.end; j += static_cast<std::uint32_t>(sb))
                    if (squared_norm(p[i] - p[j]) <= reach * reach)
                        return true;
        }
    return false;
}

// The points of the tiles that have a vertex in the mesh: a finer cut that joins pieces by leaving one
// out (a subsampled rocker arm: a 31-vertex piece gone; a subsampled bunny: its ear tips cut off; QA,
// session 20) has fewer.
std::size_t kept_points(const Hierarchy& h, const MeshResult& r)
{
    OpenMesh::VPropHandleT<int> cluster;
    if (!r.mesh.get_property_handle(cluster, kVertexCluster))
        return 0;
    std::vector<std::int32_t> nodes;
    for (const Mesh::VertexHandle v : r.mesh.vertices())
        if (!r.mesh.is_isolated(v))
            nodes.push_back(r.mesh.property(cluster, v));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    std::size_t points = 0;
    for (const std::int32_t id : nodes)
        if (id >= 0 && static_cast<std::size_t>(id) < h.nodes.size())
            points += h.nodes[static_cast<std::size_t>(id)].count();
    return points;
}

// mesh_mended's terms for a candidate mesh (topology `then`) over the one kept: fewer pieces, no more
// boundary loops, and no fewer points kept (kept_points, counted only when the topology passes). The
// candidate's kept points when it passes.
std::optional<std::size_t> mends(const Hierarchy& h, const MeshResult& candidate, const TopologyStats& then,
                                 const TopologyStats& kept_topology, std::size_t kept)
{
    if (!(then.components < kept_topology.components && then.boundary_loops <= kept_topology.boundary_loops))
        return std::nullopt;
    const std::size_t points = kept_points(h, candidate);
    if (points < kept)
        return std::nullopt;
    return points;
}

} // namespace

MendedMeshResult mesh_mended(const Hierarchy& h, const std::function<Cut(int)>& cut_at, const MeshOptions& options, int mend_steps)
{
    if (mend_steps < 0 || mend_steps > 8)
        throw InvalidInput("mesh_mended: mend_steps must be in [0, 8]");
    if (!cut_at)
        throw InvalidInput("mesh_mended: cut_at is empty; pass a function that gives the cut of each step");
    MendedMeshResult out;
    Cut kept_cut = cut_at(0);               // as cut_at gave it (mesh_cut may refine it)
    std::size_t cut_size = kept_cut.size(); // of the last cut meshed
    out.result = mesh_cut(h, kept_cut, options);
    out.asked = topology_stats(out.result.mesh);
    out.in_pieces = broken_into_pieces(h, out.result, out.asked, options);
    TopologyStats best = out.asked; // of out.result, and the points it keeps
    std::size_t best_kept = out.in_pieces ? kept_points(h, out.result) : 0;
    for (int step = 1; step <= mend_steps && out.in_pieces; ++step) {
        Cut finer = cut_at(step);
        // At the leaves, or at a noise floor: nothing finer. Checked first, since it is not meshed (QA
        // round 59: {a node, its child} as step 1's cut ended the steps without a word, where mesh_cut's
        // InvalidInput is promised); a cut meshed is checked by mesh_cut.
        if (finer.size() <= cut_size) {
            check_cut(h, finer, "mesh_mended: step " + std::to_string(step) + "'s cut");
            break;
        }
        // A large cut that is nearly all leaves (two sheets a few spacings apart, whose leaves straddle
        // both: 6,055 of 6,234 nodes) splits too few tiles to join its pieces, and each step costs a
        // whole meshing (QA round 31's box shell: three more steps, 13 to 75 s, 56 pieces to 44).
        if (cut_size > kCheapMendTiles && finer.size() < cut_size + cut_size / kMinSplitShare)
            break;
        cut_size = finer.size();
        // A finer cut can break elsewhere (the rotated bunny at 0.03: 2 pieces, at 0.021 4, at 0.015 1):
        // the steps go on while the best so far is in pieces, past one that is no better only while
        // the meshing is small enough to take a fraction of a second (the cost stays bounded where
        // the pieces do not join: at most one finer meshing of a large cut). Its size counts the tiles
        // of every remeshing round (MeshResult::meshed_tiles), not only the cut's: curves sampled as
        // wires made 500-tile cuts that mesh_cut refined and meshed three times over, 4.5 s each, all
        // for steps that joined nothing (QA round 31: 75% of the run).
        MeshResult candidate = mesh_cut(h, finer, options);
        const TopologyStats then = topology_stats(candidate.mesh);
        if (const std::optional<std::size_t> kept = mends(h, candidate, then, best, best_kept)) {
            out.result = std::move(candidate);
            out.steps = step;
            kept_cut = std::move(finer);
            best = then;
            best_kept = *kept;
            out.in_pieces = broken_into_pieces(h, out.result, best, options);
        } else if (candidate.meshed_tiles > kCheapMendTiles) {
            break;
        }
    }
    // Pieces that finer cuts did not join may be the two sides of a thin wall, which the bisector test
    // takes for neighbours (TileOptions::meet_factor): the surface joins the sides here and tears them
    // there. Last, after the finer cuts, so that a cut they close stays as it was (a plate whose rim
    // is not sampled opens along it with thin walls: the rocker arm at tolerance 0.015).
    if (out.in_pieces && options.thin_walls_when_in_pieces && options.tiles.meet_factor == 0.0) {
        MeshOptions thin = options;
        thin.tiles.meet_factor = kThinWallMeetFactor;
        MeshResult candidate = mesh_cut(h, kept_cut, thin);
        const TopologyStats then = topology_stats(candidate.mesh);
        if (mends(h, candidate, then, best, best_kept)) {
            out.result = std::move(candidate);
            out.thin_walls = true;
            out.in_pieces = broken_into_pieces(h, out.result, then, thin);
        }
    }
    return out;
}

MendedMeshResult mesh_at_tolerance(const Hierarchy& h, double tolerance, const MeshOptions& options, int mend_steps)
{
    return mesh_mended(h, [&](int step) { return cut_by_tolerance(h, tolerance * std::pow(0.5, 0.5 * step)); }, options,
                       mend_steps);
}

// mesh_to_triangle_count stops once a fitting cut's mesh is within 1 / kCloseEnough of the target.
constexpr std::size_t kCloseEnough = 100;

TriangleCountResult mesh_to_triangle_count(const Hierarchy& h, std::size_t triangles, const MeshOptions& options,
                                           std::size_t max_meshings)
{
    if (triangles == 0 || max_meshings == 0)
        throw InvalidInput("mesh_to_triangle_count: the triangle target and max_meshings must be at least 1");
    const std::size_t leaves = std::max<std::size_t>(1, h.leaf_count());
    TriangleCountResult best;  // largest N that fits so far
    TriangleCountResult over;  // smallest N that does not fit so far (kept in case nothing fits)
    std::size_t fits = 0, fails = leaves + 1; // bracket on N
    auto try_tiles = [&](std::size_t n) {
        TriangleCountResult r;
        r.cut = cut_by_budget(h, n);
        r.result = mesh_cut(h, r.cut, options);
        const std::size_t faces = r.result.mesh.n_faces();
        if (faces <= triangles) {
            if (n > fits) {
                fits = n;
                best = std::move(r);
            }
        } else if (n < fails) {
            fails = n;
            over = std::move(r);
        }
        return faces;
    };
    // First guess: about 16 faces per tile (a fine cut's fan and gap faces after collapsing).
    std::size_t n = std::clamp<std::size_t>(triangles / 16, 1, leaves);
    std::size_t meshings = 0;
    while (meshings < max_meshings) {
        const std::size_t faces = try_tiles(n);
        ++meshings;
        if (fits + 1 >= fails) // converged (this also covers the leaves fitting and one tile not fitting)
            break;
        // Close enough: the bracket's last steps change the face count by a fraction of a percent and
        // cost a meshing each (the bunny at 20,000 faces: 10 meshings, 5.7 s, for the last 0.5%).
        if (fits > 0 && best.result.mesh.n_faces() * kCloseEnough >= triangles * (kCloseEnough - 1))
            break;
        // Next: scale N by the target over the faces seen (faces per tile is nearly constant locally),
        // kept strictly inside the bracket; bisect when the guess falls outside it.
        const double scaled = static_cast<double>(n) * static_cast<double>(triangles) / std::max<double>(1.0, static_cast<double>(faces));
        std::size_t next = static_cast<std::size_t>(scaled);
        if (next <= fits || next >= fails)
            next = fits + (fails - fits) / 2;
        next = std::clamp<std::size_t>(next, 1, leaves);
        if (next == n)
            break;
        n = next;
    }
    TriangleCountResult out = fits > 0 ? std::move(best) : std::move(over);
    out.meshings = meshings;
    if (fits == 0)
        return out;
    // The face count of coarse cuts of thin parts is not monotone in N, nor is their topology: the
    // bunny's best 500-face cut (29 tiles) is in 2 pieces, 28 tiles are whole. Where the cut found is in
    // pieces that its sample joins, a few smaller budgets are meshed too, and one is kept on
    // mesh_mended's terms (fewer pieces, no more loops, no points left out that the first kept).
    out.asked = topology_stats(out.result.mesh);
    out.in_pieces = broken_into_pieces(h, out.result, out.asked, options);
    TopologyStats kept_topology = out.asked;
    std::size_t kept = out.in_pieces ? kept_points(h, out.result) : 0;
    std::size_t last = fits;
    for (const double fraction : {0.95, 0.9, 0.85, 0.8}) {
        if (!out.in_pieces)
            break;
        const auto smaller = static_cast<std::size_t>(static_cast<double>(fits) * fraction);
        if (smaller < 1 || smaller >= last)
            continue;
        last = smaller;
        TriangleCountResult r;
        r.cut = cut_by_budget(h, smaller);
        r.result = mesh_cut(h, r.cut, options);
        ++out.meshings;
        const TopologyStats then = topology_stats(r.result.mesh);
        const std::optional<std::size_t> points =
            r.result.mesh.n_faces() <= triangles ? mends(h, r.result, then, kept_topology, kept) : std::nullopt;
        if (points) {
            r.meshings = out.meshings;
            r.asked = out.asked;
            r.smaller_budget = true;
            kept_topology = then;
            kept = *points;
            r.in_pieces = broken_into_pieces(h, r.result, then, options);
            out = std::move(r);
        } else if (r.result.meshed_tiles > kCheapMendTiles) {
            break; // a large meshing (see mesh_mended) costs at most one more
        }
    }
    return out;
}


double e_rms(const Hierarchy& h, const Cut& cut)
{
    check_node_ids(h, cut);
    // Divided by the model's points: a node listed twice counted its points twice, a node missing left
    // them out, and the mean came out wrong without a word.
    if (const std::string problem = cut_problem(h, cut); !problem.empty())
        throw InvalidInput("e_rms / measure_quality: the cut is not a partition of the model's points (" + problem +
                           "); pass the cut that was meshed (MeshResult::cut)");
    double sum = 0.0;
    for (std::int32_t id : cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        const Vec3 normal = n.frame.vectors[0];
        for (std::uint32_t i = n.begin; i < n.end; ++i)
            sum += std::abs(dot(h.cloud.positions[i] - n.centre(), normal));
    }
    const double diameter = h.bbox().largest_side();
    const auto count = static_cast<double>(h.cloud.size());
    return diameter > 0 && count > 0 ? sum / (count * diameter) : 0.0;
}

namespace {

// Whether a tile is long and thin and most of its points have neighbours along a line only. A whole
// tile of an arc of a curve is planar and spreads both ways a little, so the main test is local: the
// kNeighbours nearest points of kSamples points of the tile, among at most kCandidates of its points
// (both taken at even strides: deterministic, and bounded per tile).
bool is_line_tile(const Hierarchy& h, const Node& node)
{
    constexpr std::size_t kNeighbours = 8, kSamples = 16, kCandidates = 4096;
    const std::size_t n = node.end - node.begin;
    // An arc of a curve is long and thin as a whole too (a helix's: a tenth as wide as long); a patch
    // of surface sampled in scan lines, each point's neighbours along its line, is not.
    constexpr double kMaxTileWidthRatio = 0.3;
    const auto& spread = node.frame.values;
    if (n <= kNeighbours || !(spread[1] < kMaxTileWidthRatio * kMaxTileWidthRatio * spread[2]))
        return false;
    const Vec3* points = h.cloud.positions.data() + node.begin;
    const std::size_t stride = (n + kCandidates - 1) / kCandidates;
    std::size_t lines = 0;
    std::vector<std::pair<double, std::size_t>> near;
    for (std::size_t s = 0; s < kSamples; ++s) {
        const Vec3& p = points[s * n / kSamples];
        near.clear();
        for (std::size_t i = 0; i < n; i += stride)
            near.push_back({squared_norm(points[i] - p), i});
        const std::size_t k = std::min(kNeighbours + 1, near.size()); // the sample itself among them
        std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k), near.end());
        Moments m;
        for (std::size_t j = 0; j < k; ++j)
            m.add(points[near[j].second]);
        const auto values = eigen_decomposition(m).values;
        if (values[2] > 0.0 && values[1] < kLineWidthRatio * kLineWidthRatio * values[2])
            ++lines;
    }
    return 2 * lines > kSamples;
}

} // namespace

std::size_t count_sharp_loops(const Mesh& mesh, double degrees)
{
    // Judged locally: a long loop around a curved part (a scan's outline, the bunny's base) has faces
    // that turn a lot along it, but only a slit along an acute edge has, within a few edge lengths of
    // a loop vertex, loop vertices whose faces face away from its own (the other side of the slit).
    // The loop is sharp when four fifths of its vertices are (slits along acute edges of generated
    // solids: 90-100%; the bunny's base holes and a single scan's outline: 0-61%).
    const double min_dot = std::cos(radians(degrees));
    constexpr double kReachEdges = 3.0;
    constexpr std::size_t kMaxVertices = 1024; // a longer loop is judged on this many, spread along it
    std::vector<bool> seen(mesh.n_halfedges(), false);
    std::size_t sharp = 0;
    for (const auto start : mesh.halfedges()) {
        if (!mesh.is_boundary(start) || seen[static_cast<std::size_t>(start.idx())])
            continue;
        std::vector<Mesh::VertexHandle> loop;
        double length = 0.0;
        for (auto h = start; !seen[static_cast<std::size_t>(h.idx())]; h = mesh.next_halfedge_handle(h)) {
            seen[static_cast<std::size_t>(h.idx())] = true;
            loop.push_back(mesh.to_vertex_handle(h));
            length += mesh.calc_edge_length(h);
        }
        const double reach = kReachEdges * length / static_cast<double>(loop.size());
        const std::size_t stride = (loop.size() + kMaxVertices - 1) / kMaxVertices;
        std::vector<Vec3> at;                      // the judged vertices' positions
        std::vector<std::vector<Vec3>> normals;    // and the normals of their faces
        for (std::size_t i = 0; i < loop.size(); i += stride) {
            const auto p = mesh.point(loop[i]);
            at.push_back(Vec3{p[0], p[1], p[2]});
            normals.emplace_back();
            for (const auto f : mesh.vf_range(loop[i])) {
                const auto n = mesh.calc_face_normal(f);
                normals.back().push_back(Vec3{n[0], n[1], n[2]});
            }
        }
        const auto turn = [&](std::size_t a, std::size_t b) {
            for (const Vec3& m : normals[a])
                for (const Vec3& n : normals[b])
                    if (dot(m, n) < min_dot)
                        return true;
            return false;
        };
        std::size_t sharp_vertices = 0;
        for (std::size_t a = 0; a < at.size(); ++a)
            for (std::size_t b = 0; b < at.size(); ++b)
                if (distance(at[a], at[b]) <= reach && turn(a, b)) {
                    ++sharp_vertices;
                    break;
                }
        sharp += 5 * sharp_vertices >= 4 * at.size() ? 1 : 0;
    }
    return sharp;
}

std::vector<char> nodes_in_mesh(const Hierarchy& h, const Mesh& mesh)
{
    std::vector<char> shown(h.nodes.size(), 0);
    OpenMesh::VPropHandleT<int> cluster;
    bool any = false;
    if (mesh.get_property_handle(cluster, kVertexCluster))
        for (const auto v : mesh.vertices())
            if (const int id = mesh.property(cluster, v); id >= 0 && static_cast<std::size_t>(id) < shown.size()) {
                shown[static_cast<std::size_t>(id)] = 1;
                any = true;
            }
    if (!any)
        std::fill(shown.begin(), shown.end(), 1);
    return shown;
}

QualityReport measure_quality(const Hierarchy& h, const Cut& cut, const Mesh& mesh, const QualityOptions& options)
{
    QualityReport q;
    q.e_rms = e_rms(h, cut); // first: it checks the cut
    if (options.far_points_found)
        options.far_points_found->clear(); // as no point is measured when the points have no extent
    // A vertex the caller moved to NaN or infinity reached CGAL's distance and intersection queries,
    // which threw their own precondition exception.
    if (const Mesh::VertexHandle v = first_non_finite_vertex(mesh); v.is_valid())
        throw InvalidInput("measure_quality: mesh vertex " + std::to_string(v.idx()) + " has a NaN or infinite coordinate");
    // A mesh without faces has no distance to the points: its report said 0 (every point on the mesh),
    // the best score there is, and the CLI prints distances as measured.
    if (mesh.faces().begin() == mesh.faces().end()) // deleted faces are skipped
        throw InvalidInput("measure_quality: the mesh has no faces, so no distance of the points to it can be measured");
    q.topology = topology_stats(mesh);
    // A hierarchy just built from denoised points still has the points read: the distances are to them.
    const std::vector<Vec3>& points = h.raw_positions.empty() ? h.cloud.positions : h.raw_positions;
    if (mesh.n_faces() > 0 && h.bbox().diagonal() > 0) {
        // Far: beyond 5% of the diagonal and twice the cut's largest tile error, so that a coarse cut's
        // own approximation (a 10-tile bunny) is not taken for points left out.
        double coarsest = 0.0;
        for (const std::int32_t id : cut)
            coarsest = std::max(coarsest, node_error(h.nodes[static_cast<std::size_t>(id)]));
        FarPoints far;
        far.beyond = 2.0 * coarsest;
        far.given = options.far_points;
        far.found = options.far_points_found;
        q.point_to_mesh = point_to_mesh_distance(points, mesh, far);
        q.mesh_to_points = mesh_to_point_distance(mesh, h, points);
    }
    if (q.topology.nonmanifold_edges == 0 && q.topology.nonmanifold_vertices == 0)
        q.self_intersections = self_intersecting_faces(mesh).size();
    q.caps = count_caps(mesh);
    q.sharp_loops = count_sharp_loops(mesh);
    // Vertices of each tile in the mesh, and how many of them on its border. A line tile joined to
    // its neighbours (a sphere sampled as latitude rings: every tile a stretch of one ring) is inside
    // the surface; one of a ribbon, or left out, is not.
    std::unordered_map<int, std::pair<std::size_t, std::size_t>> tile_vertices; // tile -> (all, on the border)
    OpenMesh::VPropHandleT<int> cluster;
    if (mesh.get_property_handle(cluster, kVertexCluster))
        for (const auto v : mesh.vertices()) {
            auto& [all, border] = tile_vertices[mesh.property(cluster, v)];
            ++all;
            border += mesh.is_boundary(v) ? 1 : 0;
        }
    for (const std::int32_t id : cut) {
        const Node& node = h.nodes[static_cast<std::size_t>(id)];
        q.points += node.end - node.begin;
        const auto found = tile_vertices.find(id);
        // A tile without a vertex can be one the surface passes over (a stretch of scan line between
        // its neighbours' faces): not counted.
        const bool apart = found != tile_vertices.end() && 4 * found->second.second >= 3 * found->second.first;
        if (apart && is_line_tile(h, node))
            q.line_points += node.end - node.begin;
    }
    return q;
}

} // namespace mrt
