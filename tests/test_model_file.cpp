// Tests of model_file.h: .mrt round trips are exact, and every kind of damage is rejected cleanly.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/lod_set.h"
#include "libmrtile/model_file.h"
#include "libmrtile/parallel.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"
#include "libmrtile/tiles.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <limits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <utility>

namespace mrt {
namespace {

namespace fs = std::filesystem;

Hierarchy sample(bool colors = false)
{
    PointCloud c = shapes::torus(3000);
    shapes::translate(c, {654321.0, 4321987.0, 120.0});
    recenter(c);
    if (colors)
        for (std::size_t i = 0; i < c.size(); ++i)
            c.colors.push_back({static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i * 7), 9, 255});
    return build_hierarchy(c);
}

fs::path temp_dir()
{
    const fs::path dir = fs::path(MRTILE_BINARY_DIR) / "test_model_file";
    fs::create_directories(dir);
    return dir;
}

// Serialise → parse → serialise gives the same bytes, and the parsed tree equals the original.
TEST(ModelFile, round_trip_is_byte_identical)
{
    for (bool colors : {false, true}) {
        const Hierarchy h = sample(colors);
        const std::string bytes = serialize_model(h);
        const Hierarchy back = deserialize_model(bytes, "memory");
        EXPECT_EQ(serialize_model(back), bytes);
        ASSERT_EQ(back.nodes.size(), h.nodes.size());
        EXPECT_EQ(back.cloud.origin, h.cloud.origin);
        EXPECT_EQ(back.input_index, h.input_index);
        EXPECT_EQ(back.cloud.colors, h.cloud.colors);
        for (std::size_t k = 0; k < h.nodes.size(); ++k) {
            EXPECT_EQ(back.nodes[k].moments.m2, h.nodes[k].moments.m2);
            EXPECT_EQ(back.nodes[k].frame.values, h.nodes[k].frame.values);
        }
        EXPECT_EQ(back.info.criterion, h.info.criterion);
        EXPECT_EQ(back.info.criterion_value, h.info.criterion_value);
    }
}

// The sensor's viewpoint (relative to the origin) is kept; an unknown flag is refused.
TEST(ModelFile, viewpoint_round_trip_and_unknown_flags)
{
    PointCloud c = shapes::torus(1500);
    c.viewpoint = Vec3{0.25, -3.5, 7.125};
    const Hierarchy h = build_hierarchy(c);
    const std::string bytes = serialize_model(h);
    const Hierarchy back = deserialize_model(bytes, "memory");
    ASSERT_TRUE(back.cloud.viewpoint.has_value());
    EXPECT_EQ(*back.cloud.viewpoint, *h.cloud.viewpoint);
    EXPECT_EQ(serialize_model(back), bytes);
    EXPECT_FALSE(deserialize_model(serialize_model(sample()), "memory").cloud.viewpoint.has_value());
    std::string unknown = bytes;
    unknown[20] = static_cast<char>(unknown[20] | 128); // flags: the u32 after magic, version, marker, header size
    try {
        deserialize_model(unknown, "m.mrt");
        ADD_FAILURE() << "an unknown flag was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("unknown flags"), std::string::npos) << e.what();
    }
}

// The input's coordinate system is kept as text; a damaged length is refused, not trusted.
TEST(ModelFile, crs_round_trip_and_damaged_length)
{
    PointCloud c = shapes::torus(1500);
    c.crs = "PROJCS[\"WGS 84 / UTM zone 33N\",AUTHORITY[\"EPSG\",\"32633\"]]";
    const Hierarchy h = build_hierarchy(c);
    EXPECT_EQ(h.cloud.crs, c.crs);
    const std::string bytes = serialize_model(h);
    const Hierarchy back = deserialize_model(bytes, "memory");
    EXPECT_EQ(back.cloud.crs, c.crs);
    EXPECT_EQ(serialize_model(back), bytes);
    EXPECT_TRUE(deserialize_model(serialize_model(sample()), "memory").cloud.crs.empty());
    // The length is the u32 before the text, which ends at the trailer (CRC + "MEND").
    const std::size_t length_at = bytes.size() - 8 - c.crs.size() - 4;
    for (const std::uint32_t bad : {0u, 0xffffffffu, static_cast<std::uint32_t>(c.crs.size() + 1)}) {
        std::string damaged = bytes;
        for (int k = 0; k < 4; ++k)
            damaged[length_at + static_cast<std::size_t>(k)] = static_cast<char>((bad >> (8 * k)) & 0xff);
        // A valid checksum, so that the length check itself is what refuses it.
        const std::size_t trailer = damaged.size() - 8;
        const uLong sum = crc32(0L, reinterpret_cast<const Bytef*>(damaged.data()), static_cast<uInt>(trailer));
        for (int k = 0; k < 4; ++k)
            damaged[trailer + static_cast<std::size_t>(k)] = static_cast<char>((sum >> (8 * k)) & 0xff);
        try {
            deserialize_model(damaged, "m.mrt");
            ADD_FAILURE() << "CRS length " << bad << " accepted";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find("CRS"), std::string::npos) << e.what();
        }
    }
}

