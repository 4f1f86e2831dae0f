#pragma once
//! \file lod_tileset.h
//! \brief Writes a LodSet (libmrtile/lod_set.h) as a 3D Tiles 1.1 tileset.
//! \details Empty regions become tiles without content; with Draco, every tile is quantized on one
//! grid (the root box's cube), so border vertices shared by neighbouring tiles decode identically.

#include "formats/write_3d_tiles.h"
#include "libmrtile/lod_set.h"

#include <filesystem>

namespace mrt {

//! The tile tree in the writer's terms (pointers into `set`'s meshes; `set` must outlive the result).
std::vector<TilesetTile> tileset_tiles(const LodSet& set);

//! \throw IoError naming the path that cannot be written; InvalidInput for an empty set.
void write_lod_tileset(const LodSet& set, const Vec3& origin, const std::filesystem::path& dir,
                       TilesetOptions options = {});

} // namespace mrt
