// Beyond the paper's T1 (§4.3): a fan is the best a single planar polygon can do, so a coarse tile on a
// curved surface leaves points far from the mesh whatever the rest of the surface does. Greedy insertion
// (the worst point of a fan triangle becomes a vertex, as in Garland and Heckbert's height-field
// refinement) spends faces only where a tile bends, and never touches the gap faces, the tile borders
// or the topology: a 1-to-3 split inside a fan cannot make the mesh non-manifold.
#include "libmrtile/refine_fans.h"

#include "libmrtile/errors.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <queue>
#include <string>
#include <tuple>
#include <vector>

namespace mrt {
namespace {

// Each fan is judged in its tile's plane frame (node mean and PCA axes, PlaneFrame): fans are nearly flat
// in it, so a point's fan triangle is the one its projection falls into, and deviations are measured
// along the normal.
class FanRefiner
{
public:
    FanRefiner(Mesh& mesh, const Hierarchy& h, const FanRefineOptions& options)
        : mesh_(mesh), h_(h), options_(options), tile_(OpenMesh::getProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile)),
          cluster_(OpenMesh::getProperty<OpenMesh::VertexHandle, int>(mesh, kVertexCluster))
    {
    }

    std::size_t run()
    {
        std::map<int, std::vector<Mesh::FaceHandle>> fans; // ordered by node id: deterministic
        for (const Mesh::FaceHandle f : mesh_.faces())
            if (tile_[f] >= 0)
                fans[tile_[f]].push_back(f);
        std::size_t inserted = 0;
        for (const auto& [node, faces] : fans) {
            if (static_cast<std::size_t>(node) >= h_.nodes.size())
                throw InvalidInput("refine_fans: face tile " + std::to_string(node) + " is not a node of the hierarchy");
            inserted += refine_tile(node, faces);
        }
        if (inserted > 0)
            mesh_.update_normals();
        return inserted;
    }

private:
    struct Worst
    {
        double deviation;
        int face;
        std::uint32_t point;
        std::uint32_t version;
        bool operator<(const Worst& o) const
        {
            return std::tie(deviation, o.face, o.point) < std::tie(o.deviation, face, point); // ties: lower face first
        }
    };

    std::array<std::array<double, 2>, 3> corners_uv(const PlaneFrame& fr, Mesh::FaceHandle f, std::array<double, 3>* heights) const
    {
        std::array<std::array<double, 2>, 3> out{};
        int k = 0;
        for (const Mesh::VertexHandle v : mesh_.fv_range(f)) {
            const Vec3 q = to_vec3(mesh_.point(v));
            out[k] = fr.project(q);
            if (heights)
                (*heights)[k] = fr.height(q);
            ++k;
        }
        return out;
    }

    // The point of `points` farthest from face f along the normal (deviation -1 if none).
    Worst worst_of(const PlaneFrame& fr, Mesh::FaceHandle f, const std::vector<std::uint32_t>& points) const
    {
        Worst w{-1.0, f.idx(), 0, version_[static_cast<std::size_t>(f.idx())]};
        std::array<double, 3> heights{};
        const auto t = corners_uv(fr, f, &heights);
        for (std::uint32_t i : points) {
            const Vec3& p = h_.cloud.positions[i];
            std::array<double, 3> l{};
            if (!barycentric(fr.project(p), t, l))
                continue;
            const double d = std::abs(fr.height(p) - (l[0] * heights[0] + l[1] * heights[1] + l[2] * heights[2]));
            if (d > w.deviation) {
                w.deviation = d;
                w.point = i;
            }
        }
        return w;
    }

    // Distributes `points` over `faces` by their projection (a point on no face is dropped: it lies in
    // a gap or outside the fan).
    void assign(const PlaneFrame& fr, const std::vector<Mesh::FaceHandle>& faces, const std::vector<std::uint32_t>& points)
    {
        std::vector<std::array<std::array<double, 2>, 3>> tris;
        for (const Mesh::FaceHandle f : faces)
            tris.push_back(corners_uv(fr, f, nullptr));
        for (std::uint32_t i : points) {
            const auto q = fr.project(h_.cloud.positions[i]);
            for (std::size_t k = 0; k < faces.size(); ++k) {
                std::array<double, 3> l{};
                if (barycentric(q, tris[k], l) && l[0] >= -1e-12 && l[1] >= -1e-12 && l[2] >= -1e-12) {
                    points_of(faces[k]).push_back(i);
                    break;
                }
            }
        }
    }

