// Output stage, streaming format: a cut of the hierarchy per level, split into tiles, becomes a 3D Tiles
// 1.1 tileset (REPLACE refinement: a finer tile replaces its parent once the parent's geometric error
// is too large on screen), which Cesium and other clients stream. Serialization only; the tile tree is
// the caller's. The directory is built aside and swapped into place so that a reader never sees a
// half-written tileset and a failure never destroys the previous one.
#include "formats/write_3d_tiles.h"

#include "libmrtile/atomic_file.h"
#include "libmrtile/errors.h"
#include "libmrtile/georef.h"
#include "libmrtile/parallel.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <system_error>

namespace mrt {

namespace {

using Json = nlohmann::ordered_json;
namespace fs = std::filesystem;

// Input frame -> tileset frame (z-up): through the glTF y-up frame, then the y-up -> z-up rotation
// that clients apply to glTF content.
Vec3 to_tileset_frame(const Vec3& v, UpAxis up)
{
    return from_output_frame(to_output_frame(v, up), UpAxis::Z);
}

void validate_tree(const std::vector<TilesetTile>& tiles)
{
    if (tiles.empty())
        throw InvalidInput("write_3d_tiles: no tiles (tiles[0] must be the root)");
    std::vector<char> seen(tiles.size(), 0);
    std::vector<std::size_t> stack{0};
    seen[0] = 1;
    while (!stack.empty()) {
        const std::size_t t = stack.back();
        stack.pop_back();
        const TilesetTile& tile = tiles[t];
        const std::string name = "write_3d_tiles: tile " + std::to_string(t);
        if (!std::isfinite(tile.geometric_error) || tile.geometric_error < 0.0)
            throw InvalidInput(name + ": geometric_error must be finite and >= 0");
        if (!is_finite(tile.box.min) || !is_finite(tile.box.max) || tile.box.min.x > tile.box.max.x ||
            tile.box.min.y > tile.box.max.y || tile.box.min.z > tile.box.max.z)
            throw InvalidInput(name + ": box must be finite with min <= max");
        for (const std::size_t c : tile.children) {
            if (c >= tiles.size())
                throw InvalidInput(name + ": child index " + std::to_string(c) + " out of range");
            if (seen[c])
                throw InvalidInput(name + ": child " + std::to_string(c) + " has two parents or closes a cycle");
            if (tiles[c].geometric_error > tile.geometric_error)
                throw InvalidInput(name + ": child " + std::to_string(c) +
                                   " has a larger geometric_error than its parent (REPLACE refinement needs "
                                   "errors that never grow towards the leaves)");
            seen[c] = 1;
            stack.push_back(c);
        }
    }
    for (std::size_t t = 0; t < tiles.size(); ++t)
        if (!seen[t])
            throw InvalidInput("write_3d_tiles: tile " + std::to_string(t) + " is not reachable from the root");
}

// Draco moves a vertex by up to half a quantization step, so a vertex on the box's face could decode
// just outside it: the box is enlarged by one step (of the shared grid, or of the largest cube Draco
// can choose for content inside this box).
double quantization_padding(const BoundingBox& box, const GltfOptions& gltf)
{
    if (!gltf.draco) {
        // Plain tiles hold float32 positions relative to the tileset's one offset: a vertex on the box
        // rounds by up to half a float step of the largest stored coordinate (QA round 57: up to 2e-5
        // of a half-axis outside, in small tiles far from the offset). One step of padding holds it.
        if (!gltf.offset)
            return 0.0;
        const Vec3 a = to_output_frame(box.min, gltf.up_axis) - *gltf.offset, b = to_output_frame(box.max, gltf.up_axis) - *gltf.offset;
        const double largest = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z), std::abs(b.x), std::abs(b.y), std::abs(b.z)});
        return std::ldexp(largest, -23);
    }
    const DracoOptions& d = gltf.draco_options;
    const double cube = d.grid ? d.grid->range : box.largest_side();
    return cube / (std::ldexp(1.0, d.position_bits) - 1.0);
}

