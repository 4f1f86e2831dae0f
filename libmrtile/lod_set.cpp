// Streamed LOD sets over the persistent hierarchy (the paper's "model hierarchies by triangulating
// various levels", §1 and Fig. 11-13), organised for 3D Tiles REPLACE refinement. See lod_set.h for
// the scheme; the reasons for its parts:
//  - one global mesh per level: tiles cut from it share border vertices bit for bit, so tiles of one
//    level never crack against each other;
//  - regions are hierarchy nodes: a region's points are a contiguous range, so "faces of cut nodes in
//    this region" is a range test, and children regions partition their parent exactly;
//  - skirts: a neighbour shown at another level has a slightly different border; a strip hanging
//    along the surface normal from the region's border hides the crack (the standard terrain remedy).
//    It hangs as deep as the coarser levels a viewer can show across that border lie off the surface
//    there: REPLACE refinement puts tiles of any two levels side by side, and a skirt sized by its own
//    level alone left a clean terrain's finest tiles centimetres of skirt beside a neighbour three
//    levels coarser and metres off (QA round 68, slivers of sky in CesiumJS and three.js);
//  - overlaps: each level gives a face across a region border to one side, not always the same one,
//    so a tile also holds its neighbours' faces around its own vertices, and the strip that two levels
//    gave to opposite sides is covered (QA round 68).
#include "libmrtile/lod_set.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/coverage_gap.h"
#include "libmrtile/errors.h"
#include "libmrtile/face_sequence.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/node_face_index.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iterator>
#include <limits>
#include <mutex>

