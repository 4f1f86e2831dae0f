// Beyond the paper: the notches that alpha pruning leaves in an open border between two tiles at the
// sample's outline, filled where the input points cover them (see fill_notches.h). The paper's T2
// prunes the long, flat faces there as it prunes faces across real gaps; the points tell them apart.

#include "libmrtile/fill_notches.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/union_find.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace mrt {

namespace {

void check_options(const NotchOptions& o)
{
    if (!(o.min_depth_spacings >= 0.0) || !std::isfinite(o.min_depth_spacings) || !(o.cover_spacings > 0.0) ||
        !std::isfinite(o.cover_spacings))
        throw InvalidInput("NotchOptions: min_depth_spacings must be >= 0 and cover_spacings > 0, both finite");
    if (!(o.max_turn_degrees > 0.0 && o.max_turn_degrees <= 90.0))
        throw InvalidInput("NotchOptions::max_turn_degrees must lie in (0, 90]");
    if (!(o.min_angle_degrees >= 0.0 && o.min_angle_degrees < 180.0))
        throw InvalidInput("NotchOptions::min_angle_degrees must lie in [0, 180)");
    if (o.rounds < 0 || o.rounds > 64)
        throw InvalidInput("NotchOptions::rounds must lie in [0, 64]");
}

// Whether every spot of triangle t (a barycentric grid at most `reach` apart) has an input point within
// `reach` in the triangle's plane and within `reach` of it across, and the points over the triangle lie
// in one layer: a thin part's other side a few spacings away (the bunny's ear at a coarse cut, whose
// rim loop three faces closed over its back's points) is no surface to fill in.
bool points_cover(const Hierarchy& h, const std::array<Vec3, 3>& t, double reach)
{
    const Vec3 normal = normalized(cross(t[1] - t[0], t[2] - t[0]));
    const double layer = 4.0 * reach;
    BoundingBox box = triangle_box(t);
    box.min = box.min - Vec3{layer, layer, layer};
    box.max = box.max + Vec3{layer, layer, layer};
    const Vec3 u = normalized(t[1] - t[0]), v = cross(normal, u);
    // The points near the plane, on a 2D grid of cells `reach` wide.
    std::unordered_map<std::uint64_t, std::vector<std::array<double, 2>>> cells;
    const auto cell_key = [&](double x, double y) {
        const auto cx = static_cast<std::int64_t>(std::floor(x / reach)), cy = static_cast<std::int64_t>(std::floor(y / reach));
        return (static_cast<std::uint64_t>(cx) & 0xffffffffu) << 32 | (static_cast<std::uint64_t>(cy) & 0xffffffffu);
    };
    // Over the triangle: on its plane, or off it (barycentric coordinates of the projection).
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    const double d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), det = d11 * d22 - d12 * d12;
    const auto over = [&](const Vec3& d) {
        const double p1 = dot(d, e1), p2 = dot(d, e2);
        const double b1 = (d22 * p1 - d12 * p2) / det, b2 = (d11 * p2 - d12 * p1) / det;
        return b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0;
    };
    std::size_t on = 0, off = 0;
    for (const std::uint32_t i : points_in_box(h, box)) {
        const Vec3 d = h.cloud.positions[i] - t[0];
        const double across = std::abs(dot(d, normal));
        if (across > layer)
            continue;
        if (across > reach) {
            off += over(d) ? 1 : 0;
            continue;
        }
        on += over(d) ? 1 : 0;
        const double x = dot(d, u), y = dot(d, v);
        cells[cell_key(x, y)].push_back({x, y});
    }
    if (!(det > 0.0) || 20 * off > on) // more than 5% off the plane: another layer, or a curved part
        return false;
    const auto covered = [&](const Vec3& spot) {
        const Vec3 d = spot - t[0];
        const double x = dot(d, u), y = dot(d, v);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy) {
                const auto it = cells.find(cell_key(x + dx * reach, y + dy * reach));
                if (it == cells.end())
                    continue;
                for (const auto& p : it->second)
                    if ((p[0] - x) * (p[0] - x) + (p[1] - y) * (p[1] - y) <= reach * reach)
                        return true;
            }
        return false;
    };
    return all_triangle_spots(t[0], t[1], t[2], reach, 200, covered);
}

