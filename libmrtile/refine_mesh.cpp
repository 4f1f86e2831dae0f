// Incremental refinement of a cut's mesh (the "any cut" issue's incremental form), built from the
// paper's own parts: §4.2 pseudo tiles of the finer nodes, and a Delaunay triangulation of their
// points (§4.3's T2, here constrained to the changed tiles' outline). Why a disc with a kept outline:
// a tile's region (its fan and the strips between tiles around its vertices) is the part of mesh_cut's
// surface that belongs to it, so replacing it by a triangulated disc with the same outline cannot
// change the topology or open a crack anywhere; the outline's vertices and everything beyond them stay
// bit for bit.
#include "libmrtile/refine_mesh.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/errors.h"
#include "libmrtile/fit_vertices.h"
#include "libmrtile/gap_triangulation.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/polygon2d.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace mrt {
namespace {

// Rounds of mending a region that touches itself at a vertex (LocalRefiner::unpinch).
constexpr int kPinchRounds = 20;

// LocalRefiner::refit: passes of putting back new vertices whose faces cross another face.
constexpr int kRefitCrossingPasses = 4;

// The height fit of the new vertices (LocalRefiner::fit_heights): points per descendant tile used,
// damping towards the start, the largest move as a share of the shortest incident edge, sweeps.
constexpr std::size_t kFitPointsPerTile = 64;
constexpr double kFitDamping = 0.05;
constexpr double kFitMaxMove = 0.5;
constexpr int kFitSweeps = 20;

// A point to insert: where it is, which descendant it belongs to, which input point it is (or -1).
struct NewPoint
{
    Vec3 position;
    Point2 uv;
    std::int32_t node;
    std::int64_t input_point;
};

class LocalRefiner
{
    // The descendants' pseudo tiles give their apexes, hull points and spacing; their coverage gaps
    // (a grid over the tile's points: a tenth of the focus row's time) are not asked for.
    static TileOptions pseudo_tile_options(TileOptions options)
    {
        options.measure_gaps = false;
        return options;
    }

public:
    // `changing`: the nodes whose tiles will be replaced (the index of fans and vertices holds those
    // only; the tiles made later are added as they are made).
    LocalRefiner(const Hierarchy& h, MeshResult& result, const LocalRefineOptions& options, const std::vector<std::int32_t>& changing)
        : h_(h), mesh_(result.mesh), options_(options), tile_options_(pseudo_tile_options(options.tiles)),
          tile_(OpenMesh::getProperty<OpenMesh::FaceHandle, int>(mesh_, kFaceTile)),
          gap_(OpenMesh::getProperty<OpenMesh::FaceHandle, bool>(mesh_, kFaceGap)),
          cluster_(OpenMesh::getProperty<OpenMesh::VertexHandle, int>(mesh_, kVertexCluster))
    {
        std::vector<char> indexed(h.nodes.size(), 0);
        for (const std::int32_t node : changing)
            indexed[static_cast<std::size_t>(node)] = 1;
        auto wanted = [&](int node) { return node >= 0 && static_cast<std::size_t>(node) < indexed.size() && indexed[static_cast<std::size_t>(node)]; };
        for (const auto f : mesh_.faces())
            if (wanted(tile_[f]))
                fans_[tile_[f]].push_back(f);
        for (const auto v : mesh_.vertices())
            if (wanted(cluster_[v]))
                vertices_[cluster_[v]].push_back(v);
        // Every region's new faces are tested against all faces near them, not only those within two
        // rings of its outline: a region steep in its plane reaches past the rings to the other side
        // of a thin part (QA round 67: the bunny's budget cut 200 -> 400 in place left 27 crossing
        // pairs where a fresh mesh has none; a terrain in a random run kept 3 crossing faces). Filing
        // every face costs a pass over the mesh per call.
        if (options.no_crossings)
            file_all_faces();
    }

    // Normals of the new faces and of the vertices whose faces changed (the rest keep theirs), before
    // the deleted elements are collected (which renumbers handles).
    void update_touched_normals()
    {
        for (const auto f : touched_faces_)
            if (!mesh_.status(f).deleted())
                mesh_.update_normal(f);
        std::sort(touched_vertices_.begin(), touched_vertices_.end());
        touched_vertices_.erase(std::unique(touched_vertices_.begin(), touched_vertices_.end()), touched_vertices_.end());
        for (const auto v : touched_vertices_)
            if (!mesh_.status(v).deleted())
                mesh_.update_normal(v);
    }

    // refined: the region was re-triangulated (split tiles, or merged ones for coarsen); absent: there was
    // nothing in the mesh to re-triangulate; kept: left as it was.
    enum class Outcome { refined, absent, kept };

    // Replaces the region of `node` by a triangulation of its outline with the descendants' points:
    // first the region with the strips around it, then, where that cannot be done safely (it folds in
    // its plane, or is no disc), the fan alone. `absent`: the node has no face and no vertex to replace.
    Outcome refine(std::int32_t node, const std::vector<std::int32_t>& descendants, LocalRefineStats& stats)
    {
        std::vector<Tile> tiles; // the descendants' pseudo tiles, built once for both attempts
        for (const bool with_strips : {true, false}) {
            std::vector<Mesh::FaceHandle> region = with_strips ? region_of(node) : fan_of(node);
            if (region.empty())
                continue;
            if (tiles.empty())
                for (const std::int32_t d : descendants)
                    tiles.push_back(make_tile(h_, d, tile_options_));
            std::vector<Mesh::VertexHandle> outline;
            const bool disc = mend_into_disc(node, {node}, region, outline);
            if (disc && replace_region(node, tiles, region, outline, stats)) {
                hand_over(node, descendants);
                return Outcome::refined;
            }
        }
        if (!tiles.empty())
            return Outcome::kept;
        hand_over(node, descendants);
        return Outcome::absent;
    }

    // Replaces the regions of the `merged` nodes (their fans and the strips around their vertices) by
    // one triangulation of their joint outline with the points of their ancestor's pseudo tile. False,
    // and nothing changed, where the joint region is not one disc or cannot be re-triangulated safely.
    Outcome coarsen(std::int32_t ancestor, const std::vector<std::int32_t>& merged, LocalRefineStats& stats)
    {
        std::vector<Mesh::FaceHandle> region;
        for (const std::int32_t node : merged) {
            const std::vector<Mesh::FaceHandle> part = region_of(node);
            region.insert(region.end(), part.begin(), part.end());
        }
        if (region.empty()) { // nothing of theirs in the mesh: nothing to re-triangulate
            for (const std::int32_t node : merged)
                hand_over(node, {ancestor});
            return Outcome::absent;
        }
        std::vector<Mesh::VertexHandle> outline;
        const bool disc = mend_into_disc(ancestor, merged, region, outline);
        if (!disc || !replace_region(ancestor, {make_tile(h_, ancestor, tile_options_)}, region, outline, stats))
            return Outcome::kept;
        for (const std::int32_t node : merged)
            hand_over(node, {ancestor});
        return Outcome::refined;
    }

    // The vertices this refiner made, fitted to their tiles' points as mesh_cut's fit does
    // (fit_vertices: a relaxation, then least squares along the normals, each round) on a copy of
    // their faces and the ring of faces around them, and moved to where the fit put them. Nothing else
    // moves: the ring's vertices are fitted in the copy only (so that the new vertices meet a surface
    // that fits too) and the outline stays; no edge flips (they would change faces beyond). fit_heights
    // fits each region along one normal, without relaxation: the torus refined from 0.005 to 0.002
    // had 1.9x the mean distance of a fresh mesh.
    void refit(FitOptions fit)
    {
        std::vector<Mesh::VertexHandle> movable;
        for (const auto v : created_)
            if (!mesh_.status(v).deleted())
                movable.push_back(v);
        if (movable.empty() || fit.rounds == 0)
            return;
        // The faces around the new vertices, then those around their corners.
        std::vector<char> taken(mesh_.n_faces(), 0);
        std::vector<Mesh::FaceHandle> faces;
        auto take_around = [&](Mesh::VertexHandle v) {
            for (const auto f : mesh_.vf_range(v))
                if (!taken[static_cast<std::size_t>(f.idx())]) {
                    taken[static_cast<std::size_t>(f.idx())] = 1;
                    faces.push_back(f);
                }
        };
        for (const auto v : movable)
            take_around(v);
        const std::size_t inner = faces.size();
        for (std::size_t k = 0; k < inner; ++k)
            for (const auto v : mesh_.fv_range(faces[k]))
                take_around(v);
        std::sort(faces.begin(), faces.end());
        Mesh copy;
        std::unordered_map<int, Mesh::VertexHandle> in_copy;
        {
            const QuietOpenMesh quiet;
            for (const auto f : faces) {
                std::array<Mesh::VertexHandle, 3> c;
                std::size_t k = 0;
                for (const auto v : mesh_.fv_range(f)) {
                    auto [it, added] = in_copy.emplace(v.idx(), Mesh::VertexHandle());
                    if (added)
                        it->second = copy.add_vertex(mesh_.point(v));
                    c[k++] = it->second;
                }
                if (!copy.add_face(c[0], c[1], c[2]).is_valid())
                    return; // a ring OpenMesh cannot build face by face: leave the fit of fit_heights
            }
        }
        // Points of the new vertices' tiles: about points_per_vertex per new vertex, every k-th of each.
        std::vector<std::int32_t> nodes;
        std::unordered_map<std::int32_t, std::size_t> per_node;
        for (const auto v : movable)
            if (per_node[cluster_[v]]++ == 0)
                nodes.push_back(cluster_[v]);
        std::sort(nodes.begin(), nodes.end());
        std::vector<Vec3> points;
        const std::size_t per_vertex = std::max<std::size_t>(fit.points_per_vertex, 4);
        for (const std::int32_t id : nodes) {
            const Node& node = h_.nodes[static_cast<std::size_t>(id)];
            const std::size_t stride = std::max<std::size_t>(1, node.count() / (per_vertex * per_node[id]));
            for (std::size_t i = node.begin; i < node.end; i += stride)
                points.push_back(h_.cloud.positions[i]);
        }
        fit.flip_edges = false;
        fit.points_per_vertex = 0; // sampled above
        fit_vertices(copy, points, fit);
        std::vector<Mesh::Point> before(movable.size());
        for (std::size_t k = 0; k < movable.size(); ++k) {
            before[k] = mesh_.point(movable[k]);
            mesh_.point(movable[k]) = copy.point(in_copy.at(movable[k].idx()));
        }
        // The fit undoes crossings within the copy; one with a face beyond it (a thin part's other
        // side: the bunny's ear in a random run) puts the corners of the new faces involved back. The
        // faces at a new vertex moved: they are filed again where they are now.
        file_all_faces();
        std::unordered_map<int, std::size_t> index;
        for (std::size_t k = 0; k < movable.size(); ++k)
            index[movable[k].idx()] = k;
        std::vector<Mesh::FaceHandle> suspects(faces.begin(), faces.end()); // those at a new vertex
        suspects.erase(std::remove_if(suspects.begin(), suspects.end(), [&](Mesh::FaceHandle f) {
                           for (const auto v : mesh_.fv_range(f))
                               if (index.count(v.idx()) != 0)
                                   return false;
                           return true;
                       }),
                       suspects.end());
        for (const auto f : suspects)
            file_face(f);
        for (int pass = 0; pass < kRefitCrossingPasses && !suspects.empty(); ++pass) {
            std::vector<std::size_t> back;
            for (const auto f : suspects)
                if (crosses_a_filed_face(f, [&](Mesh::FaceHandle g) { return g == f; }))
                    for (const auto v : mesh_.fv_range(f))
                        if (const auto it = index.find(v.idx()); it != index.end() && mesh_.point(v) != before[it->second])
                            back.push_back(it->second);
            suspects.clear();
            for (const std::size_t k : back) {
                mesh_.point(movable[k]) = before[k];
                for (const auto g : mesh_.vf_range(movable[k])) {
                    file_face(g);
                    suspects.push_back(g);
                }
            }
        }
    }

