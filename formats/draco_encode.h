#pragma once
//! \file draco_encode.h
//! \brief Draco compression of meshes: bare .drc files and the payload of KHR_draco_mesh_compression.
//! \details The only place that includes Draco headers (draco_encode.cpp). Positions are quantized
//! (lossy); normals are octahedral-quantized; RGBA colours are stored exactly, as the sRGB bytes
//! (bare .drc, like PLY) or as glTF's 16-bit linear values (`DracoOptions::linear_colors`; Draco
//! quantizes float attributes only, so there is no colour quantization setting).

#include "formats/mesh_buffers.h"
#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mrt {

//! An explicit quantization cube [min, min + range] on every axis, in the mesh's frame (positions
//! relative to the origin, input axes). Meshes encoded on the same grid with the same bits decode a
//! shared vertex to bit-identical positions: give every tile of a tileset the same grid so that
//! border vertices of adjacent tiles match exactly.
struct QuantizationGrid
{
    Vec3 min{0, 0, 0};
    double range = 0.0; //!< > 0; every position must lie inside the cube
};

//! The finest position quantization allowed: Draco's encoder takes memory in proportion to 2^bits,
//! whatever the mesh's size (30 bits: 4.2 GB per thread; 24 bits: 64 MB, steps of 6e-8 of the grid).
constexpr int kMaxPositionBits = 24;

struct DracoOptions
{
    //! 1..kMaxPositionBits; quantization step = extent / (2^bits - 1)
    int position_bits = 14;
    int normal_bits = 10;    //!< 1..30
    //! 0 (best compression) .. 10 (fastest). Default 3/3 = `draco_encoder`'s default -cl 7.
    int encoding_speed = 3;
    int decoding_speed = 3; //!< 0 .. 10, as encoding_speed: what the encoder may trade for faster decoding
    //! Default: none, Draco quantizes on the mesh's own bounding cube. Draco keeps the range as text with
    //! six decimals: it is rounded up to the next millionth of a unit, and a range under 1e-6 that this
    //! would more than double is an InvalidInput.
    std::optional<QuantizationGrid> grid;
    //! Colours as linear_colors (mesh_buffers.h): 16-bit normalized linear values, what glTF's COLOR_0
    //! means (the glTF writer sets it); false keeps the sRGB bytes, as a bare .drc holds them (three.js
    //! decodes a .drc's colours as sRGB, a glTF's as linear).
    bool linear_colors = false;
};

//! True when `options` have Draco store faces and vertices in the order given: its sequential coding,
//! which encode_draco uses when either speed is 10 (as Draco itself picks). Otherwise the edgebreaker
//! writes them in the order of its own traversal, whatever order it was given (the same bytes), so the
//! writers skip the vertex-cache reordering (mesh_buffers.h) that would be lost: decoded, the bunny at
//! tolerance 0.001 has 0.98 vertex-cache misses per triangle either way (0.66 in GPU order, sequential).
bool draco_keeps_face_order(const DracoOptions& options);

//! \brief Writes `mesh` as a bare Draco file, in the mesh's own axes (no rotation).
//! Positions are stored relative to an offset (float precision); the absolute coordinates are
//! decoded position + the double[3] geometry metadata entry "mrtile_origin" (= origin + offset).
//! \throw InvalidInput for bad options, an empty mesh or positions outside `options.grid`;
//! IoError naming `path` if it cannot be written (nothing is left behind).
void write_drc(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path,
               const DracoOptions& options = {});

//! The output-frame offset to flatten a mesh with when `options.grid` is set (its min corner in that
//! frame), so that the grid's origin is exactly 0 in the encoded coordinates; nullopt without a grid.
std::optional<Vec3> draco_grid_offset(const DracoOptions& options, UpAxis up);

//! What Draco actually encoded, read back by decoding the result.
struct DracoEncoded
{
    std::string bytes;
    int position_id = -1; //!< Draco attribute unique ids, -1 if absent
    int normal_id = -1;
    int color_id = -1;
    std::size_t vertex_count = 0; //!< decoded points (Draco may split or reorder vertices)
    std::size_t face_count = 0;
    std::array<float, 3> min{};   //!< of the decoded (dequantized) positions
    std::array<float, 3> max{};
};

//! \brief Encodes flattened buffers. With `options.grid`, the buffers must have been made with
//! offset draco_grid_offset(options, up) (the grid origin is then local 0).
//! \param metadata_origin if set, stored as the "mrtile_origin" geometry metadata entry.
DracoEncoded encode_draco(const MeshBuffers& buffers, const DracoOptions& options,
                          const std::optional<Vec3>& metadata_origin = std::nullopt);

//! A decoded Draco mesh (used by tests and readers).
struct DracoDecoded
{
    std::vector<float> positions;        //!< xyz per point
    std::vector<float> normals;          //!< xyz per point, or empty
    std::vector<std::uint8_t> colors;    //!< rgba per point stored as bytes (sRGB), or empty
    std::vector<std::uint16_t> linear_colors; //!< rgba per point stored as 16-bit linear values, or empty
    std::vector<std::uint32_t> indices;  //!< three per face
    std::optional<Vec3> metadata_origin; //!< "mrtile_origin" if present
};

//! \throw IoError naming `what` if the bytes are not a Draco mesh.
DracoDecoded decode_draco(const std::string& bytes, const std::string& what);

} // namespace mrt