// A model built with merged duplicates (input indices beyond the stored point count) loads back.
TEST(ModelFile, merged_duplicates_round_trip)
{
    PointCloud c = shapes::torus(1500);
    const std::size_t distinct = c.size();
    for (std::size_t i = 0; i < distinct; i += 2)
        c.positions.push_back(c.positions[i]);
    std::reverse(c.positions.begin(), c.positions.end()); // first occurrences now at the end
    const Hierarchy h = build_hierarchy(c);
    ASSERT_EQ(h.cloud.size(), distinct);
    ASSERT_GT(*std::max_element(h.input_index.begin(), h.input_index.end()), distinct);
    const std::string bytes = serialize_model(h);
    const Hierarchy back = deserialize_model(bytes, "memory");
    EXPECT_EQ(back.input_index, h.input_index);
    EXPECT_EQ(serialize_model(back), bytes);
}

// Files on disk: save → load → save is byte-identical; two builds give identical files; the build
// time is stored only when asked for.
TEST(ModelFile, save_load_and_determinism)
{
    const fs::path a = temp_dir() / "a.mrt", b = temp_dir() / "b.mrt", c = temp_dir() / "c.mrt";
    save_model(sample(), a);
    save_model(sample(), b);
    save_model(load_model(a), c);
    auto read = [](const fs::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_EQ(read(a), read(b));
    EXPECT_EQ(read(a), read(c));
    EXPECT_TRUE(std::isnan(load_model(a).info.build_seconds));
    SaveOptions timed;
    timed.record_build_time = true;
    Hierarchy h = sample();
    h.info.build_seconds = 1.25;
    save_model(h, c, timed);
    EXPECT_EQ(load_model(c).info.build_seconds, 1.25);
}

// Levels small enough for a test: a 3,000-point torus with tiles of at most 512 triangles gives a
// few levels, coarse to fine.
StoredLevels sample_levels(const Hierarchy& h)
{
    LodSetOptions o;
    o.max_tile_triangles = 512;
    o.levels = 3;
    StoredLevels stored;
    stored.recipe = "test recipe";
    stored.levels = make_lod_levels(h, o);
    return stored;
}

// The same bytes again after a change: the CRC-32 of everything before the trailer.
void refresh_checksum(std::string& bytes)
{
    const std::size_t end = bytes.size() - 8;
    const auto value = static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(end)));
    for (int i = 0; i < 4; ++i)
        bytes[end + static_cast<std::size_t>(i)] = static_cast<char>((value >> (8 * i)) & 0xffu);
}