namespace mrt {
namespace {

constexpr std::int32_t kNoNode = -1;
constexpr std::int32_t kMixed = -2;

struct LevelIndex
{
    // Cut node owning each face of the level mesh.
    std::vector<std::int32_t> face_owner;
    // Faces owned by each hierarchy node's subtree at this level (0 for nodes not above/at the cut).
    std::vector<std::size_t> faces_below;
    // The cut node of each vertex of the level mesh (kVertexCluster; -1 or past the nodes for none).
    std::vector<std::int32_t> vertex_cluster;
    // The corners of each face (three per face), and the faces around each vertex (those of vertex v
    // are vertex_faces[vertex_faces_begin[v] .. vertex_faces_begin[v + 1]), in face order): read once
    // from the half-edges, whose random accesses made most of the overlaps' cost.
    std::vector<std::uint32_t> face_corners;
    std::vector<std::uint32_t> vertex_faces_begin, vertex_faces;
    // The one cut node each vertex touches (its cluster, its faces' owners), kMixed for more than one,
    // kNoNode for none.
    std::vector<std::int32_t> vertex_node;
    // Vertices with a cluster that touch more than one node, ordered by the cluster's first point (then
    // by vertex), as faces_by_owner.
    std::vector<std::uint32_t> vertices_by_cluster;
    // True for nodes of the cut and their ancestors (regions may not go below the cut).
    std::vector<char> at_or_above_cut;
    // The largest node_error of the cut nodes in each node's subtree (0 for nodes below the cut): a
    // tile's own geometric error.
    std::vector<double> error_below;
    // Faces with an owner, ordered by the owner's first point (then by face): the faces of the cut
    // nodes inside a region [begin, end) are among one contiguous run of it, so extracting a region
    // does not scan the whole level.
    std::vector<std::uint32_t> faces_by_owner;
};

// A level's errors, boxes and skirts count only the nodes its mesh shows (nodes_in_mesh, reconstruct.h):
// a few stray points far from a scan are a cluster of their own, whose plane distance set the level's
// error, its tiles' boxes and the skirts' depth (QA round 57: a unit sphere with five strays within 50
// got skirts 16 deep and a geometric error of 8.4 on every coarse tile).

// The largest point-to-tile-plane distance over the cut's tiles that the mesh shows (nodes_in_mesh).
double level_max_plane_distance(const Hierarchy& h, const Cut& cut, const std::vector<char>& shown)
{
    double m = 0.0;
    for (std::int32_t id : cut)
        if (shown[static_cast<std::size_t>(id)])
            m = std::max(m, h.nodes[static_cast<std::size_t>(id)].max_plane_distance);
    return m;
}

// The level's geometric error: the largest node_error of its tiles that the mesh shows.
double level_node_error(const Hierarchy& h, const Cut& cut, const std::vector<char>& shown)
{
    double m = 0.0;
    for (std::int32_t id : cut)
        if (shown[static_cast<std::size_t>(id)])
            m = std::max(m, node_error(h.nodes[static_cast<std::size_t>(id)]));
    return m;
}

// The scale-free tolerance a cut satisfies: its largest tile RMS plane distance, or coverage gap where
// that exceeds the tile's largest plane distance, / largest side (cut_by_tolerance refines by both).
double cut_tolerance(const Hierarchy& h, const Cut& cut)
{
    const double side = h.scale;
    double m = 0.0;
    for (std::int32_t id : cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        m = std::max({m, n.rms_plane_distance, gap_dominates(n) ? n.coverage_gap : 0.0});
    }
    return side > 0 ? m / side : 0.0;
}

// How far a level mesh's vertices lie from the nearest sample point beyond kSampleReach point
// spacings, the largest by the cut node each vertex stands for (its cluster id; 0 for other nodes).
// Node errors measure the points against their tiles' planes, not the mesh against the points: where
// a coarse cut's fitted vertices stand off the sample (QA round 57: a corridor's 12-face level 0, its
// vertices up to 2.87 m from the walls, whose node errors gave 1.0 m), a tile's geometric error takes
// this instead, so that a client does not show it from where its error is plain. A lower bound of the
// mesh's deviation (a face spanning a concave corner between vertices on the sample is not seen), found
// in a search through the hierarchy.
// A vertex on the sampled surface but between samples (a fan centre, a split point) is up to about a
// point spacing from the nearest, so only what lies beyond kSampleReach spacings (the node's,
// node_spacing) counts: a box's exactly planar tiles keep error 0 and end their branch.
constexpr double kSampleReach = 2.0;

std::vector<double> vertex_deviation(const Hierarchy& h, const Mesh& mesh, std::size_t threads)
{
    std::vector<double> deviation(h.nodes.size(), 0.0);
    OpenMesh::VPropHandleT<int> cluster;
    if (!mesh.get_property_handle(cluster, kVertexCluster))
        throw InvalidInput("lods: level mesh lacks the cluster property");
    std::vector<Vec3> queries;
    std::vector<std::int32_t> owner;
    std::vector<double> reach; // squared: a vertex with a sample point this near has no deviation
    queries.reserve(mesh.n_vertices());
    owner.reserve(mesh.n_vertices());
    reach.reserve(mesh.n_vertices());
    for (const auto v : mesh.vertices()) {
        const int node = mesh.property(cluster, v);
        if (node < 0 || static_cast<std::size_t>(node) >= h.nodes.size())
            continue;
        const auto& p = mesh.point(v);
        queries.push_back({p[0], p[1], p[2]});
        owner.push_back(node);
        const double r = kSampleReach * node_spacing(h.nodes[static_cast<std::size_t>(node)]);
        reach.push_back(r * r);
    }
    // A search ends at the first point within reach, as nearly every vertex has one (the 1M torus's
    // tile tree: 1.16 s CPU with the full nearest-point searches, 1.01 s so, 0.60 s without either),
    // and starts at the vertex's own node, where that point mostly is (0.35 -> 0.13 s for its levels).
    const std::vector<double> squared = squared_nearest_point_distances(h, h.cloud.positions, queries, threads, &reach, &owner);
    for (std::size_t k = 0; k < squared.size(); ++k) {
        const auto node = static_cast<std::size_t>(owner[k]);
        deviation[node] = std::max(deviation[node], std::sqrt(squared[k]) - std::sqrt(reach[k]));
    }
    return deviation;
}

// Node errors measure every point of a cut node against its tile plane, strays the surface leaves out
// too: birds 5-50 m over a terrain gave its levels 0-2 errors of 50, 47 and 15 m where their meshes lie
// within a metre of the ground (QA round 63, L4), so a client refined them from kilometres away. A
// level's error is what a client sees change when it refines to the finest level, and a point that
// the finest mesh does not show (farther from it than kShownReach spacings of the level's cut node)
// shows that change only as far as the finest surface near it stands off the tile plane: at least its
// plane distance less its distance to the finest mesh (a real pole or wall that the finest level shows
// keeps its full height). Only the tail of a
// node's plane distances is looked at (beyond kHeavyTail of its RMS: a few points far out, where a
// clean sample's curvature and noise give at most about 4), so a clean sample costs a scan of its
// heavy-tailed nodes' points and keeps its errors bit for bit (their tails lie on the finest mesh).
constexpr double kHeavyTail = 4.0;
constexpr double kShownReach = 2.0;

// Values for some cut nodes of a level, sorted by node (the nodes a rule below changed; the others
// keep the node's own value), and the value of one of them.
using NodeValues = std::vector<std::pair<std::int32_t, double>>;

// Where `values` holds node `id`, or end().
NodeValues::const_iterator find_node(const NodeValues& values, std::int32_t id)
{
    const auto it = std::lower_bound(values.begin(), values.end(), std::pair<std::int32_t, double>{id, -1.0});
    return it != values.end() && it->first == id ? it : values.end();
}

double value_or(const NodeValues& values, std::int32_t id, double otherwise)
{
    const auto it = find_node(values, id);
    return it != values.end() ? it->second : otherwise;
}

double plane_distance(const Hierarchy& h, const Node& n, std::uint32_t point)
{
    return std::abs(dot(h.cloud.positions[point] - n.centre(), n.frame.vectors[0]));
}

bool heavy_tailed(const Node& n) { return n.max_plane_distance > kHeavyTail * n.rms_plane_distance; }

// Per level: the largest plane distance that the points of a cut node show, for the nodes where a
// point the finest level does not show changed it (others keep max_plane_distance); for every level
// but the finest (whose tiles have error 0). `shown[k]`: nodes_in_mesh of level k.
std::vector<NodeValues> shown_plane_distances(const Hierarchy& h, const std::vector<LodLevel>& levels,
                                                       const std::vector<std::vector<char>>& shown, const NodeFaceIndex& finest,
                                                       std::size_t threads)
{
    std::vector<NodeValues> out(levels.size());
    const std::size_t last = levels.size() - 1;
    if (last == 0 || levels[last].mesh.n_faces() == 0)
        return out;
    for (std::size_t k = 0; k < last; ++k) {
        std::vector<std::int32_t> tailed; // the level's shown heavy-tailed cut nodes
        for (const std::int32_t id : levels[k].cut)
            if (shown[k][static_cast<std::size_t>(id)] && heavy_tailed(h.nodes[static_cast<std::size_t>(id)]))
                tailed.push_back(id);
        std::vector<double> largest(tailed.size(), 0.0);
        std::vector<char> unshown(tailed.size(), 0);
        run_parallel(tailed.size(), threads, [&](std::size_t t) {
            const Node& n = h.nodes[static_cast<std::size_t>(tailed[t])];
            const double reach = kShownReach * node_spacing(n);
            for (std::uint32_t i = n.begin; i < n.end; ++i) {
                double d = plane_distance(h, n, i);
                if (d > kHeavyTail * n.rms_plane_distance) {
                    const Vec3& p = h.cloud.positions[i];
                    const double off = finest.closest(p).distance;
                    if (off > reach) {
                        d = std::max(0.0, d - off);
                        unshown[t] = 1;
                    }
                }
                largest[t] = std::max(largest[t], d);
            }
        });
        for (std::size_t t = 0; t < tailed.size(); ++t)
            if (unshown[t])
                out[k].push_back({tailed[t], largest[t]});
        std::sort(out[k].begin(), out[k].end());
    }
    return out;
}

// Coverage gaps carry stray points far off too: a node whose children lie apart has the space between
// them as its own gap (children_separation), and every ancestor has the largest of its subtree's, so
// one bird split off from the ground under it gave every coarse node of a terrain a gap of 45 m (QA
// round 63, L4). Per node: its gap with the separations from a child whose subtree the finest level
// does not show at all left out. A node's own gap is known only where it exceeds its children's (the
// gaps are stored as maxima); where it does not and nothing below was left out, the node keeps its
// stored gap, so a sample without such strays keeps every gap bit for bit.
// `shown_below` is set to one flag per node: whether the finest level shows a tile of its points.
std::vector<double> shown_coverage_gaps(const Hierarchy& h, const LodLevel& finest, const std::vector<char>& finest_shown,
                                        std::vector<char>& shown_below)
{
    const std::size_t count = h.nodes.size();
    std::vector<char> in_cut(count, 0), at_or_below_cut(count, 0);
    shown_below.assign(count, 0);
    for (const std::int32_t id : finest.cut)
        in_cut[static_cast<std::size_t>(id)] = 1;
    for (std::size_t k = 0; k < count; ++k) { // parents come first
        const std::int32_t parent = h.nodes[k].parent;
        if (in_cut[k]) {
            at_or_below_cut[k] = 1;
            shown_below[k] = finest_shown[k];
        } else if (parent >= 0 && at_or_below_cut[static_cast<std::size_t>(parent)]) {
            at_or_below_cut[k] = 1;
            shown_below[k] = shown_below[static_cast<std::size_t>(parent)];
        }
    }
    std::vector<double> gap(count, 0.0);
    for (std::size_t k = count; k-- > 0;) { // children come after their parents
        const Node& n = h.nodes[k];
        if (n.is_leaf()) {
            gap[k] = n.coverage_gap;
            continue;
        }
        const auto l = static_cast<std::size_t>(n.left), r = static_cast<std::size_t>(n.right);
        if (!at_or_below_cut[k])
            shown_below[k] = shown_below[l] || shown_below[r];
        const double stored_below = std::max(h.nodes[l].coverage_gap, h.nodes[r].coverage_gap);
        const double below = std::max(gap[l], gap[r]);
        if (n.coverage_gap > stored_below) { // its own gap, known exactly
            const bool to_strays = !(shown_below[l] && shown_below[r]) && children_separation(h, n) == n.coverage_gap;
            gap[k] = to_strays ? below : n.coverage_gap;
        } else {
            gap[k] = below == stored_below ? n.coverage_gap : below;
        }
    }
    return gap;
}

// A cut node the finest level does not show counts as strays only when it holds fewer points than this
// (the build's smallest cluster, BuildOptions::min_cluster): a few birds a coarse level meshes. A larger
// one is surface the finest level left out (the scan-line pieces of a patchy finest level, QA round 65),
// whose vertices would be measured across the hole to the nearest piece shown.
constexpr std::uint32_t kStrayCluster = 16;

// Per level, sorted by node: the cut nodes whose error strays far off had set (their plane distance or
// coverage gap), with the error their shown points give (plane distance, gap), and the cut nodes
// shown at the level whose points the finest level does not show (a cluster of strays that a coarse
// level meshes: a 4-point tile of birds 24 m over the ground, QA round 63's L3), with node_error. Other
// nodes keep node_error. `off_finest` is set to how far the level's vertices that stand for either kind
// lie off the finest surface (NodeFaceIndex::off_surface), by node (as vertex_deviation, which it adds
// to): an error does not claim less than the level shows where the finest does not.
std::vector<NodeValues> adjusted_node_errors(const Hierarchy& h, const std::vector<LodLevel>& levels,
                                             const std::vector<std::vector<char>>& shown,
                                             const std::vector<NodeValues>& shown_plane,
                                             const std::vector<double>& gaps, const std::vector<char>& shown_below,
                                             const NodeFaceIndex& finest, std::size_t threads, std::vector<NodeValues>& off_finest)
{
    std::vector<NodeValues> out(levels.size());
    off_finest.assign(levels.size(), {});
    const std::size_t last = levels.size() - 1;
    for (std::size_t k = 0; k < last; ++k)
        for (const std::int32_t id : levels[k].cut) {
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            if (!shown[k][static_cast<std::size_t>(id)])
                continue;
            const double error = std::max(value_or(shown_plane[k], id, n.max_plane_distance), gaps[static_cast<std::size_t>(id)]);
            if (error < node_error(n) || (!shown_below[static_cast<std::size_t>(id)] && n.count() < kStrayCluster))
                out[k].push_back({id, std::min(error, node_error(n))});
        }
    // The vertices standing for those nodes, all levels at once.
    std::vector<Vec3> queries;
    std::vector<std::pair<std::size_t, std::size_t>> asker; // {level, index into out[level]}
    for (std::size_t k = 0; k < last; ++k) {
        std::sort(out[k].begin(), out[k].end());
        if (out[k].empty())
            continue;
        OpenMesh::VPropHandleT<int> cluster;
        if (!levels[k].mesh.get_property_handle(cluster, kVertexCluster))
            throw InvalidInput("lods: level mesh lacks the cluster property");
        for (const auto v : levels[k].mesh.vertices()) {
            const auto it = find_node(out[k], levels[k].mesh.property(cluster, v));
            if (it == out[k].end())
                continue;
            const auto& p = levels[k].mesh.point(v);
            queries.push_back({p[0], p[1], p[2]});
            asker.push_back({k, static_cast<std::size_t>(it - out[k].begin())});
        }
    }
    if (queries.empty())
        return out;
    for (std::size_t k = 0; k < last; ++k)
        for (const auto& [id, error] : out[k])
            off_finest[k].push_back({id, 0.0});
    // Off the finest surface, not across a hole of it: where the finest level is patchy (scan lines 5 m
    // apart, whose finest tiles cover strips), a coarse vertex between its strips is no farther off the
    // surface for being metres from the nearest strip (QA round 65: a terrain's root 2.3 -> 26 m).
    std::vector<double> off_surface(queries.size());
    run_parallel(queries.size(), threads, [&](std::size_t q) { off_surface[q] = finest.off_surface(queries[q]); });
    for (std::size_t q = 0; q < queries.size(); ++q) {
        double& off = off_finest[asker[q].first][asker[q].second].second;
        off = std::max(off, off_surface[q]);
    }
    return out;
}

bool inside(const Node& region, const Node& node) { return region.begin <= node.begin && node.end <= region.end; }

// Node `id` of h, or nullptr for none (-1, or past the nodes: face and vertex ids of a level mesh).
const Node* node_of(const Hierarchy& h, std::int32_t id)
{
    return id >= 0 && static_cast<std::size_t>(id) < h.nodes.size() ? &h.nodes[static_cast<std::size_t>(id)] : nullptr;
}

// `deviation`: vertex_deviation of the level, or empty (the finest level, whose tiles have error 0).
// `shown`: nodes_in_mesh of the level; `adjusted`: its adjusted_node_errors.
LevelIndex index_level(const Hierarchy& h, const LodLevel& level, const std::vector<double>& deviation,
                       const std::vector<char>& shown, const NodeValues& adjusted)
{
    LevelIndex index;
    const Mesh& mesh = level.mesh;
    index.faces_below.assign(h.nodes.size(), 0);
    index.at_or_above_cut.assign(h.nodes.size(), 0);
    // Map node → the cut node containing it is not needed: owners come from the face/vertex ids,
    // which name tile nodes of this cut.
    OpenMesh::FPropHandleT<int> tile;
    OpenMesh::VPropHandleT<int> cluster;
    if (!mesh.get_property_handle(tile, kFaceTile) || !mesh.get_property_handle(cluster, kVertexCluster))
        throw InvalidInput("lods: level mesh lacks the tile/cluster properties");
    index.face_owner.assign(mesh.n_faces(), -1);
    for (const auto f : mesh.faces()) {
        const int owner = face_owner(mesh, tile, cluster, f);
        index.face_owner[static_cast<std::size_t>(f.idx())] = owner;
        if (node_of(h, owner))
            ++index.faces_below[static_cast<std::size_t>(owner)];
    }
    // Sorted as (first point, face) keys in one integer each: the order of a stable sort by first point
    // of the faces in face order, at a third of its cost (no comparator looking up two nodes).
    std::vector<std::uint64_t> keys;
    keys.reserve(index.face_owner.size());
    for (std::size_t f = 0; f < index.face_owner.size(); ++f)
        if (const Node* owner = node_of(h, index.face_owner[f]))
            keys.push_back(std::uint64_t{owner->begin} << 32 | f);
    std::sort(keys.begin(), keys.end());
    index.faces_by_owner.reserve(keys.size());
    for (const std::uint64_t key : keys)
        index.faces_by_owner.push_back(static_cast<std::uint32_t>(key & 0xffffffffu));
    index.error_below.assign(h.nodes.size(), 0.0);
    for (std::int32_t id : level.cut) {
        index.at_or_above_cut[static_cast<std::size_t>(id)] = 1;
        if (shown[static_cast<std::size_t>(id)])
            index.error_below[static_cast<std::size_t>(id)] =
                std::max(value_or(adjusted, id, node_error(h.nodes[static_cast<std::size_t>(id)])),
                         deviation.empty() ? 0.0 : deviation[static_cast<std::size_t>(id)]);
    }
    // For the overlaps (extract_region, overlap_faces): the cut node of each vertex, the adjacency, and
    // which vertices touch more than one cut node.
    index.vertex_cluster.assign(mesh.n_vertices(), -1);
    for (const auto v : mesh.vertices())
        index.vertex_cluster[static_cast<std::size_t>(v.idx())] = mesh.property(cluster, v);
    // A vertex that touches one cut node alone (its cluster and its faces' owners: a fan's centre) adds
    // no overlap to any region, and is passed over here and in extract_region. Level meshes hold no
    // deleted elements (meshed, or loaded from a model file), so indices run over all of them.
    assert(mesh.n_faces() == static_cast<std::size_t>(std::distance(mesh.faces().begin(), mesh.faces().end())));
    index.face_corners.assign(3 * mesh.n_faces(), 0);
    index.vertex_faces_begin.assign(mesh.n_vertices() + 1, 0);
    for (const auto f : mesh.faces()) {
        std::size_t k = 3 * static_cast<std::size_t>(f.idx());
        for (const auto v : mesh.fv_range(f)) {
            index.face_corners[k++] = static_cast<std::uint32_t>(v.idx());
            ++index.vertex_faces_begin[static_cast<std::size_t>(v.idx()) + 1];
        }
    }
    for (std::size_t v = 0; v < mesh.n_vertices(); ++v)
        index.vertex_faces_begin[v + 1] += index.vertex_faces_begin[v];
    index.vertex_faces.resize(index.vertex_faces_begin.back());
    {
        std::vector<std::uint32_t> next(index.vertex_faces_begin.begin(), index.vertex_faces_begin.end() - 1);
        for (std::size_t f = 0; f < mesh.n_faces(); ++f)
            for (std::size_t k = 0; k < 3; ++k)
                index.vertex_faces[next[index.face_corners[3 * f + k]]++] = static_cast<std::uint32_t>(f);
    }
    const auto corners_of = [&](std::size_t f) { return &index.face_corners[3 * f]; };
    index.vertex_node.assign(mesh.n_vertices(), kNoNode);
    const auto touched_by = [&](std::size_t v, std::int32_t id) {
        std::int32_t& one = index.vertex_node[v];
        if (node_of(h, id))
            one = one == kNoNode || one == id ? id : kMixed;
    };
    for (std::size_t v = 0; v < index.vertex_cluster.size(); ++v)
        touched_by(v, index.vertex_cluster[v]);
    for (std::size_t f = 0; f < mesh.n_faces(); ++f)
        for (std::size_t k = 0; k < 3; ++k)
            touched_by(corners_of(f)[k], index.face_owner[f]);
    keys.clear();
    for (std::size_t v = 0; v < index.vertex_cluster.size(); ++v)
        if (const Node* c = node_of(h, index.vertex_cluster[v]); c && index.vertex_node[v] == kMixed)
            keys.push_back(std::uint64_t{c->begin} << 32 | v);
    std::sort(keys.begin(), keys.end());
    index.vertices_by_cluster.reserve(keys.size());
    for (const std::uint64_t key : keys)
        index.vertices_by_cluster.push_back(static_cast<std::uint32_t>(key & 0xffffffffu));
    // Children come after parents: accumulate upwards.
    for (std::size_t k = h.nodes.size(); k-- > 1;) {
        const auto parent = static_cast<std::size_t>(h.nodes[k].parent);
        index.faces_below[parent] += index.faces_below[k];
        index.error_below[parent] = std::max(index.error_below[parent], index.error_below[k]);
        if (index.at_or_above_cut[k])
            index.at_or_above_cut[parent] = 1;
    }
    return index;
}

// Whether face f of the level is owned by a cut node inside `region`: the tile's own face.
bool owned_inside(const Hierarchy& h, const LevelIndex& index, const Node& region, std::uint32_t f)
{
    const Node* owner = node_of(h, index.face_owner[f]);
    return owner && inside(region, *owner);
}

// The faces of the level owned by cut nodes inside `region`, in face order: an owner inside the region
// starts in it, so they are among the run of faces_by_owner whose owners start in [region.begin,
// region.end), and extracting a region does not scan the whole level.
std::vector<std::uint32_t> owned_faces(const Hierarchy& h, const LevelIndex& index, const Node& region, bool in_face_order = true)
{
    auto owner_begin = [&](std::uint32_t f) { return h.nodes[static_cast<std::size_t>(index.face_owner[f])].begin; };
    const auto run_begin = std::partition_point(index.faces_by_owner.begin(), index.faces_by_owner.end(),
                                                [&](std::uint32_t f) { return owner_begin(f) < region.begin; });
    const auto run_end = std::partition_point(run_begin, index.faces_by_owner.end(),
                                              [&](std::uint32_t f) { return owner_begin(f) < region.end; });
    std::vector<std::uint32_t> faces;
    for (auto it = run_begin; it != run_end; ++it)
        if (inside(region, h.nodes[static_cast<std::size_t>(index.face_owner[*it])]))
            faces.push_back(*it);
    if (in_face_order)
        std::sort(faces.begin(), faces.end());
    return faces;
}

// The faces a region's tile overlaps its neighbours by (see extract_region), in face order, and how
// many skirt faces they can add: two for a face with one corner that touches the region (its edge
// away from the region can be a border), none for a face with more (its edges all meet a touching
// vertex, whose faces are all the tile's). The edges of the owned faces all meet a vertex of an owned
// face, so they carry no skirt. What the tile tree's budget counts, and what extract_region adds.
struct Overlap
{
    std::vector<std::uint32_t> faces;
    std::size_t skirt_faces = 0;
};

Overlap region_overlap(const Hierarchy& h, const LevelIndex& index, const Node& region, const std::vector<std::uint32_t>& owned)
{
    // The vertices that touch the region and another cut node: of a face owned inside, or of a cut node
    // inside (vertices_by_cluster holds only those that touch more than one).
    std::vector<std::uint32_t> touching;
    for (const std::uint32_t f : owned)
        for (std::size_t k = 0; k < 3; ++k)
            if (const std::uint32_t v = index.face_corners[3 * std::size_t{f} + k]; index.vertex_node[v] == kMixed)
                touching.push_back(v);
    auto cluster_begin = [&](std::uint32_t v) { return h.nodes[static_cast<std::size_t>(index.vertex_cluster[v])].begin; };
    const auto v_begin = std::partition_point(index.vertices_by_cluster.begin(), index.vertices_by_cluster.end(),
                                              [&](std::uint32_t v) { return cluster_begin(v) < region.begin; });
    const auto v_end = std::partition_point(v_begin, index.vertices_by_cluster.end(),
                                            [&](std::uint32_t v) { return cluster_begin(v) < region.end; });
    for (auto it = v_begin; it != v_end; ++it)
        if (inside(region, h.nodes[static_cast<std::size_t>(index.vertex_cluster[*it])]))
            touching.push_back(*it);
    std::sort(touching.begin(), touching.end());
    touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
    Overlap overlap;
    for (const std::uint32_t v : touching)
        for (std::uint32_t k = index.vertex_faces_begin[v]; k < index.vertex_faces_begin[v + 1]; ++k)
            if (!owned_inside(h, index, region, index.vertex_faces[k]))
                overlap.faces.push_back(index.vertex_faces[k]);
    std::sort(overlap.faces.begin(), overlap.faces.end());
    overlap.faces.erase(std::unique(overlap.faces.begin(), overlap.faces.end()), overlap.faces.end());
    for (const std::uint32_t f : overlap.faces) {
        int corners = 0;
        for (std::size_t k = 0; k < 3; ++k)
            corners += std::binary_search(touching.begin(), touching.end(), index.face_corners[3 * std::size_t{f} + k]) ? 1 : 0;
        overlap.skirt_faces += corners == 1 ? 2 : 0;
    }
    return overlap;
}

// The content of a tile: the level's faces owned by cut nodes inside the region and, with skirts, the
// faces around those cut nodes' vertices (the overlap), with a skirt along every border edge of them
// that is not a border of the whole level mesh, as deep as skirt_depth(the cut node
// owning the face across; -1 for none) says (a vertex between two skirt edges takes the deeper; an
// edge of depth 0 gets none: its faces would have no area). `known_overlap`: the overlap as the tile
// tree's search found it (region_overlap), or empty to find it here. Written into `out` (empty), which
// is the tile's own mesh: an OpenMesh mesh returned and assigned would be copied (it cannot be moved).
// The faces are added through a FaceSequence (what add_face builds, at a tenth of its cost), each new
// vertex recorded as the level vertex it copies, and the mesh is filled in once at the end.
void extract_region(const Hierarchy& h, const LodLevel& level, const LevelIndex& index, const Node& region,
                    const std::function<double(std::int32_t)>& skirt_depth, bool skirts, Mesh& out, std::size_t* skirt_faces,
                    std::size_t* overlap_faces, std::vector<std::uint32_t>&& known_overlap)
{
    assert(out.n_vertices() == 0);
    const Mesh& src = level.mesh;
    std::vector<int> map(src.n_vertices(), -1);
    std::vector<std::uint32_t> faces = owned_faces(h, index, region);
    // The tile's vertices: the level vertex each copies, and how far it is lowered (a skirt's foot; 0
    // for the others).
    std::vector<int> source;
    std::vector<double> lowered_copy;
    FaceSequence sequence;
    sequence.reserve(faces.size(), faces.size() + faces.size() / 4);
    auto copy_vertex = [&](int level_vertex) {
        source.push_back(level_vertex);
        lowered_copy.push_back(0.0);
        return sequence.add_vertex();
    };
    const auto add_faces = [&](const std::vector<std::uint32_t>& which) {
        for (const std::uint32_t fi : which) {
            std::array<int, 3> vs;
            for (std::size_t k = 0; k < 3; ++k) {
                const std::uint32_t v = index.face_corners[3 * std::size_t{fi} + k];
                int& m = map[v];
                if (m < 0)
                    m = copy_vertex(static_cast<int>(v));
                vs[k] = m;
            }
            if (sequence.add_face(vs[0], vs[1], vs[2]) < 0) {
                // A subset of a manifold mesh is manifold except where two fans of the region touch at
                // one vertex only: give this face its own copies of its vertices (same positions, so
                // nothing moves on screen) rather than lose it.
                for (int& v : vs)
                    v = copy_vertex(source[static_cast<std::size_t>(v)]);
                const int added = sequence.add_face(vs[0], vs[1], vs[2]);
                assert(added >= 0);
                (void)added;
            }
        }
    };
    add_faces(faces);
    // With skirts, the faces owned outside around the vertices that touch the region (a vertex of a
    // cut node inside, or of a face owned inside) overlap the neighbours: which faces a level gives a
    // region differs from level to level along its border (a face across it is owned by one side),
    // and where a neighbour is shown at another level, the strip that both levels gave away was a hole
    // seen from above (QA round 68: 1-2% of a terrain between tiles three levels apart; 0.1% with the
    // faces around the cut nodes' vertices alone, at corners where three regions meet). Both levels'
    // faces across the border overlap it instead.
    std::vector<std::uint32_t> overlap;
    if (skirts) {
        overlap = known_overlap.empty() ? region_overlap(h, index, region, faces).faces : std::move(known_overlap);
        add_faces(overlap);
    }
    *overlap_faces = overlap.size();
    faces.insert(faces.end(), overlap.begin(), overlap.end());
    *skirt_faces = 0;
    auto selected = [&](Mesh::FaceHandle f) {
        const auto fi = static_cast<std::uint32_t>(f.idx());
        return owned_inside(h, index, region, fi) || std::binary_search(overlap.begin(), overlap.end(), fi);
    };
    if (skirts) {
        // Border edges of the region that are interior edges of the level mesh get a skirt quad.
        std::vector<int> lowered(src.n_vertices(), -1);
        auto lower = [&](Mesh::VertexHandle src_v, double depth) {
            int& l = lowered[static_cast<std::size_t>(src_v.idx())];
            if (l < 0)
                l = copy_vertex(src_v.idx());
            double& by = lowered_copy[static_cast<std::size_t>(l)];
            by = std::max(by, depth);
            return l;
        };
        // The half-edges of the selected faces in face order, each face's from its first corner: an
        // order that depends only on the faces and their corners, not on half-edge indices, so that a
        // level mesh loaded from a model file (model_file.h), whose half-edges are numbered afresh,
        // gives the same tile.
        std::vector<Mesh::HalfedgeHandle> inner;
        for (const std::uint32_t fi : faces)
            for (const auto he : src.fh_range(Mesh::FaceHandle(static_cast<int>(fi))))
                inner.push_back(he);
        for (const Mesh::HalfedgeHandle he : inner) {
            const auto f = src.face_handle(he);
            const auto g = src.opposite_face_handle(he);
            if (!f.is_valid() || !g.is_valid())
                continue; // a border of the surface itself: nothing shows through
            if (!selected(f) || selected(g))
                continue;
            const double depth = skirt_depth(index.face_owner[static_cast<std::size_t>(g.idx())]);
            if (!(depth > 0))
                continue;
            // he runs a → b inside the selected face f; the skirt quad runs b → a on top, consistently.
            const auto a = src.from_vertex_handle(he), b = src.to_vertex_handle(he);
            const int ta = map[static_cast<std::size_t>(a.idx())], tb = map[static_cast<std::size_t>(b.idx())];
            const int la = lower(a, depth), lb = lower(b, depth);
            if (sequence.add_face(tb, ta, la) >= 0)
                ++*skirt_faces;
            if (sequence.add_face(tb, la, lb) >= 0)
                ++*skirt_faces;
        }
    }
    sequence.apply(out);
    const bool colored = src.has_vertex_colors();
    if (colored)
        out.request_vertex_colors();
    for (std::size_t k = 0; k < source.size(); ++k) {
        const Mesh::VertexHandle from(source[k]), to(static_cast<int>(k));
        const OpenMesh::Vec3d n = src.normal(from);
        out.set_point(to, lowered_copy[k] > 0 ? OpenMesh::Vec3d(src.point(from) - n * lowered_copy[k]) : src.point(from));
        out.set_normal(to, n);
        if (colored)
            out.set_color(to, src.color(from));
    }
}

// The box of the mesh's vertices; empty (min above max) for a mesh without any.
BoundingBox mesh_box(const Mesh& m)
{
    BoundingBox box{Vec3{1, 1, 1} * std::numeric_limits<double>::infinity(), Vec3{1, 1, 1} * -std::numeric_limits<double>::infinity()};
    for (const auto v : m.vertices()) {
        const Vec3 p = to_vec3(m.point(v));
        box.min = min(box.min, p);
        box.max = max(box.max, p);
    }
    return box;
}

// Meshes a level's cut; the level keeps the cut meshed (small separate objects refined, MeshOptions).
// A level's pieces are mended by whole levels (mend_coarse_levels: tolerance cuts, so the levels nest),
// not by mesh_cut's refinement of the tiles on its loops or folds (MeshOptions::piece_rounds,
// crack_rounds, crossing_rounds) or over holes between tiles (hole_rounds), which could make a level
// finer in places than the next.
void mesh_level(const Hierarchy& h, LodLevel& level, const MeshOptions& options)
{
    MeshOptions level_options = options;
    level_options.piece_rounds = 0;
    level_options.crack_rounds = 0;
    level_options.crossing_rounds = 0;
    level_options.hole_rounds = 0;
    MeshResult meshed = mesh_cut(h, level.cut, level_options);
    level.cut = std::move(meshed.cut);
    level.mesh = std::move(meshed.mesh);
    level.looks_airborne = meshed.surface.looks_airborne;
}

// Level 0 is the best cut whose mesh fits one tile: start from a guess of the triangles per tile and
// correct it from the measured mesh (meshing a coarse cut is cheap). `finest`: cut_by_tolerance(h, 0),
// the leaves or, for a noisy sample, the cut at its noise floor
// (Node::noise_floor), below which levels would only mesh noise; no level is finer.
// The finer levels are tolerance cuts, and a best-N cut is not one: where the sampling is uneven its
// tolerance (that of its worst tile) may hold for far fewer tiles elsewhere, and the first halving is
// then no finer than level 0 (a torus with one half ten times denser: 128 tiles at 0.0154, then 130 at
// 0.0077, and `lods` stopped at one level, since the error did not fall). So level 0 becomes the
// tolerance cut at the best-N cut's tolerance: every node of it lies at or above a node of the best-N
// cut (that node meets the tolerance), so it has at most as many tiles and the levels nest.
// Level 0's triangles (LodSetOptions::first_level_triangles, or else a tile's).
std::size_t level_zero_triangles(const LodSetOptions& o)
{
    return o.first_level_triangles > 0 ? o.first_level_triangles : o.max_tile_triangles;
}

// Level 0's faces at most: three quarters of its triangles (room for skirts in a tileset's root).
std::size_t first_level_budget(const LodSetOptions& o) { return level_zero_triangles(o) * 3 / 4; }

LodLevel first_level(const Hierarchy& h, const LodSetOptions& o, const Cut& finest)
{
    const std::size_t triangles = level_zero_triangles(o);
    const auto budget = static_cast<double>(first_level_budget(o));
    std::size_t tiles = std::max<std::size_t>(1, triangles / 32);
    LodLevel level;
    for (int attempt = 0; attempt < 6; ++attempt) {
        level.cut = tiles >= finest.size() ? finest : cut_by_budget(h, tiles);
        mesh_level(h, level, o.mesh);
        const auto faces = static_cast<double>(level.mesh.n_faces());
        if (faces <= budget || tiles == 1)
            break;
        tiles = std::max<std::size_t>(1, static_cast<std::size_t>(static_cast<double>(tiles) * 0.9 * budget / faces));
    }
    if (level.cut.size() >= finest.size()) {
        // The finest cut fits: it is the one level (its own tolerance cut is coarser where the finest
        // ends at the noise floor: a 40k-point wedge got a level 0 of 907 tiles and a finest of 946,
        // nearly the same mesh twice in its tileset, QA round 50).
        level.tolerance = 0.0;
        return level;
    }
    level.tolerance = cut_tolerance(h, level.cut);
    LodLevel nested;
    nested.cut = cut_by_tolerance(h, level.tolerance);
    if (nested.cut.size() >= level.cut.size())
        return level; // the same cut (or, below a noise floor, not coarser): keep it
    mesh_level(h, nested, o.mesh);
    nested.tolerance = cut_tolerance(h, nested.cut);
    return nested;
}

std::vector<double> finer_tolerances(const Hierarchy& h, const LodSetOptions& o, double first, std::size_t finest)
{
    std::vector<double> t;
    const std::size_t wanted = (o.levels > 0 ? o.levels : o.max_levels) - 1;
    double tol = first;
    while (t.size() < wanted) {
        // Explicit levels too, once one is asked for: past a tolerance whose cut is the finest, every
        // finer one gives that cut again and make_lod_levels skips it, so they end there. levels =
        // SIZE_MAX halved the tolerance to 0 and then pushed zeros until memory ran out.
        if ((o.levels == 0 || !t.empty()) && cut_by_tolerance(h, tol).size() >= finest)
            break;
        tol /= 2;
        t.push_back(tol);
    }
    if (o.levels == 0 && !t.empty() && t.size() == wanted)
        t.back() = 0.0; // end at the finest cut
    return t;
}

// Automatic levels halve the tolerance until the cut reaches the leaves; near the leaves a halving may
// add only a few tiles (a noisy 1M-point torus: 84,935 tiles, then its 84,940 leaves), and such a level
// costs a full mesh of the finest size for a viewer gain of nothing. Working back from the finest level
// (the leaves, always kept), a level after level 0 (`first_tiles` tiles, kept) is kept only when the next
// kept one has kMinLevelGrowth × its tiles and it has as much more than level 0.
constexpr double kMinLevelGrowth = 1.5;

// The rule for a level of `tiles` between level 0 (`first_tiles`) and the next level kept (`next_tiles`).
bool grows_enough(std::size_t tiles, std::size_t next_tiles, std::size_t first_tiles)
{
    return static_cast<double>(next_tiles) >= kMinLevelGrowth * static_cast<double>(tiles) &&
           static_cast<double>(tiles) >= kMinLevelGrowth * static_cast<double>(first_tiles);
}

void drop_small_steps(std::vector<LodLevel>& levels, std::size_t first_tiles)
{
    if (levels.size() < 2)
        return;
    std::vector<LodLevel> kept;
    kept.push_back(std::move(levels.back()));
    for (std::size_t i = levels.size() - 1; i-- > 0;)
        if (grows_enough(levels[i].cut.size(), kept.back().cut.size(), first_tiles))
            kept.push_back(std::move(levels[i]));
    std::reverse(kept.begin(), kept.end());
    levels = std::move(kept);
}

// drop_small_steps' rule again once coarse levels were mended finer (mend_coarse_levels,
// mend_stray_loops), where level 0 is meshed and levels are removed in place (a meshed level moved is
// copied): a level between level 0 and the finest goes when the next level kept has under
// kMinLevelGrowth × its tiles, or it has under kMinLevelGrowth × level 0's.
void drop_mended_small_steps(std::vector<LodLevel>& levels)
{
    if (levels.size() < 3)
        return;
    for (std::size_t k = levels.size() - 2; k >= 1; --k)
        if (!grows_enough(levels[k].cut.size(), levels[k + 1].cut.size(), levels.front().cut.size()))
            levels.erase(levels.begin() + static_cast<std::ptrdiff_t>(k));
}

// What both halves of a LOD set need: a hierarchy, and room in a tile for a mesh.
void check_lod_options(const Hierarchy& h, const LodSetOptions& o)
{
    if (o.max_tile_triangles < 64)
        throw InvalidInput("lods: max_tile_triangles must be at least 64");
    // Level 0 is the tileset's root tile (QA round 59: 2,000 gave a root of 1,363 faces against 1,000).
    if (o.tileset && o.first_level_triangles > o.max_tile_triangles)
        throw InvalidInput("lods: first_level_triangles (" + std::to_string(o.first_level_triangles) +
                           ") above max_tile_triangles (" + std::to_string(o.max_tile_triangles) +
                           "): level 0 is the tileset's root tile, which must fit one tile");
    if (o.levels == 0 && o.tolerances.empty() && o.max_levels == 0)
        throw InvalidInput("lods: max_levels must be at least 1");
    if (h.nodes.empty())
        throw InvalidInput("lods: empty hierarchy");
}

} // namespace

// A coarse level in more pieces or with more boundary loops than the finest one is seen through where
// a viewer shows it (the rocker arm's level 0, 94 tiles of a closed genus-1 part: 5 pieces, 469 open
// edges, its finer levels closed: thin parts' tiles at a coarse cut, see the README's known limits).
// Such a level is cut again at a finer tolerance, by steps of √2, up to kMendSteps times, while it
// stays coarser than the next level (tolerance cuts are monotone in the tolerance, so the levels
// still nest). Only automatic levels: tolerances the caller chose are kept.
constexpr int kMendSteps = 3;

bool worse_than(const TopologyStats& t, const TopologyStats& finest)
{
    return t.components > finest.components || t.boundary_loops > finest.boundary_loops;
}

void mend_coarse_levels(const Hierarchy& h, std::vector<LodLevel>& levels, const MeshOptions& mesh)
{
    if (levels.size() < 2)
        return;
    const TopologyStats finest = topology_stats(levels.back().mesh);
    for (std::size_t k = 0; k + 1 < levels.size(); ++k)
        for (int step = 0; step < kMendSteps && worse_than(topology_stats(levels[k].mesh), finest); ++step) {
            LodLevel finer;
            finer.tolerance = levels[k].tolerance / std::sqrt(2.0);
            finer.cut = cut_by_tolerance(h, finer.tolerance);
            if (finer.cut.size() >= levels[k + 1].cut.size())
                break;
            mesh_level(h, finer, mesh);
            levels[k].tolerance = finer.tolerance;
            levels[k].cut = std::move(finer.cut);
            levels[k].mesh = finer.mesh; // a coarse level: the copy is small (OpenMesh has no move)
        }
}

namespace {

// A coarse level can have a hole that the finest level has not, in another place than its own holes:
// where its tiles straddle a thin part (the bunny's ears, levels 0 and 1 of its automatic set: loops of
// 59-71 edges where every finer level is closed; QA round 72's renders). mend_coarse_levels counts
// loops, and a level with no more loops than the finest passes it. Here a loop of a level most of
// whose vertices lie farther than kStrayLoopEdges of the level's median edge lengths from every border
// vertex of the finest mesh is a hole between tiles (a sample's own border runs along its points, so a
// coarse level's loop around it lies on the finest level's: its vertices are hull points of border
// tiles). The level's cut nodes around such loops (their vertices' tiles and their faces') give way to
// the next level's nodes below them and the level is meshed again, kept when it has fewer such loops,
// no more loops or pieces, a genus no farther from the finest level's (a noisy sphere's hole had
// closed into a handle) and (level 0) still fits its budget, up to kMendSteps times. From the finest
// level up, so that a level can refine into the mended one below it. The levels still nest: each
// node of a level lies at or above nodes of the next. A level mended so is no tolerance cut any more.
constexpr double kStrayLoopEdges = 3.0;

// The boundary loops of `mesh` as vertex lists (in half-edge order, from the lowest half-edge).
std::vector<std::vector<Mesh::VertexHandle>> loop_vertices(const Mesh& mesh)
{
    std::vector<std::vector<Mesh::VertexHandle>> loops;
    std::vector<char> seen(mesh.n_halfedges(), 0);
    for (const auto start : mesh.halfedges()) {
        if (!mesh.is_boundary(start) || seen[static_cast<std::size_t>(start.idx())])
            continue;
        std::vector<Mesh::VertexHandle> loop;
        for (auto he = start; !seen[static_cast<std::size_t>(he.idx())]; he = mesh.next_halfedge_handle(he)) {
            seen[static_cast<std::size_t>(he.idx())] = 1;
            loop.push_back(mesh.to_vertex_handle(he));
        }
        loops.push_back(std::move(loop));
    }
    return loops;
}

double median_edge_length(const Mesh& mesh)
{
    std::vector<double> lengths;
    lengths.reserve(mesh.n_edges());
    for (const auto e : mesh.edges())
        lengths.push_back(mesh.calc_edge_length(e));
    if (lengths.empty())
        return 0.0;
    std::nth_element(lengths.begin(), lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2), lengths.end());
    return lengths[lengths.size() / 2];
}

// The loops of `mesh` away from the borders of the finest mesh (see above), as vertex lists.
std::vector<std::vector<Mesh::VertexHandle>> stray_loops(const Mesh& mesh, const std::vector<Vec3>& finest_border)
{
    std::vector<std::vector<Mesh::VertexHandle>> out;
    std::vector<std::vector<Mesh::VertexHandle>> loops = loop_vertices(mesh);
    if (loops.empty())
        return out;
    const double reach = kStrayLoopEdges * median_edge_length(mesh);
    if (!(reach > 0.0))
        return out;
    BoxGrid grid(reach);
    for (std::size_t i = 0; i < finest_border.size(); ++i)
        grid.insert(static_cast<std::uint32_t>(i), BoundingBox{finest_border[i], finest_border[i]});
    const Vec3 around{reach, reach, reach};
    for (std::vector<Mesh::VertexHandle>& loop : loops) {
        std::size_t far = 0;
        for (const Mesh::VertexHandle v : loop) {
            const Vec3 p = to_vec3(mesh.point(v));
            far += !grid.any_candidate(BoundingBox{p - around, p + around},
                                       [&](std::uint32_t i) { return distance(finest_border[i], p) <= reach; });
        }
        if (2 * far > loop.size())
            out.push_back(std::move(loop));
    }
    return out;
}

// Level k's cut with the nodes around `loops` (the tiles of their vertices, and of those vertices'
// neighbours with `wider`, and of the faces around them) replaced by the next level's nodes below
// them; empty when that replaces nothing.
Cut refined_around(const Hierarchy& h, const std::vector<LodLevel>& levels, std::size_t k,
                   const std::vector<std::vector<Mesh::VertexHandle>>& loops, bool wider)
{
    const Mesh& mesh = levels[k].mesh;
    OpenMesh::VPropHandleT<int> cluster;
    OpenMesh::FPropHandleT<int> tile;
    if (!mesh.get_property_handle(cluster, kVertexCluster) || !mesh.get_property_handle(tile, kFaceTile))
        return {};
    std::vector<char> around(h.nodes.size(), 0);
    const auto mark = [&](int id) {
        if (id >= 0 && static_cast<std::size_t>(id) < h.nodes.size())
            around[static_cast<std::size_t>(id)] = 1;
    };
    const auto mark_vertex = [&](Mesh::VertexHandle v) {
        mark(mesh.property(cluster, v));
        for (const auto f : mesh.vf_range(v))
            mark(mesh.property(tile, f));
    };
    for (const auto& loop : loops)
        for (const Mesh::VertexHandle v : loop) {
            mark_vertex(v);
            if (wider)
                for (const auto w : mesh.vv_range(v))
                    mark_vertex(w);
        }
    std::vector<char> in_cut(h.nodes.size(), 0);
    for (const std::int32_t id : levels[k].cut)
        in_cut[static_cast<std::size_t>(id)] = 1;
    std::vector<char> replaced(h.nodes.size(), 0);
    Cut cut;
    for (const std::int32_t id : levels[k + 1].cut) {
        std::int32_t above = id;
        while (above >= 0 && !in_cut[static_cast<std::size_t>(above)])
            above = h.nodes[static_cast<std::size_t>(above)].parent;
        if (above >= 0 && above != id && around[static_cast<std::size_t>(above)]) {
            cut.push_back(id);
            replaced[static_cast<std::size_t>(above)] = 1;
        }
    }
    if (cut.empty())
        return {};
    for (const std::int32_t id : levels[k].cut)
        if (!replaced[static_cast<std::size_t>(id)])
            cut.push_back(id);
    return cut;
}

void mend_stray_loops(const Hierarchy& h, std::vector<LodLevel>& levels, const LodSetOptions& o)
{
    if (levels.size() < 2)
        return;
    std::vector<Vec3> finest_border;
    const Mesh& finest = levels.back().mesh;
    for (const auto v : finest.vertices())
        if (finest.is_boundary(v))
            finest_border.push_back(to_vec3(finest.point(v)));
    const int finest_genus = topology_stats(finest).genus;
    const auto genus_off = [&](const TopologyStats& t) { return std::abs(t.genus - finest_genus); };
    for (std::size_t k = levels.size() - 1; k-- > 0;) {
        // The level's stray loops and topology, carried over from the mesh a step kept.
        std::vector<std::vector<Mesh::VertexHandle>> stray = stray_loops(levels[k].mesh, finest_border);
        TopologyStats before = topology_stats(levels[k].mesh);
        for (int step = 0; step < kMendSteps && !stray.empty(); ++step) {
            // The tiles on the loops first, then a ring wider (the bunny's ear at level 1 of a 2,000-
            // triangle set: the loops' own tiles refined split a piece off, a ring more closed it).
            bool mended = false;
            for (const bool wider : {false, true}) {
                LodLevel again;
                again.tolerance = levels[k].tolerance;
                again.cut = refined_around(h, levels, k, stray, wider);
                if (again.cut.empty() || again.cut.size() >= levels[k + 1].cut.size())
                    continue;
                mesh_level(h, again, o.mesh);
                const TopologyStats after = topology_stats(again.mesh);
                std::vector<std::vector<Mesh::VertexHandle>> still = stray_loops(again.mesh, finest_border);
                if (still.size() < stray.size() && after.boundary_loops <= before.boundary_loops &&
                    after.components <= before.components && after.genus >= 0 && genus_off(after) <= genus_off(before) &&
                    (k > 0 || again.mesh.n_faces() <= first_level_budget(o))) {
                    levels[k].cut = std::move(again.cut);
                    levels[k].mesh = again.mesh; // a coarse level: the copy is small (OpenMesh has no move); same handles
                    stray = std::move(still);
                    before = after;
                    mended = true;
                    break;
                }
            }
            if (!mended)
                break;
        }
    }
}

} // namespace