Json box_json(const BoundingBox& box, const GltfOptions& gltf)
{
    const UpAxis up = gltf.up_axis;
    const double pad = quantization_padding(box, gltf);
    const Vec3 a = to_tileset_frame(box.min, up), b = to_tileset_frame(box.max, up);
    const Vec3 lo = min(a, b) - Vec3{pad, pad, pad}, hi = max(a, b) + Vec3{pad, pad, pad};
    const Vec3 c = (lo + hi) * 0.5, h = (hi - lo) * 0.5;
    return Json::array({c.x, c.y, c.z, h.x, 0.0, 0.0, 0.0, h.y, 0.0, 0.0, 0.0, h.z});
}

std::string content_uri(std::size_t tile) { return "tiles/" + std::to_string(tile) + ".glb"; }

Json tile_json(const std::vector<TilesetTile>& tiles, std::size_t t, const GltfOptions& gltf)
{
    const TilesetTile& tile = tiles[t];
    Json out;
    out["boundingVolume"] = Json{{"box", box_json(tile.box, gltf)}};
    out["geometricError"] = tile.geometric_error;
    if (tile.mesh != nullptr)
        out["content"] = Json{{"uri", content_uri(t)}};
    if (!tile.children.empty()) {
        Json children = Json::array();
        for (const std::size_t c : tile.children)
            children.push_back(tile_json(tiles, c, gltf));
        out["children"] = std::move(children);
    }
    return out;
}

// The first entry of an existing output directory that a tileset of ours would not hold (anything but
// tileset.json and tiles/<number>.glb), or "" if there is none. Replacing the directory removes it
// as a whole, so a user's own files in it must stop the write.
std::string foreign_entry(const fs::path& dir)
{
    std::error_code ec;
    auto is_tile_name = [](const std::string& name) {
        const std::size_t dot = name.find('.');
        return dot > 0 && dot != std::string::npos && name.substr(dot) == ".glb" &&
               std::all_of(name.begin(), name.begin() + static_cast<std::ptrdiff_t>(dot),
                           [](char c) { return c >= '0' && c <= '9'; });
    };
    for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
        const std::string name = entry.path().filename().string();
        if (name == "tileset.json" && entry.is_regular_file(ec))
            continue;
        if (name == "tiles" && entry.is_directory(ec) && !entry.is_symlink(ec)) {
            for (const fs::directory_entry& tile : fs::directory_iterator(entry.path(), ec))
                if (!tile.is_regular_file(ec) || !is_tile_name(tile.path().filename().string()))
                    return (fs::path("tiles") / tile.path().filename()).string();
            continue;
        }
        return name;
    }
    return ec ? std::string("an unreadable entry (" + ec.message() + ")") : std::string();
}

// Refuses to replace anything that is not a tileset of ours: the target is removed as a whole. A
// directory with files but no tileset.json is not one at all.
void check_replaceable(const fs::path& dir)
{
    std::error_code ec;
    if (fs::is_directory(dir, ec) && !fs::is_empty(dir, ec) && !fs::exists(dir / "tileset.json", ec))
        throw IoError(dir.string() + ": exists and is not a tileset (no tileset.json); refusing to replace it");
    check_replaceable_directory(dir, "tileset", foreign_entry);
}


} // namespace

