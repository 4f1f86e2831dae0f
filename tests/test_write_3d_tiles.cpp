// Tests of write_3d_tiles.h: a three-level tileset (plain and Draco on a shared grid with an ENU->ECEF
// root transform) checked structurally by tests/npm/tileset_check.mjs, whose contents the Khronos
// validator and draco3d check; safe directory replacement; determinism; the ENU->ECEF matrix.
// OpenMesh copies a default-constructed (uninitialized) VectorT when a vertex is added; the fixtures set
// every value they use right after, so GCC's warning about that copy does not apply.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "formats/write_3d_tiles.h"
#include "libmrtile/errors.h"
#include "mesh_fixtures.h"
#include "npm/node_clients.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

namespace mrt {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::grid_mesh;

const Vec3 kOrigin{4.5e6, 5.5e6, 300.0};

std::string read_bytes(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

fs::path scratch_dir()
{
    return fs::path(MRTILE_BINARY_DIR) / ("test_write_3d_tiles." + std::to_string(::getpid()));
}

// A root over [0,8]^2 (step 1), four quadrant children (step 0.5), and four grandchildren under the
// first quadrant (step 0.25): neighbours share border vertices exactly. z = wave in [-0.25, 0.25].
struct Pyramid
{
    std::vector<std::unique_ptr<Mesh>> meshes;
    std::vector<TilesetTile> tiles;

    Pyramid()
    {
        auto add = [&](double x0, double y0, double size, double step, double error) {
            const int n = static_cast<int>(size / step);
            meshes.push_back(std::make_unique<Mesh>(grid_mesh(n, n, x0, y0, step, testing::wave)));
            TilesetTile tile;
            tile.mesh = meshes.back().get();
            tile.box = BoundingBox{{x0, y0, -0.3}, {x0 + size, y0 + size, 0.3}};
            tile.geometric_error = error;
            tiles.push_back(tile);
            return tiles.size() - 1;
        };
        add(0, 0, 8, 1.0, 1.0);
        for (int q = 0; q < 4; ++q) {
            const std::size_t child = add(4.0 * (q % 2), 4.0 * (q / 2), 4, 0.5, 0.5); // add() grows tiles
            tiles[0].children.push_back(child);
        }
        for (int q = 0; q < 4; ++q) {
            const std::size_t child = add(2.0 * (q % 2), 2.0 * (q / 2), 2, 0.25, 0.0);
            tiles[1].children.push_back(child);
        }
    }
};

TilesetOptions draco_options()
{
    TilesetOptions options;
    options.gltf.draco = true;
    options.gltf.draco_options.grid = QuantizationGrid{{-1, -1, -1}, 10.0};
    options.root_transform = enu_to_ecef_transform(8.54, 47.37, 400.0);
    return options;
}

class Tilesets : public ::testing::Test
{
protected:
    static void SetUpTestSuite()
    {
        fs::remove_all(scratch_dir());
        fs::create_directories(scratch_dir());
        pyramid_ = new Pyramid;
        write_3d_tiles(pyramid_->tiles, kOrigin, scratch_dir() / "plain", TilesetOptions{});
        write_3d_tiles(pyramid_->tiles, kOrigin, scratch_dir() / "draco", draco_options());
    }
    static void TearDownTestSuite()
    {
        delete pyramid_;
        std::error_code ec;
        fs::remove_all(scratch_dir(), ec);
    }
    static inline Pyramid* pyramid_ = nullptr;
};

// Tests of their own scratch directories: each removes this process's scratch directory when it ends
// (ctest runs every test in a process of its own, and left them behind in the build tree).
class WriteTilesets : public ::testing::Test
{
protected:
    void TearDown() override
    {
        std::error_code ec;
        fs::remove_all(scratch_dir(), ec);
    }
};

// The node structural check: 1.1 asset, refine on the root, errors never growing, child boxes inside
// parent boxes, every content present, valid (no validator error or warning; the only infos are
// those of the Draco extension, see test_write_gltf) and inside its tile's box.
TEST_F(Tilesets, pass_the_structural_check_and_every_content_validates)
{
    const json results = testing::run_node_script(
        "tileset_check.mjs", {(scratch_dir() / "plain").string(), (scratch_dir() / "draco").string()});
    ASSERT_EQ(results.size(), 2u);
    for (const json& r : results) {
        SCOPED_TRACE(r["dir"].get<std::string>());
        EXPECT_TRUE(r["problems"].empty()) << r["problems"].dump(1);
        EXPECT_EQ(r["tiles"], 9);
        EXPECT_EQ(r["contents"], 9);
        ASSERT_EQ(r["validation"].size(), 9u);
        const bool draco = r["dir"].get<std::string>().find("draco") != std::string::npos;
        for (const json& v : r["validation"]) {
            EXPECT_EQ(v["errors"], 0) << v.dump(1);
            EXPECT_EQ(v["warnings"], 0) << v.dump(1);
            EXPECT_EQ(v["infos"], draco ? 2 : 0) << v.dump(1); // UNSUPPORTED_EXTENSION + UNUSED_OBJECT
        }
        EXPECT_EQ(r["draco"].size(), draco ? 9u : 0u);
    }
}

TEST_F(Tilesets, tileset_json_has_the_expected_frame_and_boxes)
{
    const json plain = json::parse(read_bytes(scratch_dir() / "plain" / "tileset.json"));
    EXPECT_EQ(plain["asset"]["version"], "1.1");
    EXPECT_DOUBLE_EQ(plain["geometricError"].get<double>(), std::sqrt(128.36)); // root box diagonal > root error
    const json& root = plain["root"];
    EXPECT_EQ(root["refine"], "REPLACE");
    EXPECT_EQ(root["transform"], json::array({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, kOrigin.x, kOrigin.y, kOrigin.z, 1}));
    // The box padded by one float step of the largest stored coordinate (4 from the tiles' offset):
    // float32 positions round outward by up to half of that (QA round 57).
    const std::vector<double> box = root["boundingVolume"]["box"].get<std::vector<double>>();
    const std::vector<double> exact{4, 4, 0, 4, 0, 0, 0, 4, 0, 0, 0, 0.3};
    ASSERT_EQ(box.size(), exact.size());
    for (std::size_t k = 0; k < box.size(); ++k) {
        EXPECT_NEAR(box[k], exact[k], 1e-6) << k;
        if (exact[k] > 0.0 && k >= 3) {
            EXPECT_GT(box[k], exact[k]) << k; // half-axes grow
        }
    }
    EXPECT_EQ(root["content"]["uri"], "tiles/0.glb");
    ASSERT_EQ(root["children"].size(), 4u);
    EXPECT_EQ(root["children"][0]["children"][3]["content"]["uri"], "tiles/8.glb");
    EXPECT_EQ(root["children"][0]["children"][3]["geometricError"], 0.0);
    EXPECT_FALSE(root["children"][0].contains("refine")); // inherited from the root
    const json draco = json::parse(read_bytes(scratch_dir() / "draco" / "tileset.json"));
    const std::array<double, 16> enu = enu_to_ecef_transform(8.54, 47.37, 400.0);
    EXPECT_EQ(draco["root"]["transform"], json(enu));
}

// The Draco tiles share one quantization grid (and hence one per-file offset): the border x = 4 between
// the root's first and second quadrant decodes to the same float bits in both tiles.
TEST_F(Tilesets, draco_tiles_on_a_shared_grid_have_bit_identical_borders)
{
    auto decode_tile = [](int tile, std::vector<double>& translation) {
        const std::string glb = read_bytes(scratch_dir() / "draco" / "tiles" / (std::to_string(tile) + ".glb"));
        std::uint32_t length = 0;
        std::memcpy(&length, glb.data() + 12, 4);
        const json doc = json::parse(glb.substr(20, length));
        translation = doc["nodes"][0]["translation"].get<std::vector<double>>();
        const json& view = doc["bufferViews"][doc["meshes"][0]["primitives"][0]["extensions"]
                                                  ["KHR_draco_mesh_compression"]["bufferView"].get<std::size_t>()];
        const std::size_t bin = 20 + length + 8;
        return decode_draco(glb.substr(bin + view.value("byteOffset", std::size_t{0}), view["byteLength"]), "tile");
    };
    std::vector<double> ta, tb;
    const DracoDecoded a = decode_tile(1, ta), b = decode_tile(2, tb);
    EXPECT_EQ(ta, tb);
    // y-up decoded positions: the border x = 4 (same in both frames) - translation.
    std::vector<std::array<float, 3>> border_a, border_b;
    for (std::size_t i = 0; i < a.positions.size() / 3; ++i)
        if (std::fabs(a.positions[3 * i] + ta[0] - 4.0) < 1e-3)
            border_a.push_back({a.positions[3 * i], a.positions[3 * i + 1], a.positions[3 * i + 2]});
    for (std::size_t i = 0; i < b.positions.size() / 3; ++i)
        if (std::fabs(b.positions[3 * i] + tb[0] - 4.0) < 1e-3)
            border_b.push_back({b.positions[3 * i], b.positions[3 * i + 1], b.positions[3 * i + 2]});
    ASSERT_EQ(border_a.size(), 9u);
    std::sort(border_a.begin(), border_a.end());
    std::sort(border_b.begin(), border_b.end());
    EXPECT_EQ(border_a, border_b); // exact float equality
}

// Plain tiles are stored on one float offset too: two tiles of a terrain, meeting at x = 169.7 with
// vertices 0.7 apart (no short binary fractions), store their shared border as the same
// world positions, float + translation, bit for bit. With each tile's own centre as its offset, the
// floats of the two sides rounded differently (QA, session 19: 749 of 992 shared vertices off by an ulp).
TEST_F(WriteTilesets, plain_tiles_share_their_border_bit_for_bit)
{
    const fs::path dir = scratch_dir().string() + ".plain_borders";
    fs::remove_all(dir);
    const double step = 0.7, x0 = -40.3;
    const int n = 300;
    Mesh left = grid_mesh(n, 20, x0, 11.1, step, testing::wave);
    // Starts where left ends, a third as wide: the border lies 105 from one tile's centre and 35 from
    // the other's, where floats have different spacings.
    Mesh right = grid_mesh(n / 3, 20, x0 + n * step, 11.1, step, testing::wave);
    std::vector<TilesetTile> tiles(3);
    tiles[1].mesh = &left;
    tiles[1].box = BoundingBox{{x0, 11.1, -0.3}, {x0 + n * step, 11.1 + 20 * step, 0.3}};
    tiles[2].mesh = &right;
    tiles[2].box = BoundingBox{{x0 + n * step, 11.1, -0.3}, {x0 + (n + n / 3) * step, 11.1 + 20 * step, 0.3}};
    tiles[0].box = BoundingBox{tiles[1].box.min, tiles[2].box.max};
    tiles[0].geometric_error = 1.0;
    tiles[0].children = {1, 2};
    write_3d_tiles(tiles, kOrigin, dir, TilesetOptions{});
    auto world_positions = [&](int tile) {
        const std::string glb = read_bytes(dir / "tiles" / (std::to_string(tile) + ".glb"));
        std::uint32_t length = 0;
        std::memcpy(&length, glb.data() + 12, 4);
        const json doc = json::parse(glb.substr(20, length));
        const std::vector<double> t = doc["nodes"][0].value("translation", std::vector<double>{0, 0, 0});
        const json& accessor = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<std::size_t>()];
        const json& view = doc["bufferViews"][accessor["bufferView"].get<std::size_t>()];
        const std::size_t start = 20 + length + 8 + view.value("byteOffset", std::size_t{0}) + accessor.value("byteOffset", std::size_t{0});
        std::vector<std::array<double, 3>> out(accessor["count"].get<std::size_t>());
        for (std::size_t i = 0; i < out.size(); ++i) {
            float p[3];
            std::memcpy(p, glb.data() + start + 12 * i, 12);
            out[i] = {p[0] + t[0], p[1] + t[1], p[2] + t[2]};
        }
        return out;
    };
    const auto a = world_positions(1), b = world_positions(2);
    // glTF is y-up: the input's x stays x. The border: x within a few mm of x0 + n step.
    const double border = x0 + n * step;
    std::vector<std::array<double, 3>> side_a, side_b;
    for (const auto& p : a)
        if (std::fabs(p[0] - border) < 1e-3)
            side_a.push_back(p);
    for (const auto& p : b)
        if (std::fabs(p[0] - border) < 1e-3)
            side_b.push_back(p);
    ASSERT_EQ(side_a.size(), 21u);
    std::sort(side_a.begin(), side_a.end());
    std::sort(side_b.begin(), side_b.end());
    EXPECT_EQ(side_a, side_b); // exact equality
    fs::remove_all(dir);
}

TEST_F(Tilesets, output_is_byte_deterministic)
{
    const fs::path again = scratch_dir() / "draco_again";
    write_3d_tiles(pyramid_->tiles, kOrigin, again, draco_options());
    std::size_t files = 0;
    for (const auto& entry : fs::recursive_directory_iterator(scratch_dir() / "draco")) {
        if (!entry.is_regular_file())
            continue;
        ++files;
        const fs::path relative = fs::relative(entry.path(), scratch_dir() / "draco");
        EXPECT_EQ(read_bytes(entry.path()), read_bytes(again / relative)) << relative;
    }
    EXPECT_EQ(files, 10u);
}

std::vector<std::string> listing(const fs::path& dir)
{
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// A failed write leaves the previous tileset untouched and nothing beside it; a successful one
// replaces it whole; a directory that is not a tileset is never replaced.
// Each tile's skirt_faces reach its content: the tile's last faces become a second, single-sided
// primitive (GltfOptions::skirt_faces); a tile without skirts keeps one primitive.
TEST_F(WriteTilesets, each_tiles_skirts_are_its_own)
{
    Pyramid pyramid;
    pyramid.tiles[2].skirt_faces = 12;
    pyramid.tiles[6].skirt_faces = 30;
    fs::create_directories(scratch_dir());
    const fs::path dir = scratch_dir() / "skirts";
    write_3d_tiles(pyramid.tiles, kOrigin, dir);
    for (std::size_t t = 0; t < pyramid.tiles.size(); ++t) {
        const std::string bytes = read_bytes(dir / "tiles" / (std::to_string(t) + ".glb"));
        std::uint32_t length = 0;
        std::memcpy(&length, bytes.data() + 12, 4);
        const json doc = json::parse(bytes.substr(20, length));
        const json& primitives = doc["meshes"][0]["primitives"];
        const std::size_t skirts = pyramid.tiles[t].skirt_faces;
        ASSERT_EQ(primitives.size(), skirts > 0 ? 2u : 1u) << t;
        const std::size_t faces = pyramid.tiles[t].mesh->n_faces();
        EXPECT_EQ(doc["accessors"][primitives[0]["indices"].get<std::size_t>()]["count"], 3 * (faces - skirts)) << t;
        if (skirts > 0) {
            EXPECT_EQ(doc["accessors"][primitives[1]["indices"].get<std::size_t>()]["count"], 3 * skirts) << t;
            EXPECT_FALSE(doc["materials"][primitives[1]["material"].get<std::size_t>()]["doubleSided"].get<bool>()) << t;
        }
        EXPECT_TRUE(doc["materials"][primitives[0]["material"].get<std::size_t>()]["doubleSided"].get<bool>()) << t;
    }
}

TEST_F(WriteTilesets, replace_only_on_success)
{
    const fs::path base = scratch_dir() / "replace";
    fs::remove_all(base);
    fs::create_directories(base);
    const fs::path dir = base / "tiles_out";
    Pyramid pyramid;
    write_3d_tiles(pyramid.tiles, kOrigin, dir);
    const std::string before = read_bytes(dir / "tileset.json");

    std::vector<TilesetTile> growing = pyramid.tiles;
    growing[5].geometric_error = 2.0; // larger than its parent's 0.5
    EXPECT_THROW(write_3d_tiles(growing, kOrigin, dir), InvalidInput);
    Mesh empty;
    std::vector<TilesetTile> bad_content = pyramid.tiles;
    bad_content[7].mesh = &empty; // fails while the contents are written
    EXPECT_THROW(write_3d_tiles(bad_content, kOrigin, dir), InvalidInput);
    EXPECT_EQ(read_bytes(dir / "tileset.json"), before);
    EXPECT_EQ(listing(base), std::vector<std::string>{"tiles_out"});

    std::vector<TilesetTile> root_only{pyramid.tiles[0]};
    root_only[0].children.clear();
    write_3d_tiles(root_only, kOrigin, dir);
    EXPECT_EQ(listing(dir / "tiles"), std::vector<std::string>{"0.glb"});
    EXPECT_EQ(listing(base), std::vector<std::string>{"tiles_out"});

    const fs::path precious = base / "precious";
    fs::create_directories(precious);
    std::ofstream(precious / "notes.txt") << "keep me";
    EXPECT_THROW(write_3d_tiles(root_only, kOrigin, precious), IoError);
    EXPECT_EQ(read_bytes(precious / "notes.txt"), "keep me");
    fs::remove_all(base);
}

TEST_F(WriteTilesets, bad_paths_throw_io_error_naming_the_path_and_leave_nothing)
{
    Pyramid pyramid;
    const fs::path base = scratch_dir() / "bad";
    fs::remove_all(base);
    fs::create_directories(base);
    std::ofstream(base / "file") << "x";
    for (const fs::path& dir : {base / "missing" / "out", base / "file" / "out", base / "file", fs::path("/proc/mrtile_tiles")}) {
        try {
            write_3d_tiles(pyramid.tiles, kOrigin, dir);
            ADD_FAILURE() << "no exception for " << dir;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
        }
    }
    EXPECT_EQ(listing(base), std::vector<std::string>{"file"});
    fs::remove_all(scratch_dir() / "bad");
}

TEST_F(WriteTilesets, rejects_malformed_trees)
{
    Pyramid pyramid;
    const fs::path dir = scratch_dir() / "never";
    auto expect_invalid = [&](std::vector<TilesetTile> tiles) {
        EXPECT_THROW(write_3d_tiles(tiles, kOrigin, dir), InvalidInput);
        EXPECT_FALSE(fs::exists(dir));
    };
    expect_invalid({});
    auto cycle = pyramid.tiles;
    cycle[5].children.push_back(1);
    expect_invalid(cycle);
    auto unreachable = pyramid.tiles;
    unreachable[1].children.pop_back();
    expect_invalid(unreachable);
    auto out_of_range = pyramid.tiles;
    out_of_range[2].children.push_back(99);
    expect_invalid(out_of_range);
    auto negative = pyramid.tiles;
    negative[3].geometric_error = -1;
    expect_invalid(negative);
}

// ENU -> ECEF against closed forms of the WGS84 ellipsoid.
TEST(EnuToEcef, matches_the_wgs84_ellipsoid)
{
    const std::array<double, 16> m0 = enu_to_ecef_transform(0, 0, 0);
    const std::array<double, 16> expected0{0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 6378137.0, 0, 0, 1};
    for (std::size_t i = 0; i < 16; ++i)
        EXPECT_NEAR(m0[i], expected0[i], 1e-9) << i;
    const std::array<double, 16> pole = enu_to_ecef_transform(0, 90, 0);
    EXPECT_NEAR(pole[14], 6356752.314245179, 1e-6); // semi-minor axis b
    EXPECT_NEAR(std::hypot(pole[12], pole[13]), 0.0, 1e-6);

    const double lon = 8.54, lat = 47.37, h = 400.0;
    const std::array<double, 16> m = enu_to_ecef_transform(lon, lat, h);
    const std::array<double, 16> ground = enu_to_ecef_transform(lon, lat, 0);
    const double a = 6378137.0, b = 6356752.314245179;
    EXPECT_NEAR((ground[12] * ground[12] + ground[13] * ground[13]) / (a * a) + ground[14] * ground[14] / (b * b), 1.0, 1e-12);
    const Vec3 east{m[0], m[1], m[2]}, north{m[4], m[5], m[6]}, up{m[8], m[9], m[10]};
    EXPECT_NEAR(norm(east), 1.0, 1e-15);
    EXPECT_NEAR(norm(north), 1.0, 1e-15);
    EXPECT_NEAR(dot(east, north), 0.0, 1e-15);
    EXPECT_NEAR(distance(cross(east, north), up), 0.0, 1e-15); // right-handed
    // The height moves the anchor along the up vector.
    EXPECT_NEAR(distance(Vec3{m[12], m[13], m[14]}, Vec3{ground[12], ground[13], ground[14]} + up * h), 0.0, 1e-6);
    // North points towards the pole: increasing latitude moves the anchor along north.
    const std::array<double, 16> further = enu_to_ecef_transform(lon, lat + 1e-4, h);
    const Vec3 move = Vec3{further[12], further[13], further[14]} - Vec3{m[12], m[13], m[14]};
    EXPECT_GT(dot(normalized(move), north), 0.999999);
    EXPECT_THROW(enu_to_ecef_transform(0, 91, 0), InvalidInput);
}

} // namespace
} // namespace mrt