// `damaged`, its checksum made good, is refused with an IoError that names `name` and says `why`.
void expect_refused(std::string damaged, const std::string& name, const std::string& why, bool with_levels = false)
{
    refresh_checksum(damaged);
    try {
        if (with_levels)
            deserialize_model_with_levels(damaged, name);
        else
            deserialize_model(damaged, name);
        ADD_FAILURE() << "accepted; expected: " << why;
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
}

std::vector<std::array<int, 3>> corners(const Mesh& m)
{
    std::vector<std::array<int, 3>> faces;
    for (const auto f : m.faces()) {
        std::array<int, 3> c{};
        int k = 0;
        for (const auto v : m.fv_range(f))
            c[static_cast<std::size_t>(k++)] = v.idx();
        faces.push_back(c);
    }
    return faces;
}

// Stored levels come back exactly: every vertex, normal, colour, corner order and id, so that the tiles
// cut from them equal those of a LOD set meshed now; a model read without its levels skips them.
TEST(ModelFile, stored_levels_round_trip_exactly)
{
    for (bool colors : {false, true}) {
        const Hierarchy h = sample(colors);
        StoredLevels stored = sample_levels(h);
        ASSERT_GE(stored.levels.size(), 2u);
        SaveOptions options;
        options.levels = &stored;
        const std::string bytes = serialize_model(h, options);
        Model back = deserialize_model_with_levels(bytes, "memory");
        SaveOptions again;
        again.levels = &back.levels;
        EXPECT_EQ(serialize_model(back.hierarchy, again), bytes);
        EXPECT_EQ(serialize_model(deserialize_model(bytes, "memory")), serialize_model(h)); // levels skipped
        EXPECT_EQ(back.levels.recipe, "test recipe");
        ASSERT_EQ(back.levels.levels.size(), stored.levels.size());
        for (std::size_t l = 0; l < stored.levels.size(); ++l) {
            LodLevel& a = stored.levels[l];
            LodLevel& b = back.levels.levels[l];
            EXPECT_EQ(a.cut, b.cut);
            EXPECT_EQ(a.tolerance, b.tolerance);
            EXPECT_EQ(a.geometric_error, b.geometric_error);
            ASSERT_EQ(a.mesh.n_vertices(), b.mesh.n_vertices());
            EXPECT_EQ(corners(a.mesh), corners(b.mesh));
            EXPECT_EQ(b.mesh.has_vertex_colors(), colors);
            const auto tile_a = OpenMesh::getProperty<OpenMesh::FaceHandle, int>(a.mesh, kFaceTile);
            const auto tile_b = OpenMesh::getProperty<OpenMesh::FaceHandle, int>(b.mesh, kFaceTile);
            const auto gap_b = OpenMesh::getProperty<OpenMesh::FaceHandle, bool>(b.mesh, kFaceGap);
            const auto gap_a = OpenMesh::getProperty<OpenMesh::FaceHandle, bool>(a.mesh, kFaceGap);
            for (const auto f : a.mesh.faces()) {
                EXPECT_EQ(tile_a[f], tile_b[f]);
                EXPECT_EQ(gap_a[f], gap_b[f]);
                EXPECT_EQ(a.mesh.normal(f), b.mesh.normal(f));
            }
            const auto cluster_a = OpenMesh::getProperty<OpenMesh::VertexHandle, int>(a.mesh, kVertexCluster);
            const auto cluster_b = OpenMesh::getProperty<OpenMesh::VertexHandle, int>(b.mesh, kVertexCluster);
            for (const auto v : a.mesh.vertices()) {
                EXPECT_EQ(a.mesh.point(v), b.mesh.point(v));
                EXPECT_EQ(a.mesh.normal(v), b.mesh.normal(v));
                EXPECT_EQ(cluster_a[v], cluster_b[v]);
                if (colors) {
                    EXPECT_EQ(a.mesh.color(v), b.mesh.color(v));
                }
            }
        }
        // Tiles cut from the loaded levels are those of the set meshed from scratch.
        LodSetOptions o;
        o.max_tile_triangles = 512;
        o.levels = 3;
        const LodSet fresh = make_lod_set(h, o);
        const LodSet reused = make_lod_tiles(back.hierarchy, std::move(back.levels.levels), o);
        ASSERT_EQ(fresh.tiles.size(), reused.tiles.size());
        EXPECT_GT(fresh.tiles.size(), 2u);
        for (std::size_t t = 0; t < fresh.tiles.size(); ++t) {
            EXPECT_EQ(fresh.tiles[t].children, reused.tiles[t].children);
            EXPECT_EQ(corners(fresh.tiles[t].mesh), corners(reused.tiles[t].mesh));
            ASSERT_EQ(fresh.tiles[t].mesh.n_vertices(), reused.tiles[t].mesh.n_vertices());
            for (const auto v : fresh.tiles[t].mesh.vertices())
                EXPECT_EQ(fresh.tiles[t].mesh.point(v), reused.tiles[t].mesh.point(v));
        }
    }
}

// A damaged levels section is refused with an IoError naming the cause, also when its checksum was
// made to match: a node or vertex id out of range, a face that cannot be added, a truncated section.
TEST(ModelFile, damaged_stored_levels_are_rejected)
{
    const Hierarchy h = sample();
    const StoredLevels stored = sample_levels(h);
    SaveOptions options;
    options.levels = &stored;
    const std::string bytes = serialize_model(h, options);
    auto rejected = [&](std::string damaged, const std::string& why) { expect_refused(std::move(damaged), "levels.mrt", why, true); };
    // The last level's faces end the section: 17 bytes each (3 corners, tile, gap).
    const std::size_t faces_end = bytes.size() - 8;
    const std::size_t face_count = stored.levels.back().mesh.n_faces();
    const std::size_t first_face = faces_end - 17 * face_count;
    std::string out_of_range = bytes;
    for (int i = 0; i < 4; ++i)
        out_of_range[faces_end - 17 + static_cast<std::size_t>(i)] = static_cast<char>(0xff);
    rejected(out_of_range, "names vertex");
    std::string duplicate = bytes;
    duplicate.replace(faces_end - 17, 17, bytes.substr(first_face, 17)); // the first face again
    rejected(duplicate, "does not fit a manifold mesh");
    std::string repeated = bytes;
    repeated.replace(faces_end - 17 + 4, 4, bytes.substr(faces_end - 17, 4)); // second corner = first
    rejected(repeated, "repeats a corner");
    std::string gap_flag = bytes;
    gap_flag[faces_end - 1] = 7;
    rejected(gap_flag, "invalid tile or gap flag");
    // The cut's first node follows the recipe, the level count, three errors and the cut size.
    std::string bad_node = bytes;
    const std::size_t level0 = bytes.find("test recipe") + std::string("test recipe").size() + 4;
    const std::size_t node0 = level0 + 3 * 8 + 8;
    for (int i = 0; i < 4; ++i)
        bad_node[node0 + static_cast<std::size_t>(i)] = static_cast<char>(0x7f);
    rejected(bad_node, "cut names node");
    // Two levels damaged: the first is the one reported, on one thread or several (levels are read in
    // parallel).
    std::string both = bad_node;
    both.replace(faces_end - 17 + 4, 4, bytes.substr(faces_end - 17, 4));
    refresh_checksum(both);
    for (const std::size_t threads : {1u, 4u}) {
        set_default_threads(threads);
        try {
            deserialize_model_with_levels(both, "levels.mrt");
            ADD_FAILURE() << "accepted with two damaged levels";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find("stored level 0: cut names node"), std::string::npos) << e.what();
        }
    }
    set_default_threads(0);
    // Flipped bytes without a matching checksum, and truncation: rejected too.
    for (std::size_t at = level0; at < faces_end; at += 4099) {
        std::string flipped = bytes;
        flipped[at] = static_cast<char>(flipped[at] ^ 0x21);
        EXPECT_THROW(deserialize_model_with_levels(flipped, "levels.mrt"), IoError) << at;
    }
    EXPECT_THROW(deserialize_model_with_levels(bytes.substr(0, faces_end - 100), "levels.mrt"), IoError);
    // Forged files (checksum made to match) with random bytes changed in the section: each is either
    // refused with an IoError or, where the change is harmless (a coordinate's low bits), loaded as a
    // valid set of manifold meshes; never a crash (run under the sanitizer build too).
    std::uint64_t state = 12345;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return state >> 33;
    };
    std::size_t refused = 0;
    for (int trial = 0; trial < 300; ++trial) {
        std::string forged = bytes;
        for (int k = 0; k < 3; ++k)
            forged[level0 + next() % (faces_end - level0)] = static_cast<char>(next());
        refresh_checksum(forged);
        try {
            const Model m = deserialize_model_with_levels(forged, "levels.mrt");
            for (const LodLevel& level : m.levels.levels)
                for (const auto f : level.mesh.faces())
                    EXPECT_EQ(level.mesh.valence(f), 3u);
        } catch (const IoError&) {
            ++refused;
        }
    }
    EXPECT_GT(refused, 0u);
}