std::vector<LodLevel> make_lod_levels(const Hierarchy& h, const LodSetOptions& o)
{
    check_lod_options(h, o);
    // Levels are meshed in their final place: an OpenMesh mesh has no move constructor, so a meshed
    // level moved into a vector would be copied (1.2M faces over the levels of a 1M-point set). Only
    // unmeshed levels and the small first one are moved around.
    std::vector<LodLevel> levels;
    std::vector<double> tolerances = o.tolerances;
    for (std::size_t i = 0; i < tolerances.size(); ++i)
        if (!(tolerances[i] >= 0) || !std::isfinite(tolerances[i]) || (i > 0 && !(tolerances[i] < tolerances[i - 1])))
            throw InvalidInput("lods: tolerances must be finite, >= 0 and strictly decreasing (coarse to fine)");
    if (tolerances.empty()) {
        const Cut finest = cut_by_tolerance(h, 0.0);
        levels.push_back(first_level(h, o, finest));
        tolerances = finer_tolerances(h, o, levels.front().tolerance, finest.size());
    }
    std::size_t meshed = levels.size();
    // The finer levels are independent meshing jobs: cut them, mesh them on worker threads (largest
    // first), each in its place.
    std::vector<LodLevel> finer;
    for (double tol : tolerances) {
        LodLevel level;
        level.tolerance = tol;
        level.cut = cut_by_tolerance(h, tol);
        const std::size_t previous = finer.empty() ? (levels.empty() ? 0 : levels.back().cut.size()) : finer.back().cut.size();
        if (level.cut.size() > previous) // no finer than the previous level (e.g. below the build tolerance): skip
            finer.push_back(std::move(level));
    }
    if (o.tolerances.empty() && o.levels == 0) { // automatic levels: level 0 is first_level's
        const LodLevel& first = levels.front();
        drop_small_steps(finer, first.cut.size());
        // The finest alone left, with under kMinLevelGrowth × level 0's tiles: it is the one level
        // where it would fit level 0's budget (by level 0's faces per tile).
        if (finer.size() == 1 && static_cast<double>(finer.front().cut.size()) < kMinLevelGrowth * static_cast<double>(first.cut.size())) {
            const double faces_per_tile = static_cast<double>(first.mesh.n_faces()) / static_cast<double>(first.cut.size());
            if (faces_per_tile * static_cast<double>(finer.front().cut.size()) <= static_cast<double>(first_level_budget(o))) {
                levels.clear();
                meshed = 0;
            }
        }
    }
    levels.reserve(meshed + finer.size());
    for (LodLevel& level : finer)
        levels.push_back(std::move(level));
    finer.clear();
    const std::size_t total = levels.size();
    std::size_t done = meshed;
    std::mutex progress_lock;
    if (o.progress && done > 0)
        o.progress(done, total);
    run_parallel(total - meshed, o.threads, [&](std::size_t k) {
        LodLevel& level = levels[total - 1 - k]; // finest (largest) first
        mesh_level(h, level, o.mesh);
        if (o.progress) {
            const std::lock_guard<std::mutex> hold(progress_lock);
            o.progress(++done, total);
        }
    });
    if (o.tolerances.empty()) {
        mend_coarse_levels(h, levels, o.mesh);
        mend_stray_loops(h, levels, o);
        // Mending makes a level finer, up to just below the next one's tiles: the growth rule of
        // automatic levels holds again afterwards (QA round 77: a set of misregistered scans kept a
        // mended level of 3,099 tiles before the finest, of 3,132, the same mesh meshed twice).
        if (o.levels == 0)
            drop_mended_small_steps(levels);
    }
    // Two levels that mesh the same cut are one level shown twice (QA round 57: the bunny with three
    // stray points, whose small-object rounds made level 0's meshed cut the next level's, had two
    // byte-identical root tiles): the coarser copy goes.
    for (std::size_t k = 0; k + 1 < levels.size();) {
        Cut a = levels[k].cut, b = levels[k + 1].cut;
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        if (a == b)
            levels.erase(levels.begin() + static_cast<std::ptrdiff_t>(k));
        else
            ++k;
    }
    // Errors in order, coarse to fine (meshing may have refined a level's small separate objects,
    // MeshOptions::small_object_rounds, so they are taken from the cuts as meshed).
    double previous_error = std::numeric_limits<double>::infinity();
    for (LodLevel& level : levels) {
        const std::vector<char> shown = nodes_in_mesh(h, level.mesh);
        level.max_plane_distance = level_max_plane_distance(h, level.cut, shown);
        level.geometric_error = std::min(previous_error, level_node_error(h, level.cut, shown));
        previous_error = level.geometric_error;
    }
    if (!levels.empty())
        levels.back().geometric_error = 0.0;
    return levels;
}