class NotchFiller
{
public:
    NotchFiller(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of, const NotchOptions& o)
        : mesh_(mesh), h_(h), spacing_of_(spacing_of), o_(o), min_cos_(std::cos(o.max_turn_degrees * M_PI / 180.0)),
          min_angle_cos_(std::cos(o.min_angle_degrees * M_PI / 180.0)),
          grid_(mean_edge_length(mesh) * 2.0)
    {
        if (!mesh_.get_property_handle(cluster_, kVertexCluster) || !mesh_.get_property_handle(tile_, kFaceTile) ||
            !mesh_.get_property_handle(gap_, kFaceGap))
            throw InvalidInput("fill_notches: the mesh lacks the v:cluster / f:tile / f:gap properties (mesh.h)");
        for (const auto f : mesh_.faces())
            grid_.insert(static_cast<std::uint32_t>(f.idx()), triangle_box(corners(f)));
    }

    std::size_t run()
    {
        std::size_t added = 0;
        for (int round = 0; round < o_.rounds; ++round) {
            std::size_t now = 0;
            // Border half-edges of outlines in index order; a face added changes only its own border,
            // and each half-edge is looked at as it is when its turn comes.
            const std::vector<char> outline = outline_halfedges();
            const std::size_t count = mesh_.n_halfedges();
            for (std::size_t k = 0; k < count; ++k) {
                const Mesh::HalfedgeHandle in(static_cast<int>(k));
                if (!outline[k] || mesh_.status(mesh_.edge_handle(in)).deleted() || !mesh_.is_boundary(in))
                    continue;
                now += try_notch(in) ? 1 : 0;
            }
            added += now;
            if (now == 0)
                break;
        }
        return added;
    }

private:
    // The border half-edges of each piece's longest loop, its outline. The other loops are holes, which
    // hole filling judged whole (surface_holes.cpp); a notch at a hole's rim (a building's unsampled
    // walls in a terrain) filled there folded in the fit: 49 -> 75 crossing pairs on QA round 32's town.
    std::vector<char> outline_halfedges() const
    {
        UnionFind pieces(mesh_.n_vertices());
        for (const auto e : mesh_.edges()) {
            const auto h = mesh_.halfedge_handle(e, 0);
            pieces.unite(static_cast<std::uint32_t>(mesh_.from_vertex_handle(h).idx()),
                         static_cast<std::uint32_t>(mesh_.to_vertex_handle(h).idx()));
        }
        std::vector<int> loop_of(mesh_.n_halfedges(), -1);
        std::vector<double> length;
        std::vector<std::uint32_t> piece;
        for (const auto start : mesh_.halfedges()) {
            if (!mesh_.is_boundary(start) || loop_of[static_cast<std::size_t>(start.idx())] >= 0)
                continue;
            const int loop = static_cast<int>(length.size());
            double sum = 0.0;
            Mesh::HalfedgeHandle h = start;
            for (std::size_t steps = 0; steps <= mesh_.n_halfedges(); ++steps) {
                loop_of[static_cast<std::size_t>(h.idx())] = loop;
                sum += mesh_.calc_edge_length(h);
                h = mesh_.next_halfedge_handle(h);
                if (h == start || loop_of[static_cast<std::size_t>(h.idx())] >= 0)
                    break;
            }
            length.push_back(sum);
            piece.push_back(pieces.find(static_cast<std::uint32_t>(mesh_.from_vertex_handle(start).idx())));
        }
        std::unordered_map<std::uint32_t, int> longest; // piece -> loop (the first of equal lengths)
        for (int l = 0; l < static_cast<int>(length.size()); ++l) {
            const auto it = longest.find(piece[static_cast<std::size_t>(l)]);
            if (it == longest.end() || length[static_cast<std::size_t>(l)] > length[static_cast<std::size_t>(it->second)])
                longest[piece[static_cast<std::size_t>(l)]] = l;
        }
        std::vector<char> outline(mesh_.n_halfedges(), 0);
        for (std::size_t k = 0; k < loop_of.size(); ++k)
            if (loop_of[k] >= 0) {
                const auto it = longest.find(piece[static_cast<std::size_t>(loop_of[k])]);
                outline[k] = it != longest.end() && it->second == loop_of[k];
            }
        return outline;
    }

    std::array<Vec3, 3> corners(Mesh::FaceHandle f) const
    {
        std::array<Vec3, 3> c;
        int k = 0;
        for (const auto v : mesh_.fv_range(f))
            c[static_cast<std::size_t>(k++)] = to_vec3(mesh_.point(v));
        return c;
    }

    // The spacing of the points of v's node from their own spread (node_spacing); infinity where v
    // names no node.
    double own_spacing(Mesh::VertexHandle v) const
    {
        const int id = mesh_.property(cluster_, v);
        if (id < 0 || static_cast<std::size_t>(id) >= h_.nodes.size())
            return std::numeric_limits<double>::infinity();
        return node_spacing(h_.nodes[static_cast<std::size_t>(id)]);
    }