// A denoised model keeps how far each point moved (its noise floors: hierarchy.h), exactly; a damaged
// move (negative, not finite, farther than the cloud is wide), or moves in a model not denoised, are
// refused.
TEST(ModelFile, denoising_moves_round_trip_and_damage)
{
    PointCloud c = shapes::torus(3000);
    shapes::add_noise(c, 0.01);
    BuildOptions on;
    on.denoise = BuildOptions::Denoise::On;
    const Hierarchy h = build_hierarchy(c, on);
    ASSERT_EQ(h.denoise_moves.size(), h.cloud.size());
    const std::string bytes = serialize_model(h);
    const Hierarchy back = deserialize_model(bytes, "memory");
    EXPECT_EQ(back.denoise_moves, h.denoise_moves);
    EXPECT_EQ(serialize_model(back), bytes);
    for (std::size_t k = 0; k < h.nodes.size(); ++k)
        ASSERT_EQ(back.nodes[k].noise_floor, h.nodes[k].noise_floor) << k;
    EXPECT_TRUE(deserialize_model(serialize_model(sample()), "memory").denoise_moves.empty());

    // The moves are the last section here (no viewpoint, CRS or levels): the point k's at its end.
    const std::size_t moves_at = bytes.size() - 8 - 4 * h.cloud.size();
    for (const float bad : {-1.0f, 100.0f, std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()}) {
        std::string damaged = bytes;
        std::memcpy(&damaged[moves_at + 4 * 17], &bad, 4);
        refresh_checksum(damaged);
        EXPECT_THROW(deserialize_model(damaged, "m.mrt"), IoError) << bad;
    }
    std::string not_denoised = bytes;
    not_denoised[20] = static_cast<char>(not_denoised[20] & ~32);
    refresh_checksum(not_denoised);
    try {
        deserialize_model(not_denoised, "m.mrt");
        ADD_FAILURE() << "denoising moves in a model not denoised were accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("denoising"), std::string::npos) << e.what();
    }
}

