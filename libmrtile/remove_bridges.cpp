// Beyond the paper: tubes of gap faces that join two surfaces across the empty space between them, cut
// (see remove_bridges.h). The paper's T2 prunes its Delaunay triangles by their size alone, and our
// surface stage triangulates each tile's neighbourhood in the tile's plane, where a surface facing it a
// few spacings away projects among its own points; the alpha bound then lets through faces about 6
// spacings long. Where the front strings such faces into a tube, the mesh joins what the sample keeps
// apart. Judged after the surface, on the faces themselves: a tube spans space with no points in it.

#include "libmrtile/remove_bridges.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace mrt {
namespace {

// See faces_across.
constexpr double kMinMidpointShare = 0.15;
constexpr int kMaxSpotSteps = 32;

} // namespace

void check_bridge_options(const BridgeOptions& o)
{
    if (o.max_loop_edges != 0 && o.max_loop_edges != 3 && o.max_loop_edges != 4)
        throw InvalidInput("BridgeOptions::max_loop_edges must be 0 (off), 3 or 4");
    for (const double value : {o.min_edge_spacings, o.reach_spacings, o.off_share})
        if (!(value > 0.0) || !std::isfinite(value))
            throw InvalidInput("BridgeOptions: min_edge_spacings, reach_spacings and off_share must be positive and finite");
}

namespace {

// A set of faces to take out and the loops (border half-edges of the set, in order) to cap.
struct Tube
{
    std::vector<Mesh::FaceHandle> faces;
    std::vector<std::vector<Mesh::HalfedgeHandle>> loops;
};

class BridgeCutter
{
public:
    BridgeCutter(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of, const BridgeOptions& o)
        : mesh_(mesh), h_(h), spacing_of_(spacing_of), o_(o)
    {
        if (!mesh_.get_property_handle(cluster_, kVertexCluster) || !mesh_.get_property_handle(tile_, kFaceTile) ||
            !mesh_.get_property_handle(gap_, kFaceGap))
            throw InvalidInput("remove_bridges: the mesh lacks the v:cluster, f:tile or f:gap property (mesh.h)");
    }

    BridgeStats run()
    {
        if (o_.max_loop_edges == 0)
            return stats_;
        across_.assign(mesh_.n_faces(), 0);
        bool any = false;
        for (const Mesh::FaceHandle f : faces_across()) {
            across_[static_cast<std::size_t>(f.idx())] = 1;
            any = true;
        }
        if (!any)
            return stats_;
        std::vector<char> visited(across_.size(), 0);
        bool cut_any = false;
        for (std::size_t i = 0; i < across_.size(); ++i) { // the faces as they were: caps come after them
            const Mesh::FaceHandle f(static_cast<int>(i));
            if (!is_across(f) || visited[i])
                continue;
            Tube tube;
            collect(f, visited, tube.faces);
            if (as_tube(tube) && cut(tube))
                cut_any = true;
        }
        if (cut_any)
            mesh_.garbage_collection();
        return stats_;
    }

private:
    bool is_across(Mesh::FaceHandle f) const
    {
        const auto i = static_cast<std::size_t>(f.idx());
        return f.is_valid() && i < across_.size() && across_[i] && !mesh_.status(f).deleted();
    }

    // The spacing a gap face is judged by: the largest of its corners' tiles' (a coarse tile's wider
    // spacing makes its faces no candidates); 0 for a face that is no gap face or has a corner of no
    // tile with a spacing.
    double spacing_of_gap_face(Mesh::FaceHandle f) const
    {
        if (!mesh_.property(gap_, f))
            return 0.0;
        double spacing = 0.0;
        for (const Mesh::VertexHandle v : mesh_.fv_range(f)) {
            const auto it = spacing_of_.find(mesh_.property(cluster_, v));
            if (it == spacing_of_.end() || !(it->second > 0.0))
                return 0.0;
            spacing = std::max(spacing, it->second);
        }
        return spacing;
    }