    // Tiles new to the cut (`fresh`) that have no vertex in the mesh: their points lie beyond the
    // outline of the region they came from, in a neighbour's fan (their parent's points reach into a
    // neighbour's Voronoi cell: mesh_cut's tiles are cut at those cells, a node's own hull is not), or
    // their parent had nothing in the mesh. Each is adopted by the tile whose region covers it: that
    // region is re-triangulated with the tile's own pseudo-tile points and the orphans', as mesh_cut
    // gives the orphan a fan of its own in that neighbour's cell. Without this, such a tile stayed
    // without a vertex for good, and every later refinement of it found nothing to re-triangulate
    // (QA round 49: up to 24% of the tiles after long random runs). Hosts are tried nearest first
    // (the tiles of the vertices nearest the orphan's centre), at most kAdoptionTries each.
    void adopt_orphans(const std::vector<std::int32_t>& fresh, LocalRefineStats& stats)
    {
        std::vector<std::int32_t> orphans;
        for (const std::int32_t node : fresh)
            if (!has_vertex(node))
                orphans.push_back(node);
        if (orphans.empty())
            return;
        std::vector<char> is_orphan(h_.nodes.size(), 0);
        for (const std::int32_t node : orphans)
            is_orphan[static_cast<std::size_t>(node)] = 1;
        const double cell = file_all_faces();
        // Per orphan, the hosts to try: the tiles of its nearest vertices, nearest first. The vertices
        // by grid cell; a query box doubles until it holds enough vertices within its half-width (all
        // the nearest ones, then) or spans all vertices.
        BoxGrid vertex_grid(cell);
        std::vector<Mesh::VertexHandle> live;
        for (const auto v : mesh_.vertices())
            if (cluster_[v] >= 0 && !is_orphan[static_cast<std::size_t>(cluster_[v])]) {
                const Vec3 p = to_vec3(mesh_.point(v));
                vertex_grid.insert(static_cast<std::uint32_t>(v.idx()), {p, p});
                live.push_back(v);
            }
        if (live.empty())
            return;
        std::vector<std::vector<Mesh::VertexHandle>> hosts(orphans.size());
        for (std::size_t k = 0; k < orphans.size(); ++k) {
            const Node& orphan = h_.nodes[static_cast<std::size_t>(orphans[k])];
            const Vec3 centre = orphan.moments.mean;
            std::vector<std::pair<double, int>> by_distance;
            auto consider = [&](Mesh::VertexHandle v, double reach) {
                const double d2 = squared_distance(to_vec3(mesh_.point(v)), centre);
                if (d2 <= reach * reach)
                    by_distance.push_back({d2, v.idx()});
            };
            for (double reach = cell;; reach *= 2.0) {
                by_distance.clear();
                const Vec3 half{reach, reach, reach};
                const BoundingBox query{centre - half, centre + half};
                if (vertex_grid.cell_count(query) > static_cast<double>(live.size())) { // as cheap to look at them all
                    for (const auto v : live)
                        consider(v, std::numeric_limits<double>::infinity());
                    break;
                }
                vertex_grid.for_each_candidate(query, [&](std::uint32_t id) { consider(Mesh::VertexHandle(static_cast<int>(id)), reach); });
                if (by_distance.size() >= kAdoptionVertices)
                    break;
            }
            const std::size_t nearest = std::min<std::size_t>(by_distance.size(), kAdoptionVertices);
            std::partial_sort(by_distance.begin(), by_distance.begin() + static_cast<std::ptrdiff_t>(nearest), by_distance.end());
            for (std::size_t i = 0; i < nearest && hosts[k].size() < kAdoptionTries; ++i) {
                const Mesh::VertexHandle v(by_distance[i].second);
                const bool seen = std::any_of(hosts[k].begin(), hosts[k].end(), [&](Mesh::VertexHandle w) { return cluster_[w] == cluster_[v]; });
                // A host across a crease (fandisk: the orphan on one face, the nearest vertex's tile on
                // the other) would take points off its plane into its region and fold it over its
                // neighbours (8 crossing faces in a random run): its plane must be near the orphan's.
                const Vec3& host_normal = h_.nodes[static_cast<std::size_t>(cluster_[v])].frame.vectors[0];
                if (!seen && std::abs(dot(host_normal, orphan.frame.vectors[0])) >= kAdoptionMinCos)
                    hosts[k].push_back(v);
            }
        }
        for (std::size_t attempt = 0; attempt < kAdoptionTries; ++attempt) {
            // The orphans still without a vertex, grouped by this attempt's host (in orphan order).
            std::vector<std::pair<std::int32_t, std::vector<std::int32_t>>> groups;
            std::vector<Mesh::VertexHandle> seeds;
            for (std::size_t k = 0; k < orphans.size(); ++k) {
                if (attempt >= hosts[k].size() || has_vertex(orphans[k]))
                    continue;
                const auto v = hosts[k][attempt];
                if (mesh_.status(v).deleted()) // an earlier adoption re-made the host's region: ask again next time
                    continue;
                const std::int32_t host = cluster_[v];
                auto group = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == host; });
                if (group == groups.end()) {
                    groups.push_back({host, {}});
                    seeds.push_back(v);
                    group = groups.end() - 1;
                }
                group->second.push_back(orphans[k]);
            }
            for (std::size_t g = 0; g < groups.size(); ++g) {
                const auto& [host, adopted] = groups[g];
                index_tile(host, seeds[g]);
                std::vector<Mesh::FaceHandle> region = region_of(host);
                if (region.empty())
                    continue;
                std::vector<Mesh::VertexHandle> outline;
                if (!mend_into_disc(host, {host}, region, outline))
                    continue;
                // The host's own points first: it must keep its vertices (an orphan's point too near
                // one of them is left out, as any descendant's point near a point already taken is).
                std::vector<Tile> tiles{make_tile(h_, host, tile_options_)};
                for (const std::int32_t node : adopted)
                    tiles.push_back(make_tile(h_, node, tile_options_));
                if (replace_region(host, tiles, region, outline, stats))
                    for (const std::int32_t node : adopted)
                        stats.adopted += has_vertex(node) ? 1 : 0;
            }
        }
    }