// Every truncation and every single flipped byte (sampled) is rejected with an IoError.
TEST(ModelFile, truncated_or_corrupted_is_rejected)
{
    const std::string bytes = serialize_model(sample());
    for (std::size_t len : {std::size_t{0}, std::size_t{7}, std::size_t{50}, std::size_t{104}, bytes.size() / 2, bytes.size() - 1})
        EXPECT_THROW(deserialize_model(bytes.substr(0, len), "cut.mrt"), IoError) << len;
    for (std::size_t at = 0; at < bytes.size(); at += 997) {
        std::string damaged = bytes;
        damaged[at] = static_cast<char>(damaged[at] ^ 0x5a);
        EXPECT_THROW(deserialize_model(damaged, "bad.mrt"), IoError) << at;
    }
    try { // an empty file says so (QA round 57: "wrong magic")
        deserialize_model("", "empty.mrt");
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("empty.mrt: "), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("empty file"), std::string::npos) << e.what();
    }
    try {
        deserialize_model(bytes.substr(0, bytes.size() - 3), "short.mrt");
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("short.mrt"), std::string::npos);
    }
}

// A header that declares absurd sizes is rejected before anything is allocated.
TEST(ModelFile, absurd_declared_sizes_are_rejected)
{
    std::string bytes = serialize_model(sample());
    for (int i = 0; i < 8; ++i)
        bytes[24 + static_cast<std::size_t>(i)] = static_cast<char>(0xff); // point count = 2^64 - 1
    EXPECT_THROW(deserialize_model(bytes, "huge.mrt"), IoError);
    std::string version = serialize_model(sample());
    version[8] = 99;
    try {
        deserialize_model(version, "v99.mrt");
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("version 99"), std::string::npos);
    }
}

