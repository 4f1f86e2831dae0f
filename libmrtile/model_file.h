#pragma once
//! \file model_file.h
//! \brief The `.mrt` model file: a built hierarchy, saved once and cut many times.
//! \details Layout (version 3, every number little-endian whatever the host; version 1 and 2 files,
//! without the coverage gap (1) or the node hulls (1, 2), are read too and those computed on load):
//! \code
//!   header   104 bytes: magic "MRTILE\r\n", u32 version, u32 endian marker 0x01020304, u32 header size,
//!            u32 flags (1 = colours, 2 = build time recorded, 4 = viewpoint, 8 = CRS, 16 = levels,
//!            32 = points denoised, 64 = denoising moves), u64 points, u64 nodes, f64 origin[3],
//!            u32 criterion, u32 pca_limit, u32 min_cluster, u32 reclassify, f64 criterion value,
//!            f64 build seconds, u64 payload size
//!   payload  positions (points × 3 f64, relative to origin, tree order), colours (points × 4 u8, if
//!            flagged), input index (points × u32), node hulls (u64 entries, nodes × u32 hull size (0
//!            for nodes of kHullStoredAbove points or fewer), entries × u32 point index:
//!            Hierarchy::hull_points), nodes (nodes × 176 bytes: begin, end, parent, left,
//!            right, depth as 32-bit, count u64, mean 3 f64, M 6 f64, eq. 1 error f64, max plane
//!            distance f64, box min 3 f64, box max 3 f64, coverage gap f64), viewpoint (3 f64 relative to origin, if flagged),
//!            CRS (u32 length 1..2^20, then that many bytes: "EPSG:N" or WKT, if flagged), how far
//!            the denoising moved each point (points × f32, tree order, if flag 64; with flag 32), stored
//!            levels (if flag 16: u64 section size, u32 recipe length, recipe, u32 levels, then per level
//!            tolerance, geometric error, max plane distance as f64, u64 cut size, cut nodes as i32,
//!            u64 vertices, u64 faces, u32 1 if coloured, per vertex position 3 f64, normal 3 f64,
//!            cluster i32, colour 4 u8 if coloured, per face 3 u32 corners, tile i32, gap u8)
//!   trailer  u32 CRC-32 of everything before it, magic "MEND"
//! \endcode
//! The file holds only exact statistics; PCA frames are recomputed on load, so load → save is
//! byte-identical. Loading checks sizes against the file before allocating, the checksum, and the
//! tree's structure, so a truncated or corrupted file is rejected with an IoError, never half-loaded.
//! The build time is stored only when asked for (SaveOptions::record_build_time): the same input
//! and options otherwise give byte-identical files.

#include "libmrtile/hierarchy.h"
#include "libmrtile/lod_set.h"

#include <filesystem>
#include <string>

namespace mrt {

inline constexpr std::uint32_t kModelFormatVersion = 3;

//! \brief A LOD set's meshed levels (make_lod_levels) kept in the model file, so that exports of
//! the model cut tiles from them instead of meshing every level again (a minute for 1M points).
//! \details `recipe` names the options the levels were made with, in the caller's terms (the CLI
//! writes its level and mesh options); a reader reuses the levels only for the same recipe. Meshes are
//! stored exactly: loaded, they give byte-identical tiles.
struct StoredLevels
{
    std::string recipe;
    std::vector<LodLevel> levels;
};

struct SaveOptions
{
    //! Store Hierarchy::info.build_seconds (makes two builds of the same input differ in 8 bytes).
    bool record_build_time = false;
    //! Levels to store with the hierarchy (nullptr or none: no levels section). About 45 bytes per
    //! face of all levels together (the finest level has about 0.7 faces per point).
    const StoredLevels* levels = nullptr;
};

//! A model file's contents: the hierarchy and the levels stored with it (empty when there are none).
struct Model
{
    Hierarchy hierarchy;
    StoredLevels levels;
};

//! Serialises a hierarchy into the bytes of a `.mrt` file.
std::string serialize_model(const Hierarchy& h, const SaveOptions& options = {});

//! Parses the bytes of a `.mrt` file. `name` is used in error messages (usually the path).
//! \throw IoError if the bytes are truncated, corrupted or of an unsupported version.
Hierarchy deserialize_model(const std::string& bytes, const std::string& name);

//! Like deserialize_model, and the stored levels too (every level mesh is rebuilt face by face and
//! checked). \throw IoError as deserialize_model, or if a level is invalid.
Model deserialize_model_with_levels(const std::string& bytes, const std::string& name);

//! Writes atomically (temporary file + rename). \throw IoError naming the path on failure.
void save_model(const Hierarchy& h, const std::filesystem::path& path, const SaveOptions& options = {});

//! \throw IoError naming the path if it is missing, unreadable, truncated or corrupted.
//! The stored levels, if any, are checked by the checksum but not parsed.
Hierarchy load_model(const std::filesystem::path& path);

//! The hierarchy and its stored levels. \throw IoError as load_model, or if a stored level is invalid.
Model load_model_with_levels(const std::filesystem::path& path);

} // namespace mrt
