// Bridge from the LOD set chosen in libmrtile (which tiles, which errors) to the 3D Tiles writer
// (how they are serialised): kept apart so the writer stays a pure serialiser.
#include "formats/lod_tileset.h"

#include "libmrtile/errors.h"

#include <algorithm>

namespace mrt {

std::vector<TilesetTile> tileset_tiles(const LodSet& set)
{
    std::vector<TilesetTile> out(set.tiles.size());
    for (std::size_t k = 0; k < set.tiles.size(); ++k) {
        const LodTile& t = set.tiles[k];
        out[k].mesh = t.mesh.n_faces() > 0 ? &t.mesh : nullptr;
        out[k].box = t.box;
        out[k].geometric_error = t.geometric_error;
        out[k].children = t.children;
    }
    return out;
}

QuantizationGrid tileset_grid(const LodSet& set)
{
    BoundingBox box = set.tiles.empty() ? BoundingBox{} : set.tiles[0].box;
    bool any = false;
    for (const LodTile& t : set.tiles)
        for (const auto v : t.mesh.vertices()) {
            const Vec3 p = to_vec3(t.mesh.point(v));
            box.min = any ? min(box.min, p) : p;
            box.max = any ? max(box.max, p) : p;
            any = true;
        }
    // Padded: positions reach the encoder as floats relative to the grid, and a vertex on the box's
    // face may round to just outside it.
    const double side = std::max(box.largest_side(), 1e-12);
    QuantizationGrid grid;
    grid.min = box.min - Vec3{1, 1, 1} * (1e-6 * side);
    grid.range = side * (1.0 + 2e-6);
    return grid;
}

void write_lod_tileset(const LodSet& set, const Vec3& origin, const std::filesystem::path& dir, TilesetOptions options)
{
    if (set.tiles.empty())
        throw InvalidInput(dir.string() + ": the LOD set has no tiles (was it made with tileset = false?)");
    if (options.gltf.draco && !options.gltf.draco_options.grid)
        options.gltf.draco_options.grid = tileset_grid(set);
    write_3d_tiles(tileset_tiles(set), origin, dir, options);
}

} // namespace mrt
