#pragma once
//! \file write_gltf.h
//! \brief glTF 2.0 export (.glb, or .gltf with the buffer embedded as a base64 data URI), optionally
//! Draco compressed (KHR_draco_mesh_compression) and with levels of detail (MSFT_lod).
//! \details Positions are float32 relative to a per-node offset; the node's `translation` (double)
//! carries origin + offset, so georeferenced meshes (origin ~1e6) keep their precision. Deleted mesh
//! elements are skipped (no garbage collection needed); only vertices used by a face are written.
//! Output is byte-deterministic and written atomically.

#include "formats/draco_encode.h"
#include "formats/mesh_buffers.h"
#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace mrt {

struct GltfOptions
{
    //! Default Z: the input is z-up and is rotated (x, y, z) -> (x, z, -y) into glTF's y-up.
    UpAxis up_axis = UpAxis::Z;
    bool normals = true;      //!< write NORMAL (stored vertex normals, else computed)
    bool colors = true;       //!< write COLOR_0 (normalized RGBA bytes) when the mesh has colours
    bool double_sided = true; //!< material doubleSided: reconstructed surfaces are often open
    bool draco = false;       //!< KHR_draco_mesh_compression (then also extensionsRequired)
    DracoOptions draco_options; //!< used when draco is true
    //! Subtracted (in the output frame) from every position before it is stored as float, and put
    //! into the node's translation. Default: the file's own bounding-box centre, rounded (a Draco grid
    //! sets its own). Files that must agree bit for bit where they meet (the tiles of one tileset
    //! level) pass one offset: float(p - offset) is then the same number in each.
    std::optional<Vec3> offset;
    //! The mesh's last `skirt_faces` faces (by index) are skirts, the strips a 3D Tiles tile hangs
    //! from its border (lod_set.h): they go into a second primitive whose material is single-sided,
    //! the first's otherwise. A double-sided material shows a skirt's back with its normals reversed
    //! (glTF's rule), dark, and wherever the skirt's top edge meets the neighbour's surface the two
    //! fight for depth: double-sided skirts drew dashed dark lines along every tile border. Must be
    //! below the mesh's face count; 0: one primitive.
    std::size_t skirt_faces = 0;
};

//! \brief Writes one mesh (positions relative to `origin`) as a glTF scene with one node.
//! The format follows the extension of `path`: ".glb" or ".gltf".
//! \throw InvalidInput for another extension, an empty mesh or bad options; IoError naming `path`
//! if it cannot be written (nothing is left behind).
void write_gltf(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path,
                const GltfOptions& options = {});

//! Returns the bytes write_gltf would write as a .glb file.
std::string glb_bytes(const Mesh& mesh, const Vec3& origin, const GltfOptions& options = {});

struct GltfLodOptions
{
    GltfOptions gltf;
    //! MSFT_screencoverage per level (fine to coarse), written as the finest node's extras; empty:
    //! omitted. Otherwise one value per level, decreasing.
    std::vector<double> screen_coverage;
};

//! \brief Writes levels of detail into one file: one node per level, the finest node in the scene and
//! referencing the coarser ones through MSFT_lod (listed in extensionsUsed, not required, so viewers
//! without it show the finest level).
//! \throw InvalidInput if `levels_fine_to_coarse` is empty, holds a null or empty mesh, or
//! screen_coverage does not match; IoError as write_gltf.
void write_glb_lods(const std::vector<const Mesh*>& levels_fine_to_coarse, const Vec3& origin,
                    const std::filesystem::path& path, const GltfLodOptions& options = {});

} // namespace mrt