void write_3d_tiles(const std::vector<TilesetTile>& tiles, const Vec3& origin, const fs::path& dir,
                    const TilesetOptions& options)
{
    validate_tree(tiles);
    if (!is_finite(origin))
        throw InvalidInput(dir.string() + ": the tileset origin is not finite");
    check_up_axis(options.gltf.up_axis);
    const UpAxis up = options.gltf.up_axis;
    if (options.root_transform)
        for (const double v : *options.root_transform)
            if (!std::isfinite(v))
                throw InvalidInput("TilesetOptions::root_transform: non-finite entry");

    check_replaceable(dir);
    // Built aside and swapped into place; on failure (or a signal) the half-built directory goes.
    const TemporaryDirectory temporary(dir);
    const fs::path& built = temporary.path();
    temporary.write([&] { ensure_directory(built / "tiles"); });
    // One float offset for every tile (unless a Draco grid sets one): a border vertex that two tiles
    // share is then stored as the same float in both. Per-file offsets (each tile's own centre) left
    // 749 of 992 shared vertices of two terrain tiles a float ulp apart (QA, session 19).
    GltfOptions gltf = options.gltf;
    if (!gltf.offset && !(gltf.draco && gltf.draco_options.grid) && !tiles.empty()) {
        const Vec3 c = to_output_frame(tiles.front().box.centre(), gltf.up_axis);
        gltf.offset = Vec3{std::round(c.x), std::round(c.y), std::round(c.z)};
    }
    // Each tile is its own file, so they are encoded and written in parallel (Draco encoding is
    // most of an export's time). A failure is reported for the lowest failing tile, as a serial
    // loop would, whatever the thread count.
    std::vector<std::exception_ptr> failures(tiles.size());
    run_parallel(tiles.size(), options.threads, [&](std::size_t t) {
        if (tiles[t].mesh == nullptr)
            return;
        try {
            // Origin 0: the positions stay relative to the tileset origin, which the root
            // transform carries; the shared offset keeps float precision.
            GltfOptions content = gltf;
            content.skirt_faces = tiles[t].skirt_faces;
            write_gltf(*tiles[t].mesh, Vec3{}, built / content_uri(t), content);
        } catch (const InvalidInput& e) {
            failures[t] = std::make_exception_ptr(
                InvalidInput("write_3d_tiles: tile " + std::to_string(t) + ": " + e.what()));
        } catch (...) {
            failures[t] = std::current_exception();
        }
    });
    temporary.write([&] {
        for (const std::exception_ptr& failure : failures)
            if (failure)
                std::rethrow_exception(failure);
    });

    Json root = tile_json(tiles, 0, gltf); // with the offset the contents were written with
    std::array<double, 16> transform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    if (options.root_transform) {
        transform = *options.root_transform;
    } else {
        const Vec3 t = to_tileset_frame(origin, up);
        transform[12] = t.x;
        transform[13] = t.y;
        transform[14] = t.z;
    }
    Json ordered_root;
    ordered_root["boundingVolume"] = root["boundingVolume"];
    ordered_root["geometricError"] = root["geometricError"];
    ordered_root["refine"] = "REPLACE";
    ordered_root["transform"] = transform;
    for (const char* key : {"content", "children"})
        if (root.contains(key))
            ordered_root[key] = root[key];

    const TilesetTile& r = tiles[0];
    const double top_error = options.tileset_geometric_error
                                 ? *options.tileset_geometric_error
                                 : std::max(r.geometric_error, r.box.diagonal());
    if (!std::isfinite(top_error) || top_error < r.geometric_error)
        throw InvalidInput("TilesetOptions::tileset_geometric_error: must be finite and >= the root's error");
    Json tileset;
    tileset["asset"] = Json{{"version", "1.1"}, {"generator", "libmrtile"}};
    tileset["geometricError"] = top_error;
    tileset["root"] = std::move(ordered_root);
    temporary.write([&] { write_file_atomically(built / "tileset.json", tileset.dump(1) + "\n"); });
    replace_directory(built, dir, "tileset");
}

void check_tileset_directory(const fs::path& dir)
{
    check_replaceable(dir);
    check_writable_directory(dir);
}

std::array<double, 16> enu_to_ecef_transform(double longitude_deg, double latitude_deg, double height)
{
    if (!std::isfinite(longitude_deg) || !std::isfinite(latitude_deg) || !std::isfinite(height) ||
        std::fabs(latitude_deg) > 90.0)
        throw InvalidInput("enu_to_ecef_transform: longitude/latitude/height must be finite, |latitude| <= 90");
    return EnuFrame(Ellipsoid{}, Geodetic{longitude_deg, latitude_deg, height}).enu_to_ecef(); // WGS 84
}

} // namespace mrt
