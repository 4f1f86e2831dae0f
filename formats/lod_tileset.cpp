// Bridge from the LOD set chosen in libmrtile (which tiles, which errors) to the 3D Tiles writer
// (how they are serialised): kept apart so the writer stays a pure serialiser.
#include "formats/lod_tileset.h"

#include "libmrtile/errors.h"
#include "libmrtile/parallel.h"

#include <algorithm>
#include <cmath>
#include <string>

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
        out[k].skirt_faces = t.skirt_faces; // extract_region adds them last (lod_set.cpp)
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

int tileset_position_bits(const Hierarchy& h, const LodSet& set, const QuantizationGrid& grid, double unit_scale, int least)
{
    if (least < 1 || least > kMaxPositionBits)
        throw InvalidInput("tileset_position_bits: least must lie in [1, " + std::to_string(kMaxPositionBits) + "]");
    if (!(unit_scale > 0.0) || !std::isfinite(unit_scale))
        throw InvalidInput("tileset_position_bits: unit_scale must be positive and finite");
    if (set.levels.empty() || !(grid.range > 0.0))
        return least;
    check_node_ids(h, set.levels.back().cut);
    double sum = 0.0, points = 0.0;
    for (const std::int32_t id : set.levels.back().cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        sum += n.rms_plane_distance * static_cast<double>(n.count());
        points += static_cast<double>(n.count());
    }
    const double accuracy = points > 0.0 ? unit_scale * sum / points : 0.0;
    if (!(accuracy > 0.0))
        return least;
    const double largest_step = 0.5 * accuracy / (0.5 * std::sqrt(3.0));
    int bits = least;
    while (bits < kMaxPositionBits && grid.range / (std::ldexp(1.0, bits) - 1.0) > largest_step)
        ++bits;
    return bits;
}

GeoPlacement georeference(LodSet& set, const Vec3& origin, const BoundingBox& model_box, const ProjectedCrs& crs,
                          double height_offset)
{
    if (!std::isfinite(height_offset))
        throw InvalidInput("georeference: height offset is not finite");
    const TransverseMercator& tm = crs.projection;
    const Vec3 centre = origin + model_box.centre();
    GeoPlacement placement;
    const auto geodetic = [&](const Vec3& q) {
        Geodetic g = projected_to_geodetic(tm, q.x, q.y, q.z);
        g.height += height_offset;
        return g;
    };
    placement.anchor = geodetic(centre);
    placement.root_transform = enu_to_ecef_transform(placement.anchor.longitude_deg, placement.anchor.latitude_deg,
                                                     placement.anchor.height);
    const EnuFrame frame(tm.ellipsoid, placement.anchor);
    const auto to_enu = [&](const Vec3& p) {
        const Vec3 q = origin + p;
        return frame.ecef_to_enu(geodetic_to_ecef(tm.ellipsoid, geodetic(q)));
    };
    // A box's image is curved (the Earth drops away from the anchor's tangent plane): its corners'
    // box is padded by the largest sag across it, side^2 / (2 R), R a lower bound of the Earth's radius.
    const auto corner_box = [&](const BoundingBox& b) {
        BoundingBox out;
        for (int c = 0; c < 8; ++c) {
            const Vec3 corner{(c & 1) ? b.max.x : b.min.x, (c & 2) ? b.max.y : b.min.y, (c & 4) ? b.max.z : b.min.z};
            const Vec3 e = to_enu(corner);
            out.min = c == 0 ? e : min(out.min, e);
            out.max = c == 0 ? e : max(out.max, e);
        }
        const double side = b.diagonal() * tm.unit_to_metre;
        const double pad = side * side / (2.0 * 6.3e6) + 1e-6 * side;
        out.min = out.min - Vec3{pad, pad, pad};
        out.max = out.max + Vec3{pad, pad, pad};
        return out;
    };
    run_parallel(set.tiles.size(), 0, [&](std::size_t k) {
        LodTile& tile = set.tiles[k];
        BoundingBox box = corner_box(tile.box);
        // Normals: through the map's Jacobian at the tile's centre (a tile spans far less than the
        // distance over which the grid's convergence changes noticeably).
        const Vec3 c = tile.box.centre();
        const Vec3 fc = to_enu(c);
        const double step = std::max(tile.box.diagonal(), 1e-3);
        const Vec3 jx = (to_enu(c + Vec3{step, 0, 0}) - fc) / step;
        const Vec3 jy = (to_enu(c + Vec3{0, step, 0}) - fc) / step;
        const Vec3 jz = (to_enu(c + Vec3{0, 0, step}) - fc) / step;
        Mesh& mesh = tile.mesh;
        for (const auto v : mesh.vertices()) {
            const Vec3 p = to_enu(to_vec3(mesh.point(v)));
            mesh.set_point(v, to_point(p));
            box.min = min(box.min, p);
            box.max = max(box.max, p);
            if (mesh.has_vertex_normals()) {
                const Vec3 n = to_vec3(mesh.normal(v));
                mesh.set_normal(v, to_point(normalized(jx * n.x + jy * n.y + jz * n.z)));
            }
        }
        mesh.update_face_normals();
        tile.box = box;
        tile.geometric_error *= tm.unit_to_metre;
    });
    nest_tile_boxes(set.tiles);
    return placement;
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