// Forged files (checksum made to match) with values no build writes: a non-finite origin, a point far
// beyond any scene, a node's NaN or huge statistics. Each is refused by name; meshing them would give
// non-finite vertices or allocate without bound.
TEST(ModelFile, forged_values_are_refused)
{
    const Hierarchy h = sample();
    const std::string bytes = serialize_model(h);
    // A value (a double, or a 32-bit word) written over the bytes at `at`, the checksum made good again.
    auto refused = [&](std::size_t at, auto value, const std::string& why) {
        std::string forged = bytes;
        std::memcpy(&forged[at], &value, sizeof value);
        refresh_checksum(forged);
        try {
            deserialize_model(forged, "forged.mrt");
            ADD_FAILURE() << "accepted; expected: " << why;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    refused(56, inf, "origin is not finite");                   // origin.z (after magic, 4 words, 2 counts, x, y)
    const std::size_t first_point = 104;                         // the header's size
    refused(first_point + 24 * 5, 1e300, "the points span x");  // point 5's x
    // Nodes close the file before its 8-byte trailer, 176 bytes each; the last is a leaf.
    const std::size_t last = bytes.size() - 8 - 176;
    const std::size_t mean_z = last + 6 * 4 + 8 + 16, m2_xx = mean_z + 8, box_max_x = last + 120 + 24, gap = last + 168;
    refused(mean_z, nan, "mean lies outside");
    refused(mean_z, 1e6, "mean lies outside");
    refused(m2_xx, 1e250, "second moments do not fit");
    refused(box_max_x, 1e200, "box is not its points' box");
    refused(gap, -1.0, "errors do not fit");
    refused(gap, nan, "errors do not fit");
    refused(gap, 1e300, "errors do not fit");
    // The build record (QA round 34: these loaded, and `info` printed "tolerance nan"): the stop
    // criterion at 80, the build time at 88 (read only when recorded), min cluster and the reclassify
    // flag at 72 and 76.
    refused(80, nan, "stop criterion of nan");
    refused(80, -1.0, "stop criterion of -1");
    refused(80, inf, "stop criterion of inf");
    refused(72, std::uint32_t{0}, "min cluster of 0");
    refused(76, std::uint32_t{7}, "reclassify flag 7");
    Hierarchy timed = sample();
    timed.info.build_seconds = 1.5;
    SaveOptions record;
    record.record_build_time = true;
    std::string with_time = serialize_model(timed, record);
    EXPECT_EQ(deserialize_model(with_time, "timed.mrt").info.build_seconds, 1.5);
    const double negative = -1.0;
    std::memcpy(&with_time[88], &negative, 8);
    refresh_checksum(with_time);
    EXPECT_THROW(deserialize_model(with_time, "timed.mrt"), IoError);
}

// A node that no parent names (an orphan, the tree's structure otherwise intact) is refused, whatever
// its parent field says: a far index made the derived statistics read outside the node array (found by
// fuzzing), and a valid one made a second tree that `mrtile info` counted as part of the model.
std::pair<std::size_t, std::size_t> hull_section(const std::string& bytes, const Hierarchy& h);

TEST(ModelFile, orphan_nodes_are_refused)
{
    // Saving refuses such a tree (what load_model would refuse is not written: QA round 51)...
    for (const std::int32_t parent : {std::numeric_limits<std::int32_t>::max(), -1, 0, 2}) {
        SCOPED_TRACE(parent);
        Hierarchy h = sample();
        Node orphan = h.nodes.back(); // a leaf, statistics and range valid
        orphan.parent = parent;
        h.nodes.push_back(orphan);
        try {
            serialize_model(h);
            ADD_FAILURE() << "saved";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("is not a child of its parent (it would not load)"), std::string::npos) << e.what();
        }
    }
    // ...and loading refuses a file whose last node names another parent (its record's parent field;
    // the node it names no longer matches its children).
    const Hierarchy h = sample();
    const std::string bytes = serialize_model(h);
    const auto [hulls_at, hulls_size] = hull_section(bytes, h);
    constexpr std::size_t kNodeBytes = 176;
    const std::size_t parent_at = hulls_at + hulls_size + (h.nodes.size() - 1) * kNodeBytes + 8;
    for (const std::int32_t parent : {std::numeric_limits<std::int32_t>::max(), -1, 0, 2}) {
        SCOPED_TRACE(parent);
        std::string damaged = bytes;
        std::memcpy(damaged.data() + parent_at, &parent, 4);
        expect_refused(damaged, "orphan.mrt", "does not match its children");
    }
}

// Where a file of this version keeps its node hulls (after the input index; no colours) and how long
// that section is.
std::pair<std::size_t, std::size_t> hull_section(const std::string& bytes, const Hierarchy& h)
{
    const std::size_t at = 104 + 28 * h.cloud.size();
    std::uint64_t entries = 0;
    std::memcpy(&entries, bytes.data() + at, 8);
    return {at, 8 + 4 * h.nodes.size() + 4 * static_cast<std::size_t>(entries)};
}

// The bytes of an older version: without the node hulls (version 2), and without the coverage gaps
// too (version 1).
std::string older_version(const std::string& bytes, const Hierarchy& h, std::uint32_t version)
{
    std::uint32_t flags = 0;
    std::memcpy(&flags, bytes.data() + 20, 4);
    EXPECT_EQ(flags, 0u); // no colours, viewpoint, CRS or levels: nodes end the payload
    const auto [hulls_at, hulls_size] = hull_section(bytes, h);
    std::string old = bytes.substr(0, hulls_at) + bytes.substr(hulls_at + hulls_size);
    std::size_t removed = hulls_size;
    if (version == 1) {
        const std::size_t nodes = h.nodes.size(), node_start = old.size() - 8 - 176 * nodes;
        std::string v1 = old.substr(0, node_start);
        for (std::size_t k = 0; k < nodes; ++k)
            v1 += old.substr(node_start + 176 * k, 168);
        v1 += old.substr(old.size() - 8);
        old = v1;
        removed += 8 * nodes;
    }
    std::memcpy(&old[8], &version, 4);
    std::uint64_t payload = 0;
    std::memcpy(&payload, old.data() + 96, 8);
    payload -= removed;
    std::memcpy(&old[96], &payload, 8);
    refresh_checksum(old);
    return old;
}

// A version 1 file (no coverage gaps) still loads, with the gaps computed as a build would.
TEST(ModelFile, version_1_files_load_with_their_gaps_computed)
{
    const Hierarchy h = sample();
    const std::string v3 = serialize_model(h);
    const Hierarchy loaded = deserialize_model(older_version(v3, h, 1), "old.mrt");
    const std::size_t nodes = h.nodes.size();
    ASSERT_EQ(loaded.nodes.size(), nodes);
    bool some_gap = false;
    for (std::size_t k = 0; k < nodes; ++k) {
        EXPECT_EQ(loaded.nodes[k].coverage_gap, h.nodes[k].coverage_gap) << "node " << k;
        some_gap = some_gap || h.nodes[k].coverage_gap > 0;
    }
    EXPECT_TRUE(some_gap); // the torus's hole: its coarse nodes' hulls cover it
    EXPECT_EQ(serialize_model(loaded), v3); // saved again, it is the version 3 file
}

// Version 3 keeps the hull of every node of more than kHullStoredAbove points, as node_hull finds it
// from the points: a built hierarchy has none until saved (or set_node_hulls), a loaded one reads
// them, a version 2 file has them computed on load, and each gives the same file and the same mesh.
TEST(ModelFile, node_hulls_are_stored_and_version_2_files_compute_them)
{
    const Hierarchy h = sample();
    EXPECT_TRUE(h.hull_start.empty());
    const std::string v3 = serialize_model(h);
    const Hierarchy loaded = deserialize_model(v3, "new.mrt");
    ASSERT_EQ(loaded.hull_start.size(), h.nodes.size() + 1);
    std::size_t stored = 0;
    for (std::size_t k = 0; k < h.nodes.size(); ++k) {
        const auto node = static_cast<std::int32_t>(k);
        const std::vector<std::uint32_t> kept(loaded.hull_points.begin() + static_cast<std::ptrdiff_t>(loaded.hull_start[k]),
                                              loaded.hull_points.begin() + static_cast<std::ptrdiff_t>(loaded.hull_start[k + 1]));
        if (h.nodes[k].count() > kHullStoredAbove) {
            EXPECT_EQ(kept, node_hull(h, node)) << "node " << k; // computed from the points
            EXPECT_GE(kept.size(), 3u);
            ++stored;
        } else {
            EXPECT_TRUE(kept.empty()) << "node " << k;
        }
        EXPECT_EQ(node_hull(loaded, node), node_hull(h, node)) << "node " << k;
    }
    EXPECT_GT(stored, 8u);
    const Hierarchy old = deserialize_model(older_version(v3, h, 2), "old.mrt");
    EXPECT_EQ(old.hull_start, loaded.hull_start);
    EXPECT_EQ(old.hull_points, loaded.hull_points);
    EXPECT_EQ(serialize_model(old), v3);
    Hierarchy set = h;
    set_node_hulls(set);
    EXPECT_EQ(set.hull_points, loaded.hull_points);
    const Cut cut = cut_by_budget(h, 6);
    ASSERT_GT(std::count_if(cut.begin(), cut.end(), [&](std::int32_t k) { return h.nodes[static_cast<std::size_t>(k)].count() > kHullStoredAbove; }), 0);
    EXPECT_EQ(corners(mesh_cut(loaded, cut).mesh), corners(mesh_cut(h, cut).mesh));
}

// A hull section that names points outside its node, out of order, or sizes that do not add up is
// refused (checksum made good), never used to build tiles.
TEST(ModelFile, damaged_node_hulls_are_refused)
{
    const Hierarchy h = sample();
    const std::string bytes = serialize_model(h);
    const auto [at, size] = hull_section(bytes, h);
    const Hierarchy loaded = deserialize_model(bytes, "ok.mrt");
    // The root's hull: its first entry follows the sizes.
    ASSERT_GT(loaded.hull_start[1], 1u);
    const std::size_t root_first = at + 8 + 4 * h.nodes.size();
    auto refused = [&](std::size_t offset, std::uint32_t value, const std::string& why) {
        std::string forged = bytes;
        std::memcpy(&forged[offset], &value, 4);
        expect_refused(forged, "forged.mrt", why);
    };
    refused(root_first, static_cast<std::uint32_t>(h.cloud.size()), "hull names points not of the node");
    refused(root_first, loaded.hull_points[1], "hull names points not of the node"); // repeated: not ascending
    refused(at + 8, static_cast<std::uint32_t>(loaded.hull_start[1] + 1), "do not add up");
    refused(at, 0xffffffffu, "node hulls of");
    EXPECT_LT(size, bytes.size() / 20); // a small part of the file
}

// Missing files and unwritable destinations give IoErrors naming the path and leave nothing behind.
TEST(ModelFile, io_errors_name_the_path)
{
    EXPECT_THROW(load_model(temp_dir() / "missing.mrt"), IoError);
    EXPECT_THROW(load_model(temp_dir()), IoError);
    // A device is no model file; its size could not be read (QA round 29: "cannot read size
    // (Operation not supported)").
    try {
        load_model("/dev/null");
        ADD_FAILURE() << "/dev/null loaded";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("/dev/null: is not a regular file"), std::string::npos) << e.what();
    }
    const fs::path bad = temp_dir() / "no_such_dir" / "x.mrt";
    try {
        save_model(sample(), bad);
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("x.mrt"), std::string::npos);
    }
    EXPECT_FALSE(fs::exists(bad.parent_path()));
}