private:
    // adopt_orphans: hosts tried per orphan, among the tiles of how many of its nearest vertices, whose
    // planes turn at most 60 degrees from the orphan's.
    static constexpr std::size_t kAdoptionTries = 3;
    static constexpr std::size_t kAdoptionVertices = 24;
    static constexpr double kAdoptionMinCos = 0.5;

    // Files every face of the mesh in all_faces_ (cells twice the mean edge length), once per refiner:
    // faces added later are filed as they are added (replace_faces), faces whose corners moved again
    // (refit), and deleted ones are skipped when met. A host's new faces are tested against every face
    // near them, not only those within two rings of its outline: an orphan's points can lie on another
    // sheet that its host's plane sees through the host's region (the bunny refined from 0.01 to 0.002:
    // three faces of an ear crossed). Returns the cell size.
    double file_all_faces()
    {
        if (all_faces_)
            return all_faces_cell_;
        double sum = 0.0;
        std::size_t edges = 0;
        for (const auto e : mesh_.edges())
            if (!mesh_.status(e).deleted()) {
                sum += mesh_.calc_edge_length(e);
                ++edges;
            }
        all_faces_cell_ = edges > 0 && sum > 0.0 ? 2.0 * sum / static_cast<double>(edges) : 1.0;
        all_faces_.emplace(all_faces_cell_);
        for (const auto f : mesh_.faces())
            file_face(f);
        return all_faces_cell_;
    }

    // Files a face in all_faces_ where it is now.
    void file_face(Mesh::FaceHandle f) { all_faces_->insert(static_cast<std::uint32_t>(f.idx()), triangle_box(face_corners(mesh_, f))); }

    // Whether face f crosses a face filed in all_faces_ that is not deleted nor `skip`ped.
    template <typename Skip>
    bool crosses_a_filed_face(Mesh::FaceHandle f, const Skip& skip) const
    {
        const BoundingBox box = triangle_box(face_corners(mesh_, f));
        return all_faces_->any_candidate(box, [&](std::uint32_t id) {
            const Mesh::FaceHandle g(static_cast<int>(id));
            return !mesh_.status(g).deleted() && !skip(g) && box.meets(triangle_box(face_corners(mesh_, g))) &&
                   faces_intersect(mesh_, f, g);
        });
    }

    // Whether a new face crosses a face of all_faces_ (filed by the constructor whenever
    // no_crossings asks for this test). The new faces are marked in face_stamp_ by
    // crosses_surroundings, which runs first: they are tested against each other by construction, and
    // the faces it tested are skipped too.
    bool crosses_anything(const std::vector<Mesh::FaceHandle>& added)
    {
        assert(all_faces_);
        return std::any_of(added.begin(), added.end(), [&](Mesh::FaceHandle f) {
            return crosses_a_filed_face(f, [&](Mesh::FaceHandle g) { return face_stamp_[static_cast<std::size_t>(g.idx())] == stamp_; });
        });
    }

    // Whether the node has a vertex in the mesh (v:cluster = node).
    bool has_vertex(std::int32_t node) const
    {
        const auto own = vertices_.find(node);
        if (own == vertices_.end())
            return false;
        return std::any_of(own->second.begin(), own->second.end(),
                           [&](Mesh::VertexHandle v) { return !mesh_.status(v).deleted() && cluster_[v] == node; });
    }

    // Adds a tile the index does not hold yet (a tile of the cut that is not changing) from one of its
    // vertices: its vertices are joined by its fan's edges, its fan faces are theirs with f:tile = node.
    void index_tile(std::int32_t node, Mesh::VertexHandle seed)
    {
        if (fans_.count(node) != 0 || vertices_.count(node) != 0)
            return;
        std::vector<Mesh::VertexHandle>& own = vertices_[node];
        std::vector<Mesh::FaceHandle>& fan = fans_[node];
        std::vector<Mesh::VertexHandle> stack{seed};
        std::vector<int> seen{seed.idx()};
        while (!stack.empty()) {
            const auto v = stack.back();
            stack.pop_back();
            own.push_back(v);
            for (const auto g : mesh_.vf_range(v))
                if (tile_[g] == node && std::find(fan.begin(), fan.end(), g) == fan.end())
                    fan.push_back(g);
            for (const auto w : mesh_.vv_range(v))
                if (cluster_[w] == node && std::find(seen.begin(), seen.end(), w.idx()) == seen.end()) {
                    seen.push_back(w.idx());
                    stack.push_back(w);
                }
        }
    }

    // The region (marked in in_region_) made one disc if it can be: its main piece kept (strips joined
    // to it by a corner only may stay), every fan face of the replaced nodes still in it (a face left
    // naming a node would name no tile of the cut), vertices where it touches itself mended
    // (unpinch moves strips only, so the fans stay). The outline when it is one; the marks are cleared.
    bool mend_into_disc(std::int32_t node, const std::vector<std::int32_t>& replaced, std::vector<Mesh::FaceHandle>& region,
                        std::vector<Mesh::VertexHandle>& outline)
    {
        keep_main_piece(node, region);
        std::vector<Mesh::VertexHandle> pinches;
        bool disc = holds_fans(replaced) && disc_outline(region, outline, pinches);
        std::vector<int> tried;
        for (int round = 0; round < kPinchRounds && !disc && !pinches.empty(); ++round) {
            unpinch(pinches, region, tried);
            outline.clear();
            pinches.clear();
            disc = disc_outline(region, outline, pinches);
        }
        for (const auto f : region)
            in_region_[static_cast<std::size_t>(f.idx())] = 0;
        return disc;
    }

    // Whether a new face would join two outline vertices that an edge outside the region already joins
    // (where the outline turns back on itself across a narrow neck): that edge would get three faces,
    // and OpenMesh would refuse the face.
    bool reuses_an_outside_edge(const std::vector<Mesh::FaceHandle>& region, const std::vector<Mesh::VertexHandle>& outline,
                                const std::vector<std::array<std::uint32_t, 3>>& triangles) const
    {
        std::vector<int> inside(region.size());
        for (std::size_t k = 0; k < region.size(); ++k)
            inside[k] = region[k].idx();
        std::sort(inside.begin(), inside.end());
        auto in_region = [&](Mesh::FaceHandle f) { return f.is_valid() && std::binary_search(inside.begin(), inside.end(), f.idx()); };
        const std::size_t n = outline.size();
        for (const auto& t : triangles)
            for (std::size_t c = 0; c < 3; ++c) {
                const std::uint32_t a = t[c], b = t[(c + 1) % 3];
                if (a >= n || b >= n || (a + 1) % n == b || (b + 1) % n == a)
                    continue; // a new vertex, or an edge of the outline itself
                const auto he = mesh_.find_halfedge(outline[a], outline[b]);
                if (he.is_valid() && !(in_region(mesh_.face_handle(he)) && in_region(mesh_.opposite_face_handle(he))))
                    return true;
            }
        return false;
    }

    // Whether every fan face of the nodes is in the region being built (in_region_).
    bool holds_fans(const std::vector<std::int32_t>& nodes) const
    {
        for (const std::int32_t node : nodes)
            if (const auto fan = fans_.find(node); fan != fans_.end())
                for (const auto f : fan->second)
                    if (!mesh_.status(f).deleted() && !in_region_[static_cast<std::size_t>(f.idx())])
                        return false;
        return true;
    }

    // Re-triangulates the disc `region` (outline as given) of `node` with the points of `tiles` (the
    // pseudo tiles of the nodes that replace it); false, and nothing changed, where its outline or new
    // faces fold in its plane, cross the faces around it, or OpenMesh refuses a face.
    bool replace_region(std::int32_t node, const std::vector<Tile>& tiles, const std::vector<Mesh::FaceHandle>& region,
                        const std::vector<Mesh::VertexHandle>& outline, LocalRefineStats& stats)
    {
        const PlaneFrame plane = plane_of(node, region);
        std::vector<Point2> polygon;
        polygon.reserve(outline.size());
        for (const auto v : outline)
            polygon.push_back(plane.project(to_vec3(mesh_.point(v))));
        if (signed_area(polygon) <= 0.0)
            return false; // the outline folds in the plane (or is degenerate)
        std::vector<NewPoint> points = tile_points(plane, polygon, tiles);
        std::vector<Point2> inside;
        inside.reserve(points.size());
        for (const NewPoint& p : points)
            inside.push_back(p.uv);
        const std::vector<std::array<std::uint32_t, 3>> triangles = polygon_triangles(polygon, inside);
        if (triangles.empty() || reuses_an_outside_edge(region, outline, triangles))
            return false;
        // Where each triangle corner is in 3D: an outline vertex, or a new point.
        auto position = [&](std::uint32_t k) {
            return k < outline.size() ? to_vec3(mesh_.point(outline[k])) : points[k - outline.size()].position;
        };
        const double min_cos = std::cos(options_.max_tilt_degrees * M_PI / 180.0);
        auto folds = [&] {
            for (const auto& t : triangles) {
                const Vec3 normal = cross(position(t[1]) - position(t[0]), position(t[2]) - position(t[0]));
                const double length = norm(normal);
                if (!(length > 0.0) || dot(normal, plane.n) < min_cos * length)
                    return true;
            }
            return false;
        };
        if (folds())
            return false;
        if (options_.fit) {
            const std::vector<NewPoint> unfitted = points;
            fit_heights(plane, polygon, outline, tiles, triangles, points);
            if (folds())
                points = unfitted;
        }
        if (!replace_faces(region, outline, points, triangles, stats))
            return false;
        stats.faces_removed += region.size();
        stats.faces_added += triangles.size();
        return true;
    }

    // The node leaves the cut: its vertices still in the mesh (on the outline, or in another piece of
    // its region) now belong to its descendant with the nearest centre, so that every vertex names a
    // tile of the cut (v:cluster, as mesh_cut leaves it).
    void hand_over(std::int32_t node, const std::vector<std::int32_t>& descendants)
    {
        const auto own = vertices_.find(node);
        if (own != vertices_.end()) {
            const std::vector<Mesh::VertexHandle> left = std::move(own->second);
            vertices_.erase(own);
            for (const auto v : left)
                if (!mesh_.status(v).deleted() && cluster_[v] == node) {
                    const Vec3 p = to_vec3(mesh_.point(v));
                    std::int32_t nearest = descendants.front();
                    double best = std::numeric_limits<double>::infinity();
                    for (const std::int32_t d : descendants) {
                        const double d2 = squared_distance(p, h_.nodes[static_cast<std::size_t>(d)].moments.mean);
                        if (d2 < best) {
                            best = d2;
                            nearest = d;
                        }
                    }
                    cluster_[v] = nearest;
                    vertices_[nearest].push_back(v);
                }
        }
        fans_.erase(node);
    }

    // The node's fan alone (f:tile = node), marked in in_region_.
    std::vector<Mesh::FaceHandle> fan_of(std::int32_t node)
    {
        in_region_.resize(mesh_.n_faces(), 0);
        std::vector<Mesh::FaceHandle> fan;
        if (const auto found = fans_.find(node); found != fans_.end())
            for (const auto f : found->second)
                if (!mesh_.status(f).deleted() && !in_region_[static_cast<std::size_t>(f.idx())]) {
                    in_region_[static_cast<std::size_t>(f.idx())] = 1;
                    fan.push_back(f);
                }
        return fan;
    }

    // Keeps the piece of the region (faces joined by edges) with the most faces of the node's fan, or
    // the largest piece: a node's vertices can lie apart (an outline vertex handed over by a neighbour).
    void keep_main_piece(std::int32_t node, std::vector<Mesh::FaceHandle>& region)
    {
        std::vector<int> piece(region.size(), -1);
        std::unordered_map<int, std::size_t> position;
        for (std::size_t k = 0; k < region.size(); ++k)
            position[region[k].idx()] = k;
        std::vector<std::pair<std::size_t, std::size_t>> score; // (fan faces, faces) per piece
        for (std::size_t start = 0; start < region.size(); ++start) {
            if (piece[start] >= 0)
                continue;
            const int id = static_cast<int>(score.size());
            score.push_back({0, 0});
            std::vector<std::size_t> stack{start};
            piece[start] = id;
            while (!stack.empty()) {
                const std::size_t k = stack.back();
                stack.pop_back();
                score.back().first += tile_[region[k]] == node ? 1 : 0;
                ++score.back().second;
                for (const auto g : mesh_.ff_range(region[k])) {
                    const auto it = position.find(g.idx());
                    if (it != position.end() && piece[it->second] < 0) {
                        piece[it->second] = id;
                        stack.push_back(it->second);
                    }
                }
            }
        }
        if (score.size() < 2)
            return;
        const int best = static_cast<int>(std::max_element(score.begin(), score.end()) - score.begin());
        std::vector<Mesh::FaceHandle> kept;
        for (std::size_t k = 0; k < region.size(); ++k)
            if (piece[k] == best)
                kept.push_back(region[k]);
            else
                in_region_[static_cast<std::size_t>(region[k].idx())] = 0;
        region = std::move(kept);
    }

    // The new vertices moved along the plane's normal to fit the descendants' points in least squares
    // (the region is a graph over the plane: a height per vertex, linear over each triangle), as
    // fit_vertices does for a whole mesh: interpolated input points leave a curved patch's chords
    // below it. The outline stays. Damped towards where each vertex started and bounded by half its
    // shortest edge, as FitOptions' defaults are.
    void fit_heights(const PlaneFrame& plane, const std::vector<Point2>& polygon, const std::vector<Mesh::VertexHandle>& outline,
                     const std::vector<Tile>& tiles, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                     std::vector<NewPoint>& points) const
    {
        const std::size_t fixed = outline.size(), count = fixed + points.size();
        std::vector<Point2> uv(count);
        std::vector<double> height(count);
        for (std::size_t k = 0; k < fixed; ++k) {
            uv[k] = polygon[k];
            height[k] = plane.height(to_vec3(mesh_.point(outline[k])));
        }
        for (std::size_t k = fixed; k < count; ++k) {
            uv[k] = points[k - fixed].uv;
            height[k] = plane.height(points[k - fixed].position);
        }
        // A grid of the triangles' boxes, about one triangle per cell, to find the triangle under a point.
        double lo_u = uv[0][0], hi_u = lo_u, lo_v = uv[0][1], hi_v = lo_v;
        for (const Point2& p : uv) {
            lo_u = std::min(lo_u, p[0]);
            hi_u = std::max(hi_u, p[0]);
            lo_v = std::min(lo_v, p[1]);
            hi_v = std::max(hi_v, p[1]);
        }
        const std::size_t side = std::max<std::size_t>(1, static_cast<std::size_t>(std::sqrt(static_cast<double>(triangles.size()))));
        const double cell_u = std::max(hi_u - lo_u, 1e-300) / static_cast<double>(side);
        const double cell_v = std::max(hi_v - lo_v, 1e-300) / static_cast<double>(side);
        auto cell = [&](double u, double v) {
            const auto i = std::min(side - 1, static_cast<std::size_t>(std::max(0.0, (u - lo_u) / cell_u)));
            const auto j = std::min(side - 1, static_cast<std::size_t>(std::max(0.0, (v - lo_v) / cell_v)));
            return std::array<std::size_t, 2>{i, j};
        };
        // The cells' triangle lists as compressed rows (counted, then filled in triangle order): one
        // allocation per region instead of one per cell.
        std::vector<std::uint32_t> grid_start(side * side + 1, 0), grid;
        for (int pass = 0; pass < 2; ++pass) {
            std::vector<std::uint32_t> fill;
            if (pass == 1) {
                for (std::size_t c = 0; c < side * side; ++c)
                    grid_start[c + 1] += grid_start[c];
                grid.resize(grid_start.back());
                fill.assign(grid_start.begin(), grid_start.end() - 1);
            }
            for (std::uint32_t t = 0; t < triangles.size(); ++t) {
                const Point2 &a = uv[triangles[t][0]], &b = uv[triangles[t][1]], &c = uv[triangles[t][2]];
                const auto lo = cell(std::min({a[0], b[0], c[0]}), std::min({a[1], b[1], c[1]}));
                const auto hi = cell(std::max({a[0], b[0], c[0]}), std::max({a[1], b[1], c[1]}));
                for (std::size_t i = lo[0]; i <= hi[0]; ++i)
                    for (std::size_t j = lo[1]; j <= hi[1]; ++j) {
                        if (pass == 0)
                            ++grid_start[j * side + i + 1];
                        else
                            grid[fill[j * side + i]++] = t;
                    }
            }
        }
        // Per triangle, the normal equations of its points: Σ λλᵀ and Σ λ z.
        std::vector<std::array<double, 9>> normal(triangles.size(), std::array<double, 9>{});
        std::vector<std::array<double, 3>> rhs(triangles.size(), std::array<double, 3>{});
        std::size_t samples = 0;
        for (const Tile& tile : tiles) {
            const Node& node = h_.nodes[static_cast<std::size_t>(tile.node)];
            const std::size_t n = node.end - node.begin;
            const std::size_t stride = std::max<std::size_t>(1, n / kFitPointsPerTile);
            for (std::size_t i = node.begin; i < node.end; i += stride) {
                const Vec3& q = h_.cloud.positions[i];
                const Point2 p = plane.project(q);
                const auto c = cell(p[0], p[1]);
                const std::size_t at = c[1] * side + c[0];
                for (std::uint32_t g = grid_start[at]; g < grid_start[at + 1]; ++g) {
                    const std::uint32_t t = grid[g];
                    std::array<double, 3> l{};
                    if (!barycentric(p, {uv[triangles[t][0]], uv[triangles[t][1]], uv[triangles[t][2]]}, l) || l[0] < -1e-9 ||
                        l[1] < -1e-9 || l[2] < -1e-9)
                        continue;
                    const double z = plane.height(q);
                    for (int r = 0; r < 3; ++r) {
                        rhs[t][static_cast<std::size_t>(r)] += l[static_cast<std::size_t>(r)] * z;
                        for (int k = 0; k < 3; ++k)
                            normal[t][static_cast<std::size_t>(3 * r + k)] += l[static_cast<std::size_t>(r)] * l[static_cast<std::size_t>(k)];
                    }
                    ++samples;
                    break;
                }
            }
        }
        if (samples == 0)
            return;
        // Gauss-Seidel on the new vertices' heights; the damping weight is a share of the mean weight
        // the points put on a vertex.
        // Per vertex, its (triangle, corner) pairs in triangle order, as compressed rows.
        std::vector<std::uint32_t> incident_start(count + 1, 0);
        for (const auto& t : triangles)
            for (const std::uint32_t k : t)
                ++incident_start[k + 1];
        for (std::size_t k = 0; k < count; ++k)
            incident_start[k + 1] += incident_start[k];
        std::vector<std::pair<std::uint32_t, int>> incident(incident_start.back());
        std::vector<std::uint32_t> incident_fill(incident_start.begin(), incident_start.end() - 1);
        std::vector<double> shortest(count, std::numeric_limits<double>::infinity());
        for (std::uint32_t t = 0; t < triangles.size(); ++t)
            for (int r = 0; r < 3; ++r) {
                const std::uint32_t k = triangles[t][static_cast<std::size_t>(r)];
                incident[incident_fill[k]++] = {t, r};
                const std::uint32_t next = triangles[t][static_cast<std::size_t>((r + 1) % 3)];
                const double length = distance(plane.point(uv[k], height[k]), plane.point(uv[next], height[next]));
                shortest[k] = std::min(shortest[k], length);
                shortest[next] = std::min(shortest[next], length);
            }
        double weight = 0.0;
        for (std::size_t k = fixed; k < count; ++k)
            for (std::uint32_t i = incident_start[k]; i < incident_start[k + 1]; ++i) {
                const auto [t, r] = incident[i];
                weight += normal[t][static_cast<std::size_t>(4 * r)];
            }
        const double damping = kFitDamping * weight / static_cast<double>(count - fixed) + 1e-300;
        const std::vector<double> start = height;
        for (int sweep = 0; sweep < kFitSweeps; ++sweep)
            for (std::size_t k = fixed; k < count; ++k) {
                double diagonal = damping, sum = damping * start[k];
                for (std::uint32_t i = incident_start[k]; i < incident_start[k + 1]; ++i) {
                    const auto [t, r] = incident[i];
                    diagonal += normal[t][static_cast<std::size_t>(4 * r)];
                    sum += rhs[t][static_cast<std::size_t>(r)];
                    for (int c = 0; c < 3; ++c)
                        if (c != r)
                            sum -= normal[t][static_cast<std::size_t>(3 * r + c)] * height[triangles[t][static_cast<std::size_t>(c)]];
                }
                const double bound = kFitMaxMove * shortest[k];
                height[k] = std::clamp(sum / diagonal, start[k] - bound, start[k] + bound);
            }
        for (std::size_t k = fixed; k < count; ++k)
            points[k - fixed].position = plane.point(uv[k], height[k]);
    }

    // The node's fan (f:tile = node) and the faces between tiles (f:tile -1: gap faces, faces flipped
    // across tiles) at the fan's and the node's vertices: the strips to the neighbours' rims are re-made
    // with the descendants' points too. Marked in in_region_ (the caller clears the marks).
    std::vector<Mesh::FaceHandle> region_of(std::int32_t node)
    {
        in_region_.resize(mesh_.n_faces(), 0);
        std::vector<Mesh::FaceHandle> region;
        auto take = [&](Mesh::FaceHandle f) {
            char& mark = in_region_[static_cast<std::size_t>(f.idx())];
            if (!mark) {
                mark = 1;
                region.push_back(f);
            }
        };
        auto take_around = [&](Mesh::VertexHandle v) {
            for (const auto g : mesh_.vf_range(v))
                if (tile_[g] < 0 || tile_[g] == node)
                    take(g);
        };
        if (const auto fan = fans_.find(node); fan != fans_.end())
            for (const auto f : fan->second)
                if (!mesh_.status(f).deleted())
                    for (const auto v : mesh_.fv_range(f))
                        take_around(v);
        if (const auto own = vertices_.find(node); own != vertices_.end())
            for (const auto v : own->second)
                if (!mesh_.status(v).deleted())
                    take_around(v);
        return region;
    }

    // Where the region's outline passes a vertex twice (the region touches itself there), the faces
    // between tiles at that vertex join the region (which often makes it an inner vertex); where that
    // was tried before at the vertex, they leave it instead.
    void unpinch(const std::vector<Mesh::VertexHandle>& pinches, std::vector<Mesh::FaceHandle>& region,
                 std::vector<int>& tried)
    {
        for (const auto w : pinches) {
            const bool fill = std::find(tried.begin(), tried.end(), w.idx()) == tried.end();
            tried.push_back(w.idx());
            for (const auto g : mesh_.vf_range(w))
                if (tile_[g] < 0) {
                    char& mark = in_region_[static_cast<std::size_t>(g.idx())];
                    if (fill && !mark)
                        region.push_back(g);
                    mark = fill ? 1 : 0;
                }
        }
        region.erase(std::remove_if(region.begin(), region.end(),
                                    [&](Mesh::FaceHandle f) { return !in_region_[static_cast<std::size_t>(f.idx())]; }),
                     region.end());
    }

    // True when the region's faces form one disc with a simple outline; the outline, in the winding of
    // its faces (counter-clockwise seen from their side). Else the vertices it passes twice, if any.
    bool disc_outline(const std::vector<Mesh::FaceHandle>& region, std::vector<Mesh::VertexHandle>& outline,
                      std::vector<Mesh::VertexHandle>& pinches)
    {
        auto in_region = [&](Mesh::FaceHandle f) { return f.is_valid() && in_region_[static_cast<std::size_t>(f.idx())]; };
        std::unordered_map<int, Mesh::HalfedgeHandle> next_on_outline; // from-vertex → outline half-edge
        std::size_t edges = 0, border = 0;
        std::vector<int> vertices;
        for (const auto f : region)
            for (const auto he : mesh_.fh_range(f)) {
                vertices.push_back(mesh_.from_vertex_handle(he).idx());
                const auto opposite = mesh_.opposite_face_handle(he);
                if (in_region(opposite)) {
                    ++edges; // counted from both sides
                    continue;
                }
                ++border;
                if (!next_on_outline.emplace(mesh_.from_vertex_handle(he).idx(), he).second)
                    pinches.push_back(mesh_.from_vertex_handle(he)); // the outline passes it twice
            }
        if (!pinches.empty())
            return false;
        std::sort(vertices.begin(), vertices.end());
        vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
        const std::size_t e = edges / 2 + border;
        // One disc: Euler characteristic 1, and the outline is one loop through all its half-edges.
        if (static_cast<long long>(vertices.size()) - static_cast<long long>(e) + static_cast<long long>(region.size()) != 1)
            return false;
        Mesh::HalfedgeHandle he = next_on_outline.begin()->second;
        const Mesh::HalfedgeHandle first = he;
        do {
            outline.push_back(mesh_.from_vertex_handle(he));
            const auto next = next_on_outline.find(mesh_.to_vertex_handle(he).idx());
            if (next == next_on_outline.end() || outline.size() > border)
                return false;
            he = next->second;
        } while (he != first);
        if (outline.size() != border || border < 3)
            return false;
        // Start at the smallest vertex index: the same outline gives the same polygon, whatever the map's order.
        std::rotate(outline.begin(), std::min_element(outline.begin(), outline.end()), outline.end());
        return true;
    }

    // The plane the region is re-triangulated in: through the node's mean, normal to the region's
    // area-weighted face normal (the node's PCA normal when the faces cancel out). The region's own
    // normal, not the node's: the strips around the fan belong to it too, and a plane that sees the
    // whole region face-on folds it least.
    PlaneFrame plane_of(std::int32_t node, const std::vector<Mesh::FaceHandle>& region) const
    {
        const Node& n = h_.nodes[static_cast<std::size_t>(node)];
        Vec3 faces{0, 0, 0};
        for (const auto f : region) {
            const std::array<Vec3, 3> c = face_corners(mesh_, f);
            faces += cross(c[1] - c[0], c[2] - c[0]);
        }
        Vec3 normal = n.frame.vectors[0];
        const double length = norm(faces);
        if (length > 0.0)
            normal = faces / length;
        // Any unit vector across the normal: the largest PCA axis with its normal part taken out.
        Vec3 u = n.frame.vectors[2] - normal * dot(n.frame.vectors[2], normal);
        if (!(norm(u) > 1e-6))
            u = n.frame.vectors[1] - normal * dot(n.frame.vectors[1], normal);
        u = u / norm(u);
        return {n.moments.mean, u, cross(normal, u), normal}; // cross(u, v) == normal: right-handed
    }

    // The pseudo-tile points (apex and hull) of `tiles` that lie inside the outline, apart from it
    // and from each other by LocalRefineOptions::min_separation of their tile's spacing.
    std::vector<NewPoint> tile_points(const PlaneFrame& plane, const std::vector<Point2>& polygon,
                                            const std::vector<Tile>& tiles) const
    {
        std::vector<NewPoint> candidates;
        std::vector<double> separation;
        for (const Tile& tile : tiles) {
            const double sep = options_.min_separation * tile.spacing();
            auto add = [&](const Vec3& p, std::int64_t input) {
                candidates.push_back({p, plane.project(p), tile.node, input});
                separation.push_back(sep);
            };
            if (tile.has_fan())
                add(tile.apex, -1);
            for (const std::uint32_t i : tile.boundary)
                add(h_.cloud.positions[i], static_cast<std::int64_t>(i));
        }
        if (candidates.empty())
            return {};
        // Points taken so far, in a grid of cells as wide as the largest separation: a point can be too
        // near only to points in its own cell and the eight around it. Wider cells change nothing but
        // the work; a separation of 0 (or next to it) made cells so narrow that the cell indices
        // overflowed (QA round 37, UBSan), so a cell spans at least 1e-12 of the farthest coordinate.
        double farthest = 0.0;
        for (const NewPoint& c : candidates)
            farthest = std::max({farthest, std::abs(c.uv[0]), std::abs(c.uv[1])});
        const double cell = std::max({*std::max_element(separation.begin(), separation.end()), 1e-12 * farthest, 1e-300});
        auto cell_of = [&](const Point2& p) {
            return std::array<std::int64_t, 2>{static_cast<std::int64_t>(std::floor(p[0] / cell)),
                                               static_cast<std::int64_t>(std::floor(p[1] / cell))};
        };
        auto key = [](std::int64_t i, std::int64_t j) { return static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(j); };
        std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
        std::vector<NewPoint> kept;
        std::vector<double> kept_separation;
        for (std::size_t k = 0; k < candidates.size(); ++k) {
            const NewPoint& c = candidates[k];
            const double s2 = separation[k] * separation[k];
            if (!inside_polygon(polygon, c.uv))
                continue;
            bool clear = true;
            for (std::size_t i = 0; i < polygon.size() && clear; ++i)
                clear = segment_distance2(c.uv, polygon[i], polygon[(i + 1) % polygon.size()]) >= s2;
            const auto at = cell_of(c.uv);
            for (std::int64_t di = -1; di <= 1 && clear; ++di)
                for (std::int64_t dj = -1; dj <= 1 && clear; ++dj) {
                    const auto found = grid.find(key(at[0] + di, at[1] + dj));
                    if (found == grid.end())
                        continue;
                    for (const std::uint32_t j : found->second) {
                        const double dx = kept[j].uv[0] - c.uv[0], dy = kept[j].uv[1] - c.uv[1];
                        const double s = std::max(separation[k], kept_separation[j]);
                        if (dx * dx + dy * dy < s * s) {
                            clear = false;
                            break;
                        }
                    }
                }
            if (clear) {
                grid[key(at[0], at[1])].push_back(static_cast<std::uint32_t>(kept.size()));
                kept.push_back(c);
                kept_separation.push_back(separation[k]);
            }
        }
        return kept;
    }

    // Deletes the region and adds the new faces in an order that always attaches to what is there
    // (each face shares an edge with the outline or with faces already added); if OpenMesh refuses a
    // face (counted in stats.refused) or a new face crosses the faces around, the region is put back
    // as it was and false returned.
    bool replace_faces(const std::vector<Mesh::FaceHandle>& region, const std::vector<Mesh::VertexHandle>& outline,
                       const std::vector<NewPoint>& points, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                       LocalRefineStats& stats)
    {
        std::vector<std::array<Mesh::VertexHandle, 3>> old_faces;
        std::vector<char> old_gap;
        std::vector<int> old_tile;
        for (const auto f : region) {
            old_faces.push_back(face_vertices(mesh_, f));
            old_gap.push_back(gap_[f] ? 1 : 0);
            old_tile.push_back(tile_[f]);
        }
        const std::vector<std::size_t> order = attach_order(triangles, outline.size());
        if (order.size() != triangles.size())
            return false;
        for (const auto f : region)
            mesh_.delete_face(f, false);
        std::vector<Mesh::VertexHandle> corner(outline.begin(), outline.end());
        for (const NewPoint& p : points) {
            const auto v = mesh_.add_vertex(to_point(p.position));
            cluster_[v] = p.node;
            vertices_[p.node].push_back(v);
            if (mesh_.has_vertex_colors())
                mesh_.set_color(v, colour_of(p));
            corner.push_back(v);
        }
        std::vector<Mesh::FaceHandle> added;
        bool refused = false;
        {
            const QuietOpenMesh quiet;
            for (const std::size_t k : order) {
                const auto& t = triangles[k];
                const auto f = mesh_.add_face(corner[t[0]], corner[t[1]], corner[t[2]]);
                if (!f.is_valid()) {
                    refused = true;
                    break;
                }
                added.push_back(f);
                const std::int32_t owner = owner_of(t, points, outline.size());
                tile_[f] = owner;
                gap_[f] = owner < 0;
            }
        }
        // New faces that cross faces just outside the outline (a region steep in its plane can fold
        // over its surroundings): tested against the faces within two rings of the outline, then
        // against every face near them.
        const bool crossing = !refused && options_.no_crossings && (crosses_surroundings(outline, added) || crosses_anything(added));
        if (refused || crossing) {
            for (const auto f : added)
                mesh_.delete_face(f, false);
            for (std::size_t k = outline.size(); k < corner.size(); ++k)
                mesh_.delete_vertex(corner[k], false);
            put_back(outline, old_faces, old_tile, old_gap);
            stats.refused += refused ? 1 : 0;
            return false;
        }
        for (const auto f : added) {
            if (tile_[f] >= 0)
                fans_[tile_[f]].push_back(f);
            touched_faces_.push_back(f);
            if (all_faces_)
                file_face(f);
        }
        touched_vertices_.insert(touched_vertices_.end(), corner.begin(), corner.end());
        created_.insert(created_.end(), corner.begin() + static_cast<std::ptrdiff_t>(outline.size()), corner.end());
        // The fan's own vertices inside the outline (its apex) are left without faces: remove them.
        for (const auto& corners : old_faces)
            for (const auto v : corners)
                if (!mesh_.status(v).deleted() && mesh_.is_isolated(v))
                    mesh_.delete_vertex(v, false);
        return true;
    }

    // The region's old faces added again, from the outline inwards (as the new ones were): a disc
    // that was there fits its outline again.
    void put_back(const std::vector<Mesh::VertexHandle>& outline, const std::vector<std::array<Mesh::VertexHandle, 3>>& faces,
                  const std::vector<int>& tiles, const std::vector<char>& gaps)
    {
        std::unordered_map<int, std::uint32_t> local;
        std::vector<Mesh::VertexHandle> vertex(outline.begin(), outline.end());
        for (std::uint32_t k = 0; k < outline.size(); ++k)
            local[outline[k].idx()] = k;
        std::vector<std::array<std::uint32_t, 3>> triangles;
        for (const auto& corners : faces) {
            std::array<std::uint32_t, 3> t{};
            for (std::size_t c = 0; c < 3; ++c) {
                const auto [it, added] = local.emplace(corners[c].idx(), static_cast<std::uint32_t>(vertex.size()));
                if (added)
                    vertex.push_back(corners[c]);
                t[c] = it->second;
            }
            triangles.push_back(t);
        }
        std::vector<std::size_t> order = attach_order(triangles, outline.size());
        const QuietOpenMesh quiet;
        for (const std::size_t k : order) {
            const auto f = mesh_.add_face(faces[k][0], faces[k][1], faces[k][2]);
            if (!f.is_valid())
                throw std::logic_error("refine_mesh: a region could not be put back as it was");
            tile_[f] = tiles[k];
            gap_[f] = gaps[k] != 0;
            touched_faces_.push_back(f); // a new handle: its normal is computed again (the same one)
        }
        if (order.size() != faces.size())
            throw std::logic_error("refine_mesh: a region could not be put back as it was");
    }

    // Whether a new face crosses one of the faces within two rings of the outline (bounding boxes
    // first, then the exact test of self_intersecting_faces).
    bool crosses_surroundings(const std::vector<Mesh::VertexHandle>& outline, const std::vector<Mesh::FaceHandle>& added)
    {
        // Faces are marked with this call's stamp (a fresh number per call: no clearing, no hashing).
        if (++stamp_ == 0) {
            std::fill(face_stamp_.begin(), face_stamp_.end(), 0u);
            stamp_ = 1;
        }
        face_stamp_.resize(mesh_.n_faces(), 0u);
        auto mark = [&](Mesh::FaceHandle f) {
            std::uint32_t& s = face_stamp_[static_cast<std::size_t>(f.idx())];
            const bool fresh = s != stamp_;
            s = stamp_;
            return fresh;
        };
        for (const auto f : added)
            mark(f);
        // The faces at the outline's vertices and at their neighbours (each vertex visited once).
        std::vector<Mesh::FaceHandle> around;
        vertex_stamp_.resize(mesh_.n_vertices(), 0u);
        if (stamp_ == 1)
            std::fill(vertex_stamp_.begin(), vertex_stamp_.end(), 0u);
        auto take_faces_at = [&](Mesh::VertexHandle w) {
            std::uint32_t& s = vertex_stamp_[static_cast<std::size_t>(w.idx())];
            if (s == stamp_)
                return;
            s = stamp_;
            for (const auto g : mesh_.vf_range(w))
                if (mark(g))
                    around.push_back(g);
        };
        for (const auto v : outline) {
            take_faces_at(v);
            for (const auto w : mesh_.vv_range(v))
                take_faces_at(w);
        }
        // Sort and sweep along x: every pair of boxes that overlap along x is met once, in
        // O((n + m) log(n + m) + pairs) instead of n × m box tests.
        struct Box
        {
            std::array<Vec3, 2> extent;
            Mesh::FaceHandle face;
        };
        auto boxes_of = [&](const std::vector<Mesh::FaceHandle>& faces) {
            std::vector<Box> boxes;
            boxes.reserve(faces.size());
            for (const auto f : faces) {
                const std::array<Vec3, 3> c = face_corners(mesh_, f);
                boxes.push_back({{min(min(c[0], c[1]), c[2]), max(max(c[0], c[1]), c[2])}, f});
            }
            std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.extent[0].x < b.extent[0].x; });
            return boxes;
        };
        const std::vector<Box> mine = boxes_of(added), theirs = boxes_of(around);
        auto crosses = [&](const Box& a, const Box& b) {
            return !(a.extent[1].y < b.extent[0].y || b.extent[1].y < a.extent[0].y || a.extent[1].z < b.extent[0].z ||
                     b.extent[1].z < a.extent[0].z || a.extent[1].x < b.extent[0].x || b.extent[1].x < a.extent[0].x) &&
                   faces_intersect(mesh_, a.face, b.face);
        };
        for (std::size_t i = 0, j = 0; i < mine.size() && j < theirs.size();) {
            if (mine[i].extent[0].x <= theirs[j].extent[0].x) {
                for (std::size_t k = j; k < theirs.size() && theirs[k].extent[0].x <= mine[i].extent[1].x; ++k)
                    if (crosses(mine[i], theirs[k]))
                        return true;
                ++i;
            } else {
                for (std::size_t k = i; k < mine.size() && mine[k].extent[0].x <= theirs[j].extent[1].x; ++k)
                    if (crosses(mine[k], theirs[j]))
                        return true;
                ++j;
            }
        }
        return false;
    }

    // Triangles in an order where each shares an edge with the outline or an earlier one (a breadth-
    // first walk from the outline). Shorter than `triangles` if some cannot be reached.
    static std::vector<std::size_t> attach_order(const std::vector<std::array<std::uint32_t, 3>>& triangles,
                                                 std::size_t outline_size)
    {
        auto key = [](std::uint32_t a, std::uint32_t b) {
            return a < b ? (std::uint64_t{a} << 32 | b) : (std::uint64_t{b} << 32 | a);
        };
        // (edge, triangle) pairs sorted: a triangle's edge partners are one range, in triangle order.
        std::vector<std::pair<std::uint64_t, std::size_t>> by_edge;
        by_edge.reserve(3 * triangles.size());
        for (std::size_t k = 0; k < triangles.size(); ++k)
            for (int i = 0; i < 3; ++i)
                by_edge.push_back({key(triangles[k][i], triangles[k][(i + 1) % 3]), k});
        std::sort(by_edge.begin(), by_edge.end());
        auto range_of = [&](std::uint64_t edge) {
            const auto first = std::lower_bound(by_edge.begin(), by_edge.end(), std::pair<std::uint64_t, std::size_t>{edge, 0});
            auto last = first;
            while (last != by_edge.end() && last->first == edge)
                ++last;
            return std::make_pair(first, last);
        };
        std::vector<char> placed(triangles.size(), 0);
        std::vector<std::size_t> order;
        order.reserve(triangles.size());
        for (std::uint32_t i = 0; i < outline_size; ++i) {
            const auto [first, last] = range_of(key(i, static_cast<std::uint32_t>((i + 1) % outline_size)));
            if (first == last)
                return {};
            for (auto it = first; it != last; ++it)
                if (!placed[it->second]) {
                    placed[it->second] = 1;
                    order.push_back(it->second);
                }
        }
        for (std::size_t head = 0; head < order.size(); ++head) {
            const auto& t = triangles[order[head]];
            for (int i = 0; i < 3; ++i) {
                const auto [first, last] = range_of(key(t[i], t[(i + 1) % 3]));
                for (auto it = first; it != last; ++it)
                    if (!placed[it->second]) {
                        placed[it->second] = 1;
                        order.push_back(it->second);
                    }
            }
        }
        return order;
    }

    // The descendant whose points make all three corners, or -1 (a face between descendants or on the outline).
    static std::int32_t owner_of(const std::array<std::uint32_t, 3>& t, const std::vector<NewPoint>& points,
                                 std::size_t outline_size)
    {
        std::int32_t owner = -1;
        for (const std::uint32_t k : t) {
            if (k < outline_size)
                return -1;
            const std::int32_t node = points[k - outline_size].node;
            if (owner >= 0 && node != owner)
                return -1;
            owner = node;
        }
        return owner;
    }

    // A new vertex's colour: its input point's, or for an apex the mean of (up to kFitPointsPerTile of)
    // its tile's points, as color_vertices gives a fan centre the colours around it.
    Mesh::Color colour_of(const NewPoint& p) const
    {
        const auto& colours = h_.cloud.colors;
        if (p.input_point >= 0 && static_cast<std::size_t>(p.input_point) < colours.size()) {
            const auto& c = colours[static_cast<std::size_t>(p.input_point)];
            return Mesh::Color(c[0], c[1], c[2], c[3]);
        }
        const Node& node = h_.nodes[static_cast<std::size_t>(p.node)];
        const std::size_t stride = std::max<std::size_t>(1, (node.end - node.begin) / kFitPointsPerTile);
        std::array<double, 4> sum{0, 0, 0, 0};
        double count = 0.0;
        for (std::size_t i = node.begin; i < node.end && i < colours.size(); i += stride) {
            for (std::size_t k = 0; k < 4; ++k)
                sum[k] += colours[i][k];
            count += 1.0;
        }
        if (count == 0.0)
            return Mesh::Color(255, 255, 255, 255);
        auto mean = [&](std::size_t k) { return static_cast<unsigned char>(std::lround(sum[k] / count)); };
        return Mesh::Color(mean(0), mean(1), mean(2), mean(3));
    }

    const Hierarchy& h_;
    Mesh& mesh_;
    const LocalRefineOptions& options_;
    const TileOptions tile_options_;
    OpenMesh::PropertyManager<OpenMesh::FPropHandleT<int>> tile_;
    OpenMesh::PropertyManager<OpenMesh::FPropHandleT<bool>> gap_;
    OpenMesh::PropertyManager<OpenMesh::VPropHandleT<int>> cluster_;
    std::unordered_map<std::int32_t, std::vector<Mesh::FaceHandle>> fans_;
    std::unordered_map<std::int32_t, std::vector<Mesh::VertexHandle>> vertices_; // by v:cluster
    std::vector<char> in_region_; // per face: in the region being refined
    std::vector<Mesh::FaceHandle> touched_faces_;     // new faces (update_touched_normals)
    std::vector<Mesh::VertexHandle> touched_vertices_; // their corners, outlines included
    std::vector<std::uint32_t> face_stamp_; // per face: the crossing test's call that last saw it
    std::vector<std::uint32_t> vertex_stamp_; // per vertex: the same, for the vertices whose faces were taken
    std::uint32_t stamp_ = 0;
    std::optional<BoxGrid> all_faces_; // every face, filed when first needed (file_all_faces)
    double all_faces_cell_ = 0.0;      // its cell size
    std::vector<Mesh::VertexHandle> created_; // vertices added (refit)
};

