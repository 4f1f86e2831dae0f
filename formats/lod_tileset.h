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

//! The one Draco grid of a tileset: the cube over every tile's vertices (skirts included), padded by a
//! millionth of its side. Not the root's box: that holds every point, and a stray point the mesh
//! leaves out far away would stretch the grid and coarsen every position as much. The root's box
//! when no tile has vertices.
QuantizationGrid tileset_grid(const LodSet& set);

//! With Draco and no grid in `options`, tiles are quantized on tileset_grid(set).
//! \throw IoError naming the path that cannot be written; InvalidInput for an empty set.
void write_lod_tileset(const LodSet& set, const Vec3& origin, const std::filesystem::path& dir,
                       TilesetOptions options = {});

} // namespace mrt