// QA round qa3: a default-constructed Hierarchy saved without a word into a file that load_model then
// refused ("declared sizes ... do not fit the file"); so did one whose input_index or colours do not
// match its points. Such a hierarchy is refused before anything is written.
TEST(ModelFile, a_hierarchy_load_model_would_refuse_is_not_saved)
{
    const fs::path path = temp_dir() / "refused.mrt";
    EXPECT_THROW(save_model(Hierarchy{}, path), InvalidInput);
    EXPECT_FALSE(fs::exists(path));
    Hierarchy short_index = sample();
    short_index.input_index.pop_back();
    EXPECT_THROW(serialize_model(short_index), InvalidInput);
    Hierarchy few_colours = sample(true);
    few_colours.cloud.colors.pop_back();
    EXPECT_THROW(save_model(few_colours, path), InvalidInput);
    EXPECT_FALSE(fs::exists(path));
    // Denoising moves: one per point, of a denoised hierarchy, each within what the loader accepts.
    Hierarchy moves = sample();
    moves.denoise_moves.assign(moves.cloud.size(), 0.001f);
    EXPECT_THROW(serialize_model(moves), InvalidInput); // not denoised
    moves.info.denoised = true;
    EXPECT_NO_THROW(deserialize_model(serialize_model(moves), "sample"));
    moves.denoise_moves.pop_back();
    EXPECT_THROW(serialize_model(moves), InvalidInput);
    moves.denoise_moves.push_back(std::numeric_limits<float>::quiet_NaN());
    EXPECT_THROW(save_model(moves, path), InvalidInput);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_NO_THROW(deserialize_model(serialize_model(sample(true)), "sample"));
    // The build record and the viewpoint, as the loader holds them.
    Hierarchy info = sample();
    info.info.criterion_value = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(serialize_model(info), InvalidInput);
    info = sample();
    info.info.min_cluster = 0;
    EXPECT_THROW(serialize_model(info), InvalidInput);
    info = sample();
    info.cloud.viewpoint = Vec3{1e300, 0, 0};
    EXPECT_THROW(save_model(info, path), InvalidInput);
    EXPECT_FALSE(fs::exists(path));
    info.cloud.viewpoint = Vec3{1e3, 0, 0};
    EXPECT_EQ(deserialize_model(serialize_model(info), "sample").cloud.viewpoint->x, 1e3);
}

} // namespace
} // namespace mrt