// What refine_mesh and coarsen_mesh check before any change.
void check_update(const Hierarchy& h, const MeshResult& result, const Cut& cut, const LocalRefineOptions& options,
                  const char* name)
{
    if (!(options.max_tilt_degrees > 0.0 && options.max_tilt_degrees <= 90.0))
        throw InvalidInput("LocalRefineOptions::max_tilt_degrees must be in (0, 90]");
    // Finite too: an infinite separation left out every descendant's point, and a refined sphere of 322
    // faces came back as 80 (the outlines alone, re-triangulated).
    if (!(options.min_separation >= 0.0) || !std::isfinite(options.min_separation))
        throw InvalidInput("LocalRefineOptions::min_separation must be a finite number >= 0");
    check_tile_options(options.tiles);
    // The options of a step meshed afresh, checked before the first step changes anything: a bad one
    // was found only when a step was meshed afresh, after the in-place step had changed `result` (QA
    // round 51: 335 -> 152 tiles), and its message named SurfaceOptions.
    try {
        check_mesh_options(options.remesh);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string(name) + ": LocalRefineOptions::remesh: " + e.what());
    }
    if (!(options.max_kept_share >= 0.0) || !std::isfinite(options.max_kept_share))
        throw InvalidInput("LocalRefineOptions::max_kept_share must be a finite number >= 0 (1 or more: never mesh afresh)");
    if (!(options.max_step_ratio >= 1.0)) // infinity: never
        throw InvalidInput("LocalRefineOptions::max_step_ratio must be at least 1 (infinity: never mesh afresh)");
    if (!OpenMesh::hasProperty<OpenMesh::FaceHandle, int>(result.mesh, kFaceTile) ||
        !OpenMesh::hasProperty<OpenMesh::FaceHandle, bool>(result.mesh, kFaceGap) ||
        !OpenMesh::hasProperty<OpenMesh::VertexHandle, int>(result.mesh, kVertexCluster))
        throw InvalidInput(std::string(name) + ": the mesh has no tile ids (v:cluster, f:tile, f:gap); pass a mesh_cut result");
    check_node_ids(h, cut);
    if (const std::string problem = cut_problem(h, cut); !problem.empty())
        throw InvalidInput(std::string(name) + ": the cut asked for is not a partition of the points: " + problem);
    check_node_ids(h, result.cut);
    // The mesh's own cut too: with a node listed twice or missing, the result's cut came out no
    // partition (the duplicate's run meshed twice, the missing node's points in no tile) without a word.
    if (const std::string problem = cut_problem(h, result.cut); !problem.empty())
        throw InvalidInput(std::string(name) + ": result.cut is not a partition of the points (" + problem + "); pass the MeshResult of "
                           "mesh_cut (or of an earlier refine_mesh, coarsen_mesh or update_mesh) with its cut unchanged");
    // And the mesh must be that cut's: every fan face names a node of it. A mesh of another cut (or
    // model) put in result.mesh was patched where its tile ids happened to match and came back with
    // result.cut claiming tiles it does not have.
    std::vector<char> in_cut(h.nodes.size(), 0);
    for (const std::int32_t node : result.cut)
        in_cut[static_cast<std::size_t>(node)] = 1;
    const auto check_tile = [&](const char* element, int index, int node) {
        if (node >= 0 && (static_cast<std::size_t>(node) >= in_cut.size() || !in_cut[static_cast<std::size_t>(node)]))
            throw InvalidInput(std::string(name) + ": " + element + " " + std::to_string(index) + " of result.mesh names tile " +
                               std::to_string(node) + ", which is not a node of result.cut: the mesh and its cut do not "
                               "belong together (pass the MeshResult of mesh_cut or of an earlier update unchanged)");
    };
    OpenMesh::FPropHandleT<int> tile;
    result.mesh.get_property_handle(tile, kFaceTile);
    for (const auto f : result.mesh.faces())
        check_tile("face", f.idx(), result.mesh.property(tile, f));
    // Every vertex names its tile's node too (or none), and the steps index nodes by it: a vertex whose
    // v:cluster lay beyond the nodes was read out of bounds when a step adopted an orphan tile (QA round
    // 51). And a vertex that is no point stops the step here rather than in the measurements after it.
    OpenMesh::VPropHandleT<int> cluster;
    result.mesh.get_property_handle(cluster, kVertexCluster);
    for (const auto v : result.mesh.vertices()) {
        check_tile("vertex", v.idx(), result.mesh.property(cluster, v));
        if (!is_finite(to_vec3(result.mesh.point(v))))
            throw InvalidInput(std::string(name) + ": vertex " + std::to_string(v.idx()) + " of result.mesh has a NaN or infinite coordinate");
    }
}