    double spacing(Mesh::VertexHandle v) const
    {
        const auto it = spacing_of_.find(mesh_.property(cluster_, v));
        return it == spacing_of_.end() ? 0.0 : it->second;
    }

    // The border half-edges a -> c (`in`) and c -> b: face (a, c, b) when it fills a notch.
    bool try_notch(Mesh::HalfedgeHandle in)
    {
        const Mesh::HalfedgeHandle out = mesh_.next_halfedge_handle(in);
        const Mesh::VertexHandle a = mesh_.from_vertex_handle(in), c = mesh_.to_vertex_handle(in), b = mesh_.to_vertex_handle(out);
        if (a == b || !mesh_.is_boundary(out))
            return false;
        const double s = spacing(c);
        if (!(s > 0.0))
            return false;
        const Vec3 pa = to_vec3(mesh_.point(a)), pc = to_vec3(mesh_.point(c)), pb = to_vec3(mesh_.point(b));
        const Vec3 ab = pb - pa;
        const double base = norm(ab);
        if (!(base > 0.0))
            return false;
        const double depth = norm(cross(pc - pa, ab)) / base;
        if (depth <= o_.min_depth_spacings * std::min(s, own_spacing(c)))
            return false;
        // A notch opens wide (the tiles' hulls end on the outline at some angle); a narrow inlet's
        // triangle is a sliver reaching into the surface, where the bunny's ear at a coarse cut had one
        // and a later local refinement (refine_mesh) folded near it.
        if (dot(normalized(pa - pc), normalized(pb - pc)) > min_angle_cos_)
            return false;
        // Turned like the faces it joins (across a -> c and c -> b); a convex corner's triangle folds
        // back over them and turns the other way.
        const Vec3 n = cross(pc - pa, pb - pa);
        if (!(norm(n) > 0.0))
            return false;
        const Vec3 normal = normalized(n);
        for (const Mesh::HalfedgeHandle h : {in, out}) {
            const Mesh::FaceHandle f = mesh_.face_handle(mesh_.opposite_halfedge_handle(h));
            if (!f.is_valid() || dot(to_vec3(mesh_.calc_face_normal(f)), normal) < min_cos_)
                return false;
        }
        // a and b already joined elsewhere: the face would close more than the notch.
        if (mesh_.find_halfedge(b, a).is_valid() || mesh_.find_halfedge(a, b).is_valid())
            return false;
        const std::array<Vec3, 3> t{pa, pc, pb};
        if (!points_cover(h_, t, o_.cover_spacings * s) || crosses(t, {a, b, c}))
            return false;
        const Mesh::FaceHandle f = mesh_.add_face(a, c, b);
        if (!f.is_valid())
            return false; // refused (a non-manifold corner): the notch stays
        mesh_.property(tile_, f) = -1;
        mesh_.property(gap_, f) = true;
        grid_.insert(static_cast<std::uint32_t>(f.idx()), triangle_box(t));
        return true;
    }

    // Whether triangle t meets a face of the mesh that shares none of its corners.
    bool crosses(const std::array<Vec3, 3>& t, const std::array<Mesh::VertexHandle, 3>& own) const
    {
        return grid_.any_candidate(triangle_box(t), [&](std::uint32_t id) {
            const Mesh::FaceHandle f(static_cast<int>(id));
            if (mesh_.status(f).deleted())
                return false;
            for (const auto v : mesh_.fv_range(f))
                if (v == own[0] || v == own[1] || v == own[2])
                    return false;
            return triangles_meet(t, corners(f));
        });
    }

    Mesh& mesh_;
    const Hierarchy& h_;
    const std::unordered_map<std::int32_t, double>& spacing_of_;
    const NotchOptions& o_;
    double min_cos_;
    double min_angle_cos_;
    BoxGrid grid_;
    OpenMesh::VPropHandleT<int> cluster_;
    OpenMesh::FPropHandleT<int> tile_;
    OpenMesh::FPropHandleT<bool> gap_;
};

} // namespace

std::size_t fill_notches(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
                         const NotchOptions& options)
{
    check_options(options);
    if (mesh.n_faces() == 0)
        return 0;
    NotchFiller filler(mesh, h, spacing_of, options);
    const std::size_t added = filler.run();
    if (added > 0) {
        mesh.update_face_normals();
        mesh.update_vertex_normals();
    }
    return added;
}

} // namespace mrt
