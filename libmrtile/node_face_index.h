#pragma once
//! \file node_face_index.h
//! \brief The faces of a mesh made from a cut, indexed by the hierarchy nodes that own them: exact
//! closest points on the surface without a search structure over all of it (lod_set.cpp measures
//! coarse levels against the finest with it).

#include "libmrtile/errors.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace mrt {

//! The tile (hierarchy node) owning a face of a mesh_cut mesh: its own (kFaceTile), or for a gap face
//! (tile -1) the tile of its smallest-index vertex (kVertexCluster; deterministic).
inline int face_owner(const Mesh& mesh, OpenMesh::FPropHandleT<int> tile, OpenMesh::VPropHandleT<int> cluster, Mesh::FaceHandle f)
{
    int owner = mesh.property(tile, f);
    if (owner < 0) {
        int smallest = -1;
        for (const auto v : mesh.fv_range(f))
            if (smallest < 0 || v.idx() < smallest) {
                smallest = v.idx();
                owner = mesh.property(cluster, v);
            }
    }
    return owner;
}

//! A mesh's faces by the hierarchy node that owns them (face_owner), with the box of the faces in each
//! node's subtree: a search down the hierarchy, nearer child first and pruned by the boxes, finds the
//! closest point of the surface exactly. lod_set.cpp asks it about a few points of a LOD set's finest
//! level, which then need no search structure over the whole mesh (a CGAL AABB tree over a 1M-point
//! model's finest level was 0.35 s of a 1.8 s export). It refers to `h` and `mesh`, which must outlive
//! it. \throw InvalidInput (constructor) if the mesh lacks the tile/cluster properties.
class NodeFaceIndex
{
public:
    NodeFaceIndex(const Hierarchy& h, const Mesh& mesh) : h_(h), mesh_(mesh)
    {
        OpenMesh::FPropHandleT<int> tile;
        OpenMesh::VPropHandleT<int> cluster;
        if (!mesh.get_property_handle(tile, kFaceTile) || !mesh.get_property_handle(cluster, kVertexCluster))
            throw InvalidInput("lods: level mesh lacks the tile/cluster properties");
        const std::size_t nodes = h.nodes.size();
        std::vector<std::int32_t> owner(mesh.n_faces(), -1);
        first_.assign(nodes + 1, 0);
        box_.assign(nodes, BoundingBox{});
        has_box_.assign(nodes, 0);
        for (const auto f : mesh.faces()) {
            const int o = face_owner(mesh, tile, cluster, f);
            if (o < 0 || static_cast<std::size_t>(o) >= nodes)
                continue;
            owner[static_cast<std::size_t>(f.idx())] = o;
            ++first_[static_cast<std::size_t>(o) + 1];
            for (const auto v : mesh.fv_range(f))
                grow(static_cast<std::size_t>(o), to_vec(mesh.point(v)));
        }
        for (std::size_t k = 0; k < nodes; ++k)
            first_[k + 1] += first_[k];
        faces_.resize(first_[nodes]);
        std::vector<std::uint32_t> next(first_.begin(), first_.end() - 1);
        for (std::size_t f = 0; f < owner.size(); ++f)
            if (owner[f] >= 0)
                faces_[next[static_cast<std::size_t>(owner[f])]++] = static_cast<std::uint32_t>(f);
        for (std::size_t k = nodes; k-- > 1;) // children come after their parents
            if (has_box_[k]) {
                const std::size_t parent = static_cast<std::size_t>(h.nodes[k].parent);
                grow(parent, box_[k].min);
                grow(parent, box_[k].max);
            }
    }

    struct Closest
    {
        double distance = std::numeric_limits<double>::infinity();
        bool on_border = false; //!< the closest point lies on a border edge or vertex of the surface
    };

