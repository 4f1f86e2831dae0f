#pragma once
//! \file mesh.h
//! \brief The output type: an OpenMesh half-edge triangle mesh with the ids of the method attached.
//! \details Positions are double precision and relative to the cloud's origin (see point_cloud.h).
//! Properties (read them with OpenMesh::getProperty / makePropertyManagerFromExisting):
//!  - kVertexCluster  ("v:cluster", int): the hierarchy node whose tile the vertex belongs to (a rim
//!    vertex merged across a gap strip is in the fans of two or more tiles and names one of them).
//!  - kFaceTile       ("f:tile", int): the tile (hierarchy node) of a T1 fan face, -1 for T2 gap faces
//!    (and for the two faces of an edge flip (fit_vertices.h) across faces of different tiles).
//!  - kFaceGap        ("f:gap", bool): true for gap-filling (T2) faces.
//! Vertex normals use OpenMesh's standard property.

#include "libmrtile/vec3.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <array>
#include <cstddef>
#include <mutex>

namespace mrt {

struct MeshTraits : public OpenMesh::DefaultTraits
{
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
    //! RGBA; vertex colours are requested (mesh.request_vertex_colors()) only when the input had colours.
    using Color = OpenMesh::Vec4uc;
    VertexAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
    FaceAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
    EdgeAttributes(OpenMesh::Attributes::Status);
    HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge);
};

using Mesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;

//! A mesh point or normal as the library's Vec3.
inline Vec3 to_vec3(const OpenMesh::Vec3d& v) { return {v[0], v[1], v[2]}; }
//! A Vec3 as a mesh point or normal.
inline OpenMesh::Vec3d to_point(const Vec3& p) { return {p.x, p.y, p.z}; }

//! The corners of triangle f, in its winding.
inline std::array<Vec3, 3> face_corners(const Mesh& mesh, Mesh::FaceHandle f)
{
    std::array<Vec3, 3> p;
    std::size_t k = 0;
    for (const auto v : mesh.fv_range(f))
        p[k++] = to_vec3(mesh.point(v));
    return p;
}

//! The corner vertices of triangle f, in its winding.
inline std::array<Mesh::VertexHandle, 3> face_vertices(const Mesh& mesh, Mesh::FaceHandle f)
{
    std::array<Mesh::VertexHandle, 3> v;
    std::size_t k = 0;
    for (const auto vh : mesh.fv_range(f))
        v[k++] = vh;
    return v;
}

//! The mean length of the mesh's edges; 1 for a mesh without edges or length (a grid cell size that
//! always works).
inline double mean_edge_length(const Mesh& mesh)
{
    double sum = 0.0;
    for (const auto e : mesh.edges())
        sum += mesh.calc_edge_length(e);
    return mesh.n_edges() > 0 && sum > 0.0 ? sum / static_cast<double>(mesh.n_edges()) : 1.0;
}

//! The first vertex (deleted ones skipped) with a NaN or infinite coordinate; an invalid handle when
//! there is none. The stages that take a caller's mesh refuse one with their own message.
inline Mesh::VertexHandle first_non_finite_vertex(const Mesh& mesh)
{
    for (const auto v : mesh.vertices())
        if (!is_finite(to_vec3(mesh.point(v))))
            return v;
    return Mesh::VertexHandle();
}

inline constexpr const char* kVertexCluster = "v:cluster";
inline constexpr const char* kFaceTile = "f:tile";
inline constexpr const char* kFaceGap = "f:gap";

//! Silences OpenMesh's console streams for its lifetime (the library never prints; OpenMesh writes
//! "complex edge" and reader/writer chatter to omerr/omlog). Restores their previous state.
//! \details The streams are global and stages run on several threads at once (levels, tiles), so the
//! guards are counted: the first to start silences, the last to end restores. A per-guard save and
//! restore would let one thread's guard switch the streams back on under another's add_face calls.
class QuietOpenMesh
{
public:
    QuietOpenMesh()
    {
        const std::lock_guard<std::mutex> hold(state().lock);
        State& s = state();
        if (s.guards++ == 0) {
            s.log = omlog().is_enabled();
            s.out = omout().is_enabled();
            s.err = omerr().is_enabled();
            omlog().disable();
            omout().disable();
            omerr().disable();
        }
    }
    ~QuietOpenMesh()
    {
        const std::lock_guard<std::mutex> hold(state().lock);
        State& s = state();
        if (--s.guards == 0) {
            if (s.log)
                omlog().enable();
            if (s.out)
                omout().enable();
            if (s.err)
                omerr().enable();
        }
    }
    QuietOpenMesh(const QuietOpenMesh&) = delete;
    QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

private:
    struct State
    {
        std::mutex lock;
        std::size_t guards = 0;
        bool log = true, out = true, err = true;
    };
    static State& state()
    {
        static State s;
        return s;
    }
};

} // namespace mrt