LodSet make_lod_tiles(const Hierarchy& h, std::vector<LodLevel> levels, const LodSetOptions& o)
{
    check_lod_options(h, o);
    if (levels.empty())
        throw InvalidInput("lods: no levels");
    // The caller vouches that the levels are h's, but a cut naming no node of h was read out of bounds
    // (QA round 51); the check costs nothing next to the tiling.
    for (std::size_t k = 0; k < levels.size(); ++k)
        check_cut(h, levels[k].cut, "lods: level " + std::to_string(k));
    // Coarse to fine, as make_lod_levels gives them: levels in another order made a tile tree whose
    // children were coarser than their parents, each clamped to its parent's error (QA round 59).
    for (std::size_t k = 1; k < levels.size(); ++k)
        if (!(levels[k].tolerance < levels[k - 1].tolerance) || levels[k].geometric_error > levels[k - 1].geometric_error) {
            char what[200]; // %g: a tolerance of 1e-7 is no "0.000000"
            std::snprintf(what, sizeof what, " (tolerance %.6g, geometric error %.6g) is not finer than level %zu (%.6g, %.6g)",
                          levels[k].tolerance, levels[k].geometric_error, k - 1, levels[k - 1].tolerance, levels[k - 1].geometric_error);
            throw InvalidInput("lods: level " + std::to_string(k) + what + ": levels go coarse to fine, as make_lod_levels gives them");
        }
    LodSet set;
    set.levels = std::move(levels);

    // The levels' errors (and below, the tiles', error_below) are floored by how far each level's
    // vertices stand off the sample (vertex_deviation), coarser levels raised to the finer ones' floors
    // so that errors still fall level by level; the finest level's stay 0. With or without the tile
    // tree: `lods` writes the levels' errors too (until session 51 its lods.json kept the node errors).
    const std::size_t last = set.levels.size() - 1;
    std::vector<std::vector<char>> shown(set.levels.size());
    for (std::size_t k = 0; k < set.levels.size(); ++k)
        shown[k] = nodes_in_mesh(h, set.levels[k].mesh);
    // First the errors of the nodes as their shown points give them (shown_plane_distances), each level
    // at most the coarser one's as in make_lod_levels (equal to its errors where no stray far off sets
    // a node's); the skirts hang by the shown plane distances too.
    const NodeFaceIndex finest(h, set.levels.back().mesh);
    const std::vector<NodeValues> shown_plane = shown_plane_distances(h, set.levels, shown, finest, o.threads);
    std::vector<char> shown_below;
    const std::vector<double> gaps = shown_coverage_gaps(h, set.levels.back(), shown.back(), shown_below);
    std::vector<NodeValues> off_finest;
    const std::vector<NodeValues> adjusted = adjusted_node_errors(h, set.levels, shown, shown_plane, gaps, shown_below, finest, o.threads, off_finest);
    std::vector<double> skirt_depth(set.levels.size());
    double coarser = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < set.levels.size(); ++k) {
        double error = 0.0, plane = 0.0;
        for (const std::int32_t id : set.levels[k].cut) {
            if (!shown[k][static_cast<std::size_t>(id)])
                continue;
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            error = std::max(error, value_or(adjusted[k], id, node_error(n)));
            plane = std::max(plane, value_or(shown_plane[k], id, n.max_plane_distance));
        }
        skirt_depth[k] = 2.0 * plane;
        if (k < last)
            set.levels[k].geometric_error = std::min(coarser, error);
        coarser = set.levels[k].geometric_error;
    }
    std::vector<std::vector<double>> deviation(set.levels.size());
    for (std::size_t k = 0; k < last; ++k) {
        deviation[k] = vertex_deviation(h, set.levels[k].mesh, o.threads);
        for (const auto& [id, off] : off_finest[k])
            deviation[k][static_cast<std::size_t>(id)] = std::max(deviation[k][static_cast<std::size_t>(id)], off);
        const double farthest = deviation[k].empty() ? 0.0 : *std::max_element(deviation[k].begin(), deviation[k].end());
        set.levels[k].geometric_error = std::max(set.levels[k].geometric_error, farthest);
    }
    for (std::size_t k = last; k-- > 0;)
        set.levels[k].geometric_error = std::max(set.levels[k].geometric_error, set.levels[k + 1].geometric_error);
    if (!o.tileset)
        return set;
    std::vector<LevelIndex> index;
    for (std::size_t k = 0; k < set.levels.size(); ++k)
        index.push_back(index_level(h, set.levels[k], deviation[k], shown[k], adjusted[k]));
    // Regions are chosen within three quarters of the budget (room for the overlap and the skirts), and
    // with them within all of it: a small region's skirt can outgrow the quarter (QA round 28b: at 256,
    // a quarter of the bunny's tiles were over, up to 343 faces). The overlap is found for each region
    // that may fit (region_overlap, as extract_region adds it): per node for every node, it took the
    // index of a 1M-point torus's finest level 0.2 s, and a bound cheap enough overstated it (the
    // bunny at 256 in 2,182 tiles instead of 1,495).
    const std::size_t face_budget = o.max_tile_triangles * 3 / 4;

    // Breadth-first over (region, level).
    struct Pending
    {
        std::int32_t region;
        std::size_t level;
        std::ptrdiff_t parent;
        std::vector<std::uint32_t> overlap; // as the search found it (extract_region takes it), or empty
    };
    // queue[k] becomes set.tiles[k] (each entry makes a tile, in order).
    std::vector<Pending> queue;
    queue.push_back({0, 0, -1, {}});
    for (std::size_t q = 0; q < queue.size(); ++q) {
        const Pending p{queue[q].region, queue[q].level, queue[q].parent, {}}; // the overlap stays for extraction
        const Node& region = h.nodes[static_cast<std::size_t>(p.region)];
        LodTile tile;
        tile.region = p.region;
        tile.level = p.level;
        // The tile's own error: the largest of its cut nodes' (a smooth part of a level refines later
        // than a rough one), never above its level's; the finest level's are 0. Parents are raised to
        // their children's below, once the tree stands.
        tile.geometric_error = p.level == last ? 0.0
                                               : std::min(set.levels[p.level].geometric_error,
                                                          index[p.level].error_below[static_cast<std::size_t>(p.region)]);
        tile.box = region.box;
        const std::size_t id = set.tiles.size();
        if (p.parent >= 0)
            set.tiles[static_cast<std::size_t>(p.parent)].children.push_back(id);
        const bool exact = tile.geometric_error <= 0.0;
        set.tiles.push_back(std::move(tile));
        // A tile whose error is 0 ends its branch: clients refine by screen-space error, which is 0 for it
        // at any distance, so its children would never load (QA round 57: fandisk's flat faces at
        // --max-tile-triangles 128 had two such chains, 2,988 bytes nobody fetches).
        if (p.level == last || exact)
            continue;
        // Children: the largest regions below whose next-level content fits the budget; never below
        // that level's cut (a cut node's faces cannot be split between tiles).
        const LevelIndex& next = index[p.level + 1];
        std::vector<std::int32_t> stack{p.region};
        std::vector<Pending> children;
        while (!stack.empty()) {
            const std::int32_t id_q = stack.back();
            stack.pop_back();
            const Node& n = h.nodes[static_cast<std::size_t>(id_q)];
            const std::size_t faces = next.faces_below[static_cast<std::size_t>(id_q)];
            bool fits = faces <= face_budget;
            Overlap overlap;
            if (fits && o.skirts) { // the overlap and its skirts, counted only for a region that may fit
                overlap = region_overlap(h, next, n, owned_faces(h, next, n, false));
                fits = faces + overlap.faces.size() + overlap.skirt_faces <= o.max_tile_triangles;
            }
            const bool stop = n.is_leaf() || fits ||
                              !next.at_or_above_cut[static_cast<std::size_t>(n.left)] ||
                              !next.at_or_above_cut[static_cast<std::size_t>(n.right)];
            if (stop) {
                children.push_back({id_q, p.level + 1, static_cast<std::ptrdiff_t>(id), std::move(overlap.faces)});
            } else {
                stack.push_back(n.right);
                stack.push_back(n.left);
            }
        }
        for (Pending& c : children)
            queue.push_back(std::move(c));
    }
    // A parent's error is at least its children's: REPLACE refinement needs errors that fall down the
    // tree, and where a finer level's vertices stand farther off the sample than the coarser's in the
    // same region, lowering the child to its parent's error (as until QA round 62) understated what the
    // child shows (a sphere with a sparse cap: tiles of levels 1-3 at the root's 0.036, their vertices
    // up to 0.089 off). Raising the parent instead errs on the side of refining early. Children come
    // after their parents in `tiles`, so one backward pass carries a raise up the whole chain.
    for (std::size_t k = set.tiles.size(); k-- > 0;)
        for (const std::size_t c : set.tiles[k].children)
            set.tiles[k].geometric_error = std::max(set.tiles[k].geometric_error, set.tiles[c].geometric_error);
    std::vector<std::size_t> parent(set.tiles.size(), 0);
    for (std::size_t k = 0; k < set.tiles.size(); ++k)
        for (const std::size_t c : set.tiles[k].children)
            parent[c] = k;
    // Skirt depths. Across a border of tile B (level L), a viewer can show any tile that holds the cut
    // node owning the face across and is no ancestor of B: of each level from the first at which B's
    // ancestor no longer holds that node. The crack between B and such a tile is at most how far each
    // lies off the surface there, so B's skirt hangs twice the largest error of the cut nodes of those
    // levels that hold the node across (node_error, or how far its vertices stand off: the errors the
    // tiles take theirs from, but where the border is, not a tile's worst), and at least twice its
    // level's plane distances (the depth before QA round 68 for every edge).
    // The tree above needs only the level indices, so the tiles' meshes (most of the time of an export
    // from stored levels) are cut afterwards, each on its own: the same meshes on any number of threads.
    run_parallel(set.tiles.size(), o.threads, [&](std::size_t k) {
        LodTile& tile = set.tiles[k];
        const LodLevel& level = set.levels[tile.level];
        const Node& region = h.nodes[static_cast<std::size_t>(tile.region)];
        std::vector<std::size_t> chain(tile.level + 1); // the tile's ancestors by level, itself last
        for (std::size_t t = k, l = tile.level + 1; l-- > 0; t = parent[t])
            chain[l] = t;
        const double least = skirt_depth[tile.level];
        const auto depth = [&](std::int32_t across) {
            const Node* node = node_of(h, across);
            if (!node)
                return least;
            std::size_t first = tile.level;
            for (std::size_t l = 1; l < tile.level && first == tile.level; ++l)
                if (!inside(h.nodes[static_cast<std::size_t>(set.tiles[chain[l]].region)], *node))
                    first = l;
            double off = 0.0;
            for (std::size_t l = first; l < tile.level; ++l) {
                // The level's cut node holding the node across: its first ancestor at or above that cut.
                std::int32_t n = across;
                while (n >= 0 && !index[l].at_or_above_cut[static_cast<std::size_t>(n)])
                    n = h.nodes[static_cast<std::size_t>(n)].parent;
                if (n >= 0)
                    off = std::max(off, index[l].error_below[static_cast<std::size_t>(n)]);
            }
            return std::max(least, 2.0 * off);
        };
        extract_region(h, level, index[tile.level], region, depth, o.skirts, tile.mesh, &tile.skirt_faces,
                       &tile.overlap_faces, std::move(queue[k].overlap));
        // The content's box (not the region's points': strays the mesh leaves out made a bunny's root
        // box 17 times its size, QA round 57); empty for a tile without content.
        tile.box = mesh_box(tile.mesh);
    });
    nest_tile_boxes(set.tiles);
    // A tile with no content at any level below (its points all left out) takes its parent's box (a
    // bounding volume must be a box, and lie inside its parent's), the root its region's.
    for (std::size_t k = 0; k < set.tiles.size(); ++k) // parents come first
        if (!(set.tiles[k].box.min.x <= set.tiles[k].box.max.x))
            set.tiles[k].box = k == 0 ? h.nodes[static_cast<std::size_t>(set.tiles[k].region)].box : set.tiles[parent[k]].box;
    return set;
}

LodSet make_lod_set(const Hierarchy& h, const LodSetOptions& o) { return make_lod_tiles(h, make_lod_levels(h, o), o); }

void nest_tile_boxes(std::vector<LodTile>& tiles)
{
    for (std::size_t k = tiles.size(); k-- > 0;)
        for (std::size_t c : tiles[k].children) {
            tiles[k].box.min = min(tiles[k].box.min, tiles[c].box.min);
            tiles[k].box.max = max(tiles[k].box.max, tiles[c].box.max);
        }
}

} // namespace mrt
