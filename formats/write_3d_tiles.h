#pragma once
//! \file write_3d_tiles.h
//! \brief 3D Tiles 1.1 export: tileset.json plus one .glb per tile with content. Pure serialization:
//! choosing the tiles, their boxes and geometric errors is done by the caller.
//! \details The tileset frame is z-up; tile boxes and the root transform are expressed in it. The
//! glTF contents are y-up as the specification requires (clients rotate them y-up -> z-up), with
//! positions relative to the tileset origin; the root transform carries the origin.

#include "formats/write_gltf.h"
#include "libmrtile/mesh.h"
#include "libmrtile/point_cloud.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <vector>

namespace mrt {

//! One node of the tile tree.
struct TilesetTile
{
    const Mesh* mesh = nullptr;         //!< content; nullptr = no content
    BoundingBox box;                    //!< model units, relative to origin (as the mesh positions), input axes
    double geometric_error = 0.0;       //!< model units, >= 0, never larger than the parent's
    std::vector<std::size_t> children;  //!< indices into the tiles vector
    std::size_t skirt_faces = 0;        //!< the content's last faces that are skirts (GltfOptions::skirt_faces)
};

struct TilesetOptions
{
    //! Content options. up_axis also tells the frame of the boxes; Draco's grid, if any, is shared by
    //! every tile (so border vertices of neighbouring tiles decode identically). Its skirt_faces is
    //! each tile's own (TilesetTile::skirt_faces).
    GltfOptions gltf;
    //! Column-major 4x4 root transform mapping positions relative to origin (tileset z-up frame) to
    //! the tileset's coordinates, e.g. enu_to_ecef_transform(). Default: translation by origin.
    std::optional<std::array<double, 16>> root_transform;
    //! Top-level geometricError (error when nothing is rendered). Default: the larger of the root's
    //! error and the root box diagonal.
    std::optional<double> tileset_geometric_error;
    //! Tiles are encoded and written on this many threads (0 = the default, see parallel.h). The files
    //! do not depend on it.
    std::size_t threads = 0;
};

//! \brief Writes `dir`/tileset.json and `dir`/tiles/<index>.glb (tiles[0] is the root).
//! With Draco, every box is enlarged by one position quantization step so that it still contains the
//! dequantized content.
//! The directory is built in "<dir>.tmp.<pid>" and then swapped into place, so an existing `dir` is
//! replaced only on success and a failure leaves nothing behind. Byte-deterministic.
//! \throw InvalidInput if the tiles do not form a tree rooted at tiles[0], an error is negative,
//! non-finite or larger than its parent's, or a content mesh is empty; IoError naming the path that
//! cannot be written.
void write_3d_tiles(const std::vector<TilesetTile>& tiles, const Vec3& origin, const std::filesystem::path& dir,
                    const TilesetOptions& options = {});

//! \brief Checks before any work that write_3d_tiles could write `dir`: an existing `dir` is a tileset
//! of ours (tileset.json and tiles/<n>.glb only, so that replacing it removes nothing else) and its
//! temporary directory can be created. \throw IoError naming `dir` and the cause.
void check_tileset_directory(const std::filesystem::path& dir);

//! \brief Column-major 4x4 matrix mapping local east-north-up metres at the WGS84 point
//! (longitude, latitude in degrees, ellipsoidal height in metres) to ECEF (EPSG:4978), the frame of
//! Cesium and other 3D Tiles clients. Pass it as TilesetOptions::root_transform when the mesh
//! positions relative to origin are local ENU metres around that point.
std::array<double, 16> enu_to_ecef_transform(double longitude_deg, double latitude_deg, double height);

} // namespace mrt