    // The gap faces, in face order, that span empty space: an edge over min_edge_spacings spacings,
    // and off_share of the area farther than reach_spacings from every point, judged at spots on a
    // barycentric grid a third of the reach apart (at most kMaxSpotSteps to an edge). Only faces with
    // a long edge whose midpoint lies off the sample by kMinMidpointShare of the face's longest edge
    // are judged: a face across the gap between two surfaces has an edge from one to the other, its
    // middle half the gap from both (0.44-0.50 of the longest edge in the tubes of QA round 80), while a
    // chord of a curved sampled surface lies off it by its sagitta, L / 8r of its length L. Without
    // it a coarse cut of a dense sample, all long gap faces thousands of spots each, spent most of its
    // meshing here (the 4M-point torus: 100 tiles 1.9 s of 2.1, 1,000 tiles 1.1 of 2.3). Midpoints
    // and spots are asked in two batches whether a point lies within their radius (no box beyond it
    // opened: a spot off the sample costs a few nodes), each from its face's first corner's tile's node.
    std::vector<Mesh::FaceHandle> faces_across()
    {
        // Each long edge's midpoint, asked for a point within the larger of the reach and
        // kMinMidpointShare of its face's longest edge.
        struct LongFace
        {
            Mesh::FaceHandle face;
            std::array<Vec3, 3> corners;
            double reach;
            std::int32_t node; // its first corner's tile's
        };
        std::vector<LongFace> long_faces;
        std::vector<std::size_t> first_middle{0};
        std::vector<Vec3> middles;
        std::vector<double> radii;
        std::vector<std::int32_t> first_nodes;
        for (const Mesh::FaceHandle f : mesh_.faces()) {
            const double spacing = spacing_of_gap_face(f);
            if (!(spacing > 0.0))
                continue;
            const std::array<Vec3, 3> p = face_corners(mesh_, f);
            const double reach = o_.reach_spacings * spacing;
            const double longest = std::max({distance(p[0], p[1]), distance(p[1], p[2]), distance(p[2], p[0])});
            const std::int32_t node = mesh_.property(cluster_, *mesh_.cfv_begin(f));
            for (int k = 0; k < 3; ++k)
                if (distance(p[k], p[(k + 1) % 3]) > o_.min_edge_spacings * spacing) {
                    middles.push_back((p[k] + p[(k + 1) % 3]) * 0.5);
                    radii.push_back(std::max(reach, kMinMidpointShare * longest));
                    first_nodes.push_back(node);
                }
            if (middles.size() == first_middle.back())
                continue;
            long_faces.push_back({f, p, reach, node});
            first_middle.push_back(middles.size());
        }
        stats_.long_faces = long_faces.size();
        if (long_faces.empty())
            return {};
        const std::vector<char> middle_near = has_point_within(h_, middles, radii, &first_nodes);

        // The spots of the faces with a midpoint off the sample (centres of equal sub-triangles, as
        // close_covered_holes judges a face's share off the sample), asked for a point within the reach.
        std::vector<const LongFace*> judged;
        std::vector<std::size_t> first_spot{0};
        std::vector<Vec3> spots;
        radii.clear();
        first_nodes.clear();
        for (std::size_t i = 0; i < long_faces.size(); ++i) {
            if (std::all_of(middle_near.begin() + static_cast<std::ptrdiff_t>(first_middle[i]),
                            middle_near.begin() + static_cast<std::ptrdiff_t>(first_middle[i + 1]), [](char near) { return near != 0; }))
                continue;
            const LongFace& l = long_faces[i];
            visit_subtriangle_centres(l.corners[0], l.corners[1], l.corners[2], l.reach / 3.0, kMaxSpotSteps,
                                      [&](const Vec3& spot) { spots.push_back(spot); });
            radii.resize(spots.size(), l.reach);
            first_nodes.resize(spots.size(), l.node);
            judged.push_back(&l);
            first_spot.push_back(spots.size());
        }
        stats_.judged = judged.size();
        const std::vector<char> spot_near = has_point_within(h_, spots, radii, &first_nodes);
        std::vector<Mesh::FaceHandle> across;
        for (std::size_t i = 0; i < judged.size(); ++i) {
            std::size_t off = 0;
            for (std::size_t s = first_spot[i]; s < first_spot[i + 1]; ++s)
                off += spot_near[s] ? 0 : 1;
            const auto spots_of_face = static_cast<double>(first_spot[i + 1] - first_spot[i]);
            const std::array<Vec3, 3>& p = judged[i]->corners;
            const double area = 0.5 * norm(cross(p[1] - p[0], p[2] - p[0]));
            if (area > 0.0 && area * (static_cast<double>(off) / spots_of_face) >= o_.off_share * area)
                across.push_back(judged[i]->face);
        }
        return across;
    }