    void fit_face_arrays()
    {
        if (face_points_.size() < mesh_.n_faces()) {
            face_points_.resize(mesh_.n_faces());
            version_.resize(mesh_.n_faces(), 0);
        }
    }

    std::vector<std::uint32_t>& points_of(Mesh::FaceHandle f)
    {
        fit_face_arrays();
        return face_points_[static_cast<std::size_t>(f.idx())];
    }

    std::size_t refine_tile(int node_id, const std::vector<Mesh::FaceHandle>& faces)
    {
        const Node& node = h_.nodes[static_cast<std::size_t>(node_id)];
        const double slack = options_.max_deviation * node.rms_plane_distance;
        if (!(slack > 0.0))
            return 0; // a flat tile: its fan is exact
        PlaneFrame fr;
        fr.origin = node.centre();
        fr.n = node.frame.vectors[0];
        fr.u = node.frame.vectors[2];
        fr.v = cross(fr.n, fr.u);
        std::vector<std::uint32_t> points(node.count());
        for (std::uint32_t k = 0; k < node.count(); ++k)
            points[k] = node.begin + k;
        fit_face_arrays();
        assign(fr, faces, points);
        std::priority_queue<Worst> queue;
        for (const Mesh::FaceHandle f : faces)
            queue.push(worst_of(fr, f, points_of(f)));
        std::size_t inserted = 0;
        while (!queue.empty() && inserted < options_.max_points_per_tile) {
            const Worst w = queue.top();
            queue.pop();
            const Mesh::FaceHandle f(w.face);
            if (w.version != version_[static_cast<std::size_t>(w.face)])
                continue; // the face was split since
            if (!(w.deviation > slack))
                break;
            const Vec3& p = h_.cloud.positions[w.point];
            const Mesh::VertexHandle v = mesh_.add_vertex(Mesh::Point(p.x, p.y, p.z));
            cluster_[v] = node_id;
            std::vector<std::uint32_t> moved = std::move(points_of(f));
            points_of(f).clear();
            mesh_.split_copy(f, v); // the new faces copy f's tile id and gap flag
            fit_face_arrays();
            std::vector<Mesh::FaceHandle> around;
            for (const Mesh::FaceHandle g : mesh_.vf_range(v))
                around.push_back(g);
            moved.erase(std::remove(moved.begin(), moved.end(), w.point), moved.end());
            for (const Mesh::FaceHandle g : around) {
                points_of(g).clear();
                ++version_[static_cast<std::size_t>(g.idx())];
            }
            assign(fr, around, moved);
            for (const Mesh::FaceHandle g : around)
                queue.push(worst_of(fr, g, points_of(g)));
            ++inserted;
        }
        return inserted;
    }

    Mesh& mesh_;
    const Hierarchy& h_;
    const FanRefineOptions& options_;
    OpenMesh::PropertyManager<OpenMesh::FPropHandleT<int>> tile_;
    OpenMesh::PropertyManager<OpenMesh::VPropHandleT<int>> cluster_;
    std::vector<std::vector<std::uint32_t>> face_points_;
    std::vector<std::uint32_t> version_;
};

} // namespace

std::size_t refine_fans(Mesh& mesh, const Hierarchy& h, const FanRefineOptions& options)
{
    if (!(options.max_deviation >= 0.0))
        throw InvalidInput("FanRefineOptions::max_deviation must be >= 0");
    if (options.max_deviation == 0.0 || options.max_points_per_tile == 0 || mesh.n_faces() == 0 ||
        !OpenMesh::hasProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile) ||
        !OpenMesh::hasProperty<OpenMesh::FaceHandle, bool>(mesh, kFaceGap) ||
        !OpenMesh::hasProperty<OpenMesh::VertexHandle, int>(mesh, kVertexCluster))
        return 0;
    return FanRefiner(mesh, h, options).run();
}

} // namespace mrt