// The nodes of `cut` under `node` (all of its points), by first point; empty if `cut` is coarser there.
class NodesBelow
{
public:
    NodesBelow(const Hierarchy& h, const Cut& cut) : h_(h), by_begin_(cut)
    {
        std::sort(by_begin_.begin(), by_begin_.end(), [&](std::int32_t a, std::int32_t b) { return node(a).begin < node(b).begin; });
    }

    std::vector<std::int32_t> operator()(std::int32_t id) const
    {
        const Node& n = node(id);
        const auto first = std::partition_point(by_begin_.begin(), by_begin_.end(),
                                                [&](std::int32_t d) { return node(d).begin < n.begin; });
        std::vector<std::int32_t> run;
        std::size_t covered = 0;
        for (auto it = first; it != by_begin_.end() && node(*it).end <= n.end; ++it) {
            run.push_back(*it);
            covered += node(*it).end - node(*it).begin;
        }
        if (run.empty() || covered != n.end - n.begin || node(run.front()).begin != n.begin)
            return {};
        return run;
    }

private:
    const Node& node(std::int32_t id) const { return h_.nodes[static_cast<std::size_t>(id)]; }
    const Hierarchy& h_;
    std::vector<std::int32_t> by_begin_;
};

// For each node of `upper`, the nodes of `lower` under it; InvalidInput (prefix, node id, suffix) where
// `lower` is coarser than `upper`.
std::vector<std::vector<std::int32_t>> runs_below(const Hierarchy& h, const Cut& upper, const Cut& lower,
                                                  const char* prefix, const char* suffix)
{
    const NodesBelow below(h, lower);
    std::vector<std::vector<std::int32_t>> runs;
    runs.reserve(upper.size());
    for (const std::int32_t node : upper) {
        runs.push_back(below(node));
        if (runs.back().empty())
            throw InvalidInput(prefix + std::to_string(node) + suffix);
    }
    return runs;
}