    //! The closest point of the finest surface to q (exact; ties: the first face found).
    Closest closest(const Vec3& q) const
    {
        Closest best;
        if (h_.nodes.empty() || !has_box_[0])
            return best;
        std::uint32_t best_face = 0;
        Vec3 at = q;
        std::vector<std::pair<double, std::size_t>> stack{{box_distance(0, q), 0}};
        while (!stack.empty()) {
            const auto [bound, k] = stack.back();
            stack.pop_back();
            if (!(bound < best.distance))
                continue;
            for (std::uint32_t i = first_[k]; i < first_[k + 1]; ++i) {
                const std::array<Vec3, 3> c = corners(faces_[i]);
                const Vec3 p = closest_point_on_triangle(q, c[0], c[1], c[2]);
                const double d = norm(q - p);
                if (d < best.distance) {
                    best.distance = d;
                    best_face = faces_[i];
                    at = p;
                }
            }
            const Node& n = h_.nodes[k];
            if (n.is_leaf())
                continue;
            std::array<std::pair<double, std::size_t>, 2> children;
            std::size_t count = 0;
            for (const std::int32_t c : {n.left, n.right})
                if (has_box_[static_cast<std::size_t>(c)])
                    children[count++] = {box_distance(static_cast<std::size_t>(c), q), static_cast<std::size_t>(c)};
            if (count == 2 && children[0].first < children[1].first)
                std::swap(children[0], children[1]); // the nearer is searched first: pushed last
            for (std::size_t c = 0; c < count; ++c)
                if (children[c].first < best.distance)
                    stack.push_back(children[c]);
        }
        if (best.distance < std::numeric_limits<double>::infinity())
            best.on_border = on_border(best_face, at);
        return best;
    }

    //! How far q stands off the finest surface: its distance to it, where its closest point is no point
    //! of the surface's border; else 0. Across a hole of the finest level (a coarse vertex between the
    //! strips of a patchy finest level, scan lines 5 m apart) there is no surface for q to stand off,
    //! only metres to the nearest strip's border (QA round 65: a clean terrain's root 2.3 -> 26 m with
    //! the distance alone); a bird's tent stands over the inside of the ground.
    double off_surface(const Vec3& q) const
    {
        const Closest c = closest(q);
        return c.on_border ? 0.0 : c.distance;
    }

private:
    static Vec3 to_vec(const Mesh::Point& p) { return {p[0], p[1], p[2]}; }

    void grow(std::size_t k, const Vec3& p)
    {
        if (!has_box_[k]) {
            box_[k] = {p, p};
            has_box_[k] = 1;
        } else {
            box_[k].min = min(box_[k].min, p);
            box_[k].max = max(box_[k].max, p);
        }
    }

    std::array<Vec3, 3> corners(std::uint32_t face) const
    {
        std::array<Vec3, 3> c;
        std::size_t n = 0;
        for (const auto v : mesh_.fv_range(mesh_.face_handle(static_cast<int>(face))))
            c[n++] = to_vec(mesh_.point(v));
        return c;
    }

    // Whether point p of the face lies on one of its edges (within a millionth of the edge's length)
    // that is a border of the mesh, or at a corner that is a border vertex.
    bool on_border(std::uint32_t face, const Vec3& p) const
    {
        const auto f = mesh_.face_handle(static_cast<int>(face));
        for (const auto he : mesh_.fh_range(f)) {
            const auto from = mesh_.from_vertex_handle(he), to = mesh_.to_vertex_handle(he);
            const Vec3 a = to_vec(mesh_.point(from)), b = to_vec(mesh_.point(to));
            const double length = norm(b - a);
            const bool at_edge = point_segment_distance(p, a, b) <= 1e-6 * length;
            if (!at_edge)
                continue;
            if (mesh_.is_boundary(mesh_.edge_handle(he)))
                return true;
            for (const auto v : {from, to})
                if (norm(p - to_vec(mesh_.point(v))) <= 1e-6 * length && mesh_.is_boundary(v))
                    return true;
        }
        return false;
    }

    static double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b)
    {
        const Vec3 ab = b - a;
        const double l2 = dot(ab, ab);
        const double t = l2 > 0.0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
        return norm(p - (a + ab * t));
    }

    double box_distance(std::size_t k, const Vec3& q) const
    {
        const Vec3 below = box_[k].min - q, above = q - box_[k].max;
        return norm(Vec3{std::max({0.0, below.x, above.x}), std::max({0.0, below.y, above.y}), std::max({0.0, below.z, above.z})});
    }

    const Hierarchy& h_;
    const Mesh& mesh_;
    std::vector<std::uint32_t> first_; // faces_[first_[k], first_[k + 1]) are node k's own
    std::vector<std::uint32_t> faces_;
    std::vector<BoundingBox> box_;      // of the faces in node k's subtree
    std::vector<char> has_box_;
};

} // namespace mrt