    // The faces across empty space connected to `start` through edges.
    void collect(Mesh::FaceHandle start, std::vector<char>& visited, std::vector<Mesh::FaceHandle>& faces) const
    {
        std::vector<Mesh::FaceHandle> stack{start};
        visited[static_cast<std::size_t>(start.idx())] = 1;
        while (!stack.empty()) {
            const Mesh::FaceHandle f = stack.back();
            stack.pop_back();
            faces.push_back(f);
            for (const Mesh::FaceHandle g : mesh_.ff_range(f))
                if (is_across(g) && !visited[static_cast<std::size_t>(g.idx())]) {
                    visited[static_cast<std::size_t>(g.idx())] = 1;
                    stack.push_back(g);
                }
        }
    }

    // Whether the faces form an annulus with two short loops, each bordering faces outside it on
    // every edge; fills tube.loops.
    bool as_tube(Tube& tube) const
    {
        std::unordered_set<int> vertices, edges;
        std::unordered_map<int, Mesh::HalfedgeHandle> border_from; // a border half-edge by its start
        for (const Mesh::FaceHandle f : tube.faces)
            for (const Mesh::HalfedgeHandle he : mesh_.fh_range(f)) {
                vertices.insert(mesh_.to_vertex_handle(he).idx());
                edges.insert(mesh_.edge_handle(he).idx());
                const Mesh::FaceHandle outside = mesh_.opposite_face_handle(he);
                if (is_across(outside))
                    continue;
                if (!outside.is_valid())
                    return false; // the mesh's own border: a tube hangs between two surfaces
                if (!border_from.emplace(mesh_.from_vertex_handle(he).idx(), he).second)
                    return false; // two border edges leave one vertex: a pinch, no simple loop
            }
        const long euler = static_cast<long>(vertices.size()) - static_cast<long>(edges.size()) + static_cast<long>(tube.faces.size());
        if (euler != 0)
            return false;
        std::unordered_set<int> used;
        for (const auto& start : border_from) {
            const Mesh::HalfedgeHandle first = start.second;
            if (used.count(first.idx()))
                continue;
            std::vector<Mesh::HalfedgeHandle> loop;
            Mesh::HalfedgeHandle he = first;
            while (loop.size() <= o_.max_loop_edges) {
                used.insert(he.idx());
                loop.push_back(he);
                const auto next = border_from.find(mesh_.to_vertex_handle(he).idx());
                if (next == border_from.end())
                    return false;
                he = next->second;
                if (he == first)
                    break;
            }
            if (he != first || loop.size() < 3 || loop.size() > o_.max_loop_edges)
                return false;
            // From its smallest half-edge on (the map's order is not fixed; the caps' corners are).
            std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end(), [](auto x, auto y) { return x.idx() < y.idx(); }),
                        loop.end());
            tube.loops.push_back(std::move(loop));
            if (tube.loops.size() > 2)
                return false;
        }
        std::sort(tube.loops.begin(), tube.loops.end(), [](const auto& a, const auto& b) { return a[0].idx() < b[0].idx(); });
        return tube.loops.size() == 2;
    }

    // The cap of a loop: its corners in the loop's order, as one triangle or two across the shorter
    // diagonal that is no edge yet. Empty where none fits or a face would have no area.
    std::vector<std::array<Mesh::VertexHandle, 3>> cap_of(const std::vector<Mesh::HalfedgeHandle>& loop) const
    {
        std::vector<Mesh::VertexHandle> v;
        for (const Mesh::HalfedgeHandle he : loop)
            v.push_back(mesh_.from_vertex_handle(he));
        std::vector<std::array<Mesh::VertexHandle, 3>> cap;
        if (v.size() == 3) {
            cap.push_back({v[0], v[1], v[2]});
        } else {
            const auto point = [&](Mesh::VertexHandle x) { return to_vec3(mesh_.point(x)); };
            std::array<std::size_t, 2> order{0, 1}; // the diagonal from v[k] to v[k + 2]
            if (distance(point(v[1]), point(v[3])) < distance(point(v[0]), point(v[2])))
                order = {1, 0};
            for (const std::size_t k : order) {
                const Mesh::VertexHandle a = v[k], b = v[k + 1], c = v[k + 2], d = v[(k + 3) % 4];
                if (mesh_.find_halfedge(a, c).is_valid())
                    continue;
                cap = {{a, b, c}, {a, c, d}};
                break;
            }
        }
        for (const auto& t : cap) {
            const Vec3 a = to_vec3(mesh_.point(t[0])), b = to_vec3(mesh_.point(t[1])), c = to_vec3(mesh_.point(t[2]));
            if (!(norm(cross(b - a, c - a)) > 0.0))
                return {};
        }
        return cap;
    }

    // Takes the tube out and caps its loops; puts it back as it was where a cap is refused.
    bool cut(const Tube& tube)
    {
        std::vector<std::array<Mesh::VertexHandle, 3>> caps;
        for (const auto& loop : tube.loops) {
            // One face outside across every edge of a 3-edge loop: the cap would be its twin, a closed
            // pair of faces.
            const Mesh::FaceHandle outside = mesh_.opposite_face_handle(loop[0]);
            if (std::all_of(loop.begin(), loop.end(), [&](Mesh::HalfedgeHandle he) { return mesh_.opposite_face_handle(he) == outside; }))
                return false;
            const auto cap = cap_of(loop);
            if (cap.empty())
                return false;
            caps.insert(caps.end(), cap.begin(), cap.end());
        }
        struct Removed
        {
            std::array<Mesh::VertexHandle, 3> corners;
            int tile;
            bool gap;
        };
        std::vector<Removed> taken;
        for (const Mesh::FaceHandle f : tube.faces) {
            taken.push_back({face_vertices(mesh_, f), mesh_.property(tile_, f), mesh_.property(gap_, f)});
            mesh_.delete_face(f, false);
        }
        std::vector<Mesh::FaceHandle> added;
        for (const auto& t : caps) {
            const Mesh::FaceHandle f = mesh_.add_face(t[0], t[1], t[2]);
            if (!f.is_valid())
                break; // refused (a complex edge): undone below
            added.push_back(f);
        }
        if (added.size() < caps.size()) {
            for (const Mesh::FaceHandle f : added)
                mesh_.delete_face(f, false);
            for (auto it = taken.rbegin(); it != taken.rend(); ++it) {
                const Mesh::FaceHandle f = mesh_.add_face(it->corners[0], it->corners[1], it->corners[2]);
                assert(f.is_valid()); // its place is free again
                if (!f.is_valid())
                    continue;
                mesh_.property(tile_, f) = it->tile;
                mesh_.property(gap_, f) = it->gap;
            }
            return false;
        }
        for (const Mesh::FaceHandle f : added) {
            mesh_.property(tile_, f) = -1;
            mesh_.property(gap_, f) = true;
        }
        for (const Removed& r : taken)
            for (const Mesh::VertexHandle v : r.corners)
                if (!mesh_.status(v).deleted() && mesh_.is_isolated(v))
                    mesh_.delete_vertex(v, false);
        ++stats_.tubes;
        stats_.removed += taken.size();
        stats_.caps += added.size();
        return true;
    }

    Mesh& mesh_;
    const Hierarchy& h_;
    const std::unordered_map<std::int32_t, double>& spacing_of_;
    const BridgeOptions& o_;
    OpenMesh::VPropHandleT<int> cluster_;
    OpenMesh::FPropHandleT<int> tile_;
    OpenMesh::FPropHandleT<bool> gap_;
    std::vector<char> across_; // by face index, at the start: faces across empty space
    BridgeStats stats_;
};

} // namespace

BridgeStats remove_bridges(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
                           const BridgeOptions& options)
{
    check_bridge_options(options);
    return BridgeCutter(mesh, h, spacing_of, options).run();
}

} // namespace mrt
