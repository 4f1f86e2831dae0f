// Tests of model_file.h: .mrt round trips are exact, and every kind of damage is rejected cleanly.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/errors.h"
#include "libmrtile/model_file.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

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
    unknown[20] = static_cast<char>(unknown[20] | 16); // flags: the u32 after magic, version, marker, header size
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

// Missing files and unwritable destinations give IoErrors naming the path and leave nothing behind.
TEST(ModelFile, io_errors_name_the_path)
{
    EXPECT_THROW(load_model(temp_dir() / "missing.mrt"), IoError);
    EXPECT_THROW(load_model(temp_dir()), IoError);
    const fs::path bad = temp_dir() / "no_such_dir" / "x.mrt";
    try {
        save_model(sample(), bad);
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("x.mrt"), std::string::npos);
    }
    EXPECT_FALSE(fs::exists(bad.parent_path()));
}

} // namespace
} // namespace mrt