void finish(const Hierarchy& h, MeshResult& result, LocalRefiner& refiner, Cut meshed, const LocalRefineOptions& options)
{
    sort_in_point_order(h, meshed);
    if (options.refit && options.fit) {
        FitOptions fit = options.remesh.fit;
        if (result.surface.height_field_used) {
            fit.vertical = true;
            fit.axis = result.surface.height_field_axis;
        }
        refiner.refit(fit);
    }
    refiner.update_touched_normals();
    result.mesh.garbage_collection();
    result.cut = std::move(meshed);
    result.tiles = result.cut.size();
}

// Of the nodes of two partitions, the ones with no ancestor among them (`upper`: the coarser of the
// two everywhere) or with no descendant among them (`lower`: the finer everywhere); each a partition.
Cut envelope(const Hierarchy& h, const Cut& a, const Cut& b, bool upper)
{
    std::vector<char> in(h.nodes.size(), 0), above(h.nodes.size(), 0); // above: an ancestor of one of them
    for (const Cut* cut : {&a, &b})
        for (const std::int32_t n : *cut) {
            in[static_cast<std::size_t>(n)] = 1;
            for (std::int32_t p = h.nodes[static_cast<std::size_t>(n)].parent; p >= 0 && !above[static_cast<std::size_t>(p)];
                 p = h.nodes[static_cast<std::size_t>(p)].parent)
                above[static_cast<std::size_t>(p)] = 1;
        }
    auto has_ancestor_in = [&](std::int32_t n) {
        for (std::int32_t p = h.nodes[static_cast<std::size_t>(n)].parent; p >= 0; p = h.nodes[static_cast<std::size_t>(p)].parent)
            if (in[static_cast<std::size_t>(p)])
                return true;
        return false;
    };
    Cut out;
    for (const Cut* cut : {&a, &b})
        for (const std::int32_t n : *cut) {
            const bool keep = upper ? !has_ancestor_in(n) : !above[static_cast<std::size_t>(n)];
            if (keep && in[static_cast<std::size_t>(n)] == 1) {
                in[static_cast<std::size_t>(n)] = 2; // taken once (still counts as in)
                out.push_back(n);
            }
        }
    return out;
}

} // namespace

