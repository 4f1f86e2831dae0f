#pragma once
//! \file mesh_buffers.h
//! \brief A mesh flattened into the float/index arrays that glTF and Draco store.
//! \details Shared by write_gltf and draco_encode so that both see the same vertices in the same
//! order. Deleted vertices and faces (a mesh that was not garbage-collected) are skipped; only vertices
//! used by a face are kept. Positions are float32 relative to a per-file `offset` (double), so that a
//! georeferenced mesh keeps its precision: the writer puts `offset` into a node translation or metadata.

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace mrt {

//! Which axis of the input points up. glTF is y-up.
enum class UpAxis
{
    Y, //!< input is already y-up: written as is
    Z, //!< input is z-up: (x, y, z) -> (x, z, -y)
};

//! \throw InvalidInput unless `up` is UpAxis::Y or UpAxis::Z (static_cast<UpAxis>(42) was taken for Y).
void check_up_axis(UpAxis up);

//! Maps a point or direction of the input frame into the output (glTF) frame.
Vec3 to_output_frame(const Vec3& v, UpAxis up);
//! Inverse of to_output_frame.
Vec3 from_output_frame(const Vec3& v, UpAxis up);

struct MeshBufferOptions
{
    UpAxis up_axis = UpAxis::Z;    //!< default Z: rotate into glTF's y-up
    bool normals = true;           //!< fill `normals` (stored ones if usable, otherwise computed)
    bool colors = true;            //!< fill `colors` when the mesh has vertex colours
    //! Reorder triangles for the GPU's post-transform vertex cache and vertices for fetch locality
    //! (meshoptimizer's optimizeVertexCache and optimizeVertexFetch, what gltfpack does): renderers draw
    //! the same triangles with fewer vertex shader runs (bunny at tolerance 0.002: 2.4 -> 0.65 per
    //! triangle with a 16-entry cache; the surface stage emits faces in no useful order). Only the
    //! order changes; false keeps the mesh's face order. The Draco writers set it only where Draco keeps
    //! the order (draco_keeps_face_order, draco_encode.h).
    bool gpu_order = true;
    //! Subtracted (in the output frame) from every position. Default: the bounding-box centre of the
    //! used vertices in the output frame, rounded to whole units.
    std::optional<Vec3> offset;
    //! Only the faces whose index lies in [first_face, end_face) (deleted ones are skipped as always),
    //! and the vertices they use: a Draco tile's skirts are encoded apart from its surface
    //! (GltfOptions::skirt_faces). Default: every face.
    std::size_t first_face = 0;
    std::size_t end_face = std::numeric_limits<std::size_t>::max();
    //! The triangles of faces from index split_face on come after all the others, each part in an
    //! order of its own (GPU order within each), so that two index ranges over one vertex array draw
    //! them apart (a plain tile's surface and skirts). MeshBuffers::split_triangle tells where the
    //! second part starts. Default: one part.
    std::size_t split_face = std::numeric_limits<std::size_t>::max();
};

struct MeshBuffers
{
    Vec3 offset;                       //!< output frame: position = float(frame(p) - offset)
    std::vector<float> positions;      //!< xyz per vertex
    std::vector<float> normals;        //!< unit xyz per vertex, or empty
    std::vector<std::uint8_t> colors;  //!< rgba per vertex as the points gave them (sRGB bytes), or empty
    std::vector<std::uint32_t> indices; //!< three per triangle
    std::array<float, 3> min{};         //!< of positions
    std::array<float, 3> max{};
    //! Triangles before MeshBufferOptions::split_face's part (all of them without a split).
    std::size_t split_triangle = 0;

    std::size_t vertex_count() const { return positions.size() / 3; }
    std::size_t face_count() const { return indices.size() / 3; }
};

//! \brief Flattens `mesh` (positions relative to some origin, in the input frame). Vertices are
//! numbered in the order of their first use by the index buffer (after the GPU reordering, if on).
//! Normals: a vertex's stored normal is used when it is finite and non-zero (normalized); otherwise
//! the area-weighted normal of its faces, or the up axis if all its faces are degenerate.
//! \throw InvalidInput if the mesh has no (non-deleted) face, a used position is not finite, or a
//! face refers to a deleted vertex.
MeshBuffers make_mesh_buffers(const Mesh& mesh, const MeshBufferOptions& options = {});

//! \brief sRGB-encoded rgba bytes (what PLY, LAS, PTX and the mesh's colours hold) as the 16-bit
//! normalized *linear* values glTF's COLOR_0 means (glTF 2.0: vertex colours are linear multipliers of
//! the base colour; 3D Tiles: point colours are sRGB and must be linearized in glTF). RGB through the
//! exact sRGB decoding curve, alpha (coverage, not a colour) scaled as is. 16 bits, since 8-bit linear
//! values merge the dark shades: sRGB 0-12 would become linear bytes 0-1.
std::vector<std::uint16_t> linear_colors(const std::vector<std::uint8_t>& srgb);

} // namespace mrt