namespace {

// For each node of the mesh's cut, the nodes of `finer` under it; InvalidInput where `finer` is coarser.
std::vector<std::vector<std::int32_t>> refine_runs(const Hierarchy& h, const Cut& meshed, const Cut& finer)
{
    return runs_below(h, meshed, finer, "refine_mesh: node ",
                      " of the mesh's cut is finer than the cut asked for (refine_mesh only refines; coarsen_mesh coarsens)");
}

// For each node of `coarser`, the nodes of the mesh's cut under it; InvalidInput where `coarser` is finer.
std::vector<std::vector<std::int32_t>> coarsen_runs(const Hierarchy& h, const Cut& coarser, const Cut& meshed)
{
    return runs_below(h, coarser, meshed, "coarsen_mesh: node ",
                      " of the cut asked for is finer than the mesh's cut (coarsen_mesh only coarsens; refine_mesh refines)");
}

// `runs`: refine_runs(h, result.cut, finer).
LocalRefineStats refine_in_place(const Hierarchy& h, MeshResult& result, const Cut& finer,
                                 const std::vector<std::vector<std::int32_t>>& runs, const LocalRefineOptions& options)
{
    std::vector<std::int32_t> changing;
    for (std::size_t k = 0; k < result.cut.size(); ++k)
        if (runs[k].size() != 1 || runs[k].front() != result.cut[k])
            changing.push_back(result.cut[k]);
    LocalRefineStats stats;
    LocalRefiner refiner(h, result, options, changing);
    Cut meshed, fresh;
    meshed.reserve(finer.size());
    for (std::size_t k = 0; k < result.cut.size(); ++k) {
        const std::int32_t node = result.cut[k];
        const std::vector<std::int32_t>& run = runs[k];
        if (run.size() == 1 && run.front() == node) {
            meshed.push_back(node);
            continue;
        }
        switch (refiner.refine(node, run, stats)) {
        case LocalRefiner::Outcome::refined:
            ++stats.refined;
            meshed.insert(meshed.end(), run.begin(), run.end());
            fresh.insert(fresh.end(), run.begin(), run.end());
            break;
        case LocalRefiner::Outcome::absent:
            ++stats.absent;
            meshed.insert(meshed.end(), run.begin(), run.end());
            fresh.insert(fresh.end(), run.begin(), run.end());
            break;
        case LocalRefiner::Outcome::kept:
            ++stats.kept;
            meshed.push_back(node);
            break;
        }
    }
    refiner.adopt_orphans(fresh, stats);
    finish(h, result, refiner, std::move(meshed), options);
    return stats;
}

// `runs`: coarsen_runs(h, coarser, result.cut).
LocalRefineStats coarsen_in_place(const Hierarchy& h, MeshResult& result, const Cut& coarser,
                                  const std::vector<std::vector<std::int32_t>>& runs, const LocalRefineOptions& options)
{
    std::vector<std::int32_t> changing;
    for (std::size_t k = 0; k < coarser.size(); ++k)
        if (runs[k].size() != 1 || runs[k].front() != coarser[k])
            changing.insert(changing.end(), runs[k].begin(), runs[k].end());
    LocalRefineStats stats;
    LocalRefiner refiner(h, result, options, changing);
    Cut meshed, fresh;
    meshed.reserve(result.cut.size());
    for (std::size_t k = 0; k < coarser.size(); ++k) {
        const std::int32_t node = coarser[k];
        const std::vector<std::int32_t>& run = runs[k];
        if (run.size() == 1 && run.front() == node) {
            meshed.push_back(node);
            continue;
        }
        switch (refiner.coarsen(node, run, stats)) {
        case LocalRefiner::Outcome::refined: // re-triangulated (as the coarser tile)
            ++stats.coarsened;
            meshed.push_back(node);
            fresh.push_back(node);
            break;
        case LocalRefiner::Outcome::absent:
            ++stats.absent;
            meshed.push_back(node);
            fresh.push_back(node);
            break;
        case LocalRefiner::Outcome::kept:
            ++stats.kept;
            meshed.insert(meshed.end(), run.begin(), run.end());
            break;
        }
    }
    refiner.adopt_orphans(fresh, stats);
    finish(h, result, refiner, std::move(meshed), options);
    return stats;
}

// The nodes of `cut` that are not nodes of `other`: how many, and their points.
struct CutDifference
{
    std::size_t nodes = 0, points = 0;
};

CutDifference not_in(const Hierarchy& h, const Cut& cut, const Cut& other)
{
    std::vector<char> in_other(h.nodes.size(), 0);
    for (const std::int32_t n : other)
        in_other[static_cast<std::size_t>(n)] = 1;
    CutDifference d;
    for (const std::int32_t n : cut)
        if (!in_other[static_cast<std::size_t>(n)]) {
            ++d.nodes;
            d.points += h.nodes[static_cast<std::size_t>(n)].count();
        }
    return d;
}

// Runs an in-place step towards `target`, or meshes `target` afresh: at once where the step replaces
// each changing tile by LocalRefineOptions::max_step_ratio tiles or more on average (or merges as many
// into one), after the step where the tiles it left as they were hold more than max_kept_share of the
// points whose tiles were to change.
template <typename Step>
LocalRefineStats step_or_remesh(const Hierarchy& h, MeshResult& result, const Cut& target, const LocalRefineOptions& options,
                                const Step& step)
{
    const auto remesh = [&](LocalRefineStats stats) {
        stats.faces_removed = result.mesh.n_faces();
        result = mesh_cut(h, target, options.remesh);
        stats.faces_added = result.mesh.n_faces();
        stats.remeshed = true;
        stats.kept = 0;
        return stats;
    };
    const CutDifference leaving = not_in(h, result.cut, target); // the tiles to change
    const auto old_tiles = static_cast<double>(leaving.nodes), new_tiles = static_cast<double>(not_in(h, target, result.cut).nodes);
    if (old_tiles > 0.0 && new_tiles > 0.0 && std::max(old_tiles / new_tiles, new_tiles / old_tiles) >= options.max_step_ratio)
        return remesh({});
    const LocalRefineStats stats = step();
    const std::size_t short_of = stats.kept > 0 ? not_in(h, result.cut, target).points : 0;
    if (short_of > 0 && static_cast<double>(short_of) > options.max_kept_share * static_cast<double>(leaving.points))
        return remesh(stats);
    return stats;
}

} // namespace

LocalRefineStats refine_mesh(const Hierarchy& h, MeshResult& result, const Cut& finer, const LocalRefineOptions& options)
{
    check_update(h, result, finer, options, "refine_mesh");
    // The direction is checked here, before a step too large is meshed afresh.
    const std::vector<std::vector<std::int32_t>> runs = refine_runs(h, result.cut, finer);
    return step_or_remesh(h, result, finer, options, [&] { return refine_in_place(h, result, finer, runs, options); });
}

LocalRefineStats coarsen_mesh(const Hierarchy& h, MeshResult& result, const Cut& coarser, const LocalRefineOptions& options)
{
    check_update(h, result, coarser, options, "coarsen_mesh");
    // The direction is checked here, before a step too large is meshed afresh.
    const std::vector<std::vector<std::int32_t>> runs = coarsen_runs(h, coarser, result.cut);
    return step_or_remesh(h, result, coarser, options, [&] { return coarsen_in_place(h, result, coarser, runs, options); });
}

LocalRefineStats update_mesh(const Hierarchy& h, MeshResult& result, const Cut& cut, const LocalRefineOptions& options)
{
    check_update(h, result, cut, options, "update_mesh");
    return step_or_remesh(h, result, cut, options, [&] {
        // First merge where the new cut is coarser (to the coarser of the two cuts everywhere), then
        // split where it is finer than what is meshed then (tiles kept by the first step stay as they are).
        const Cut upper = envelope(h, result.cut, cut, true);
        const LocalRefineStats merged = coarsen_in_place(h, result, upper, coarsen_runs(h, upper, result.cut), options);
        const Cut lower = envelope(h, result.cut, cut, false);
        LocalRefineStats stats = refine_in_place(h, result, lower, refine_runs(h, result.cut, lower), options);
        stats.coarsened += merged.coarsened;
        stats.kept += merged.kept;
        stats.absent += merged.absent;
        stats.adopted += merged.adopted;
        stats.refused += merged.refused;
        stats.faces_removed += merged.faces_removed;
        stats.faces_added += merged.faces_added;
        return stats;
    });
}

} // namespace mrt
