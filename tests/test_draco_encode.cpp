// Tests of draco_encode.h: round trips within the quantization step, exact colours, the origin in the
// metadata, a shared explicit grid making border vertices of neighbouring meshes bit-identical, and
// decoding by independent clients (draco3d from npm, the draco_decoder command).
// OpenMesh copies a default-constructed (uninitialized) VectorT when a vertex is added; the fixtures set
// every value they use right after, so GCC's warning about that copy does not apply.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "formats/draco_encode.h"
#include "libmrtile/errors.h"
#include "mesh_fixtures.h"
#include "npm/node_clients.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace mrt {
namespace {

namespace fs = std::filesystem;
using testing::grid_mesh;
using testing::uv_sphere;

fs::path scratch(const std::string& name)
{
    const fs::path dir = fs::path(MRTILE_BINARY_DIR) / ("test_draco_encode." + std::to_string(::getpid()));
    fs::create_directories(dir);
    return dir / name;
}

std::string read_bytes(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Vec3 point(const Mesh& mesh, Mesh::VertexHandle v)
{
    const auto& p = mesh.point(v);
    return {p[0], p[1], p[2]};
}

Vec3 decoded_point(const DracoDecoded& d, std::size_t i)
{
    return {d.positions[3 * i], d.positions[3 * i + 1], d.positions[3 * i + 2]};
}

// Index of the decoded point nearest to `p` (brute force; the meshes are small).
std::size_t nearest(const DracoDecoded& d, const Vec3& p)
{
    std::size_t best = 0;
    double best_d2 = INFINITY;
    for (std::size_t i = 0; i < d.positions.size() / 3; ++i) {
        const double d2 = squared_distance(decoded_point(d, i), p);
        if (d2 < best_d2) {
            best_d2 = d2;
            best = i;
        }
    }
    return best;
}

class DracoFiles : public ::testing::Test
{
protected:
    static void TearDownTestSuite()
    {
        std::error_code ec;
        fs::remove_all(scratch("x").parent_path(), ec);
    }
};

// Every source vertex comes back within half a quantization step per axis (plus float rounding), with
// the origin + offset in the metadata restoring absolute coordinates far from zero.
TEST_F(DracoFiles, round_trip_within_quantization_far_from_origin)
{
    const Vec3 origin{5.0e6, -3.0e6, 250.0};
    const Mesh mesh = uv_sphere(20, 40, 7.0, {0.3, 0.2, -0.1}, true);
    const fs::path path = scratch("sphere.drc");
    write_drc(mesh, origin, path);
    const DracoDecoded d = decode_draco(read_bytes(path), path.string());
    ASSERT_EQ(d.positions.size(), 3 * mesh.n_vertices());
    ASSERT_EQ(d.indices.size(), 3 * mesh.n_faces());
    ASSERT_EQ(d.normals.size(), d.positions.size());
    ASSERT_EQ(d.colors.size(), 4 * mesh.n_vertices());
    ASSERT_TRUE(d.metadata_origin.has_value());
    const Vec3 offset = *d.metadata_origin - origin; // the rounded centre (0, 0, 0)
    EXPECT_EQ(offset, (Vec3{0, 0, 0}));
    const double step = 14.0 / ((1 << 14) - 1); // the sphere's bounding cube is 14 wide
    double worst = 0, worst_normal = 0;
    for (const auto v : mesh.vertices()) {
        const Vec3 p = point(mesh, v);
        const std::size_t i = nearest(d, p - offset);
        const Vec3 absolute = *d.metadata_origin + decoded_point(d, i);
        for (int k = 0; k < 3; ++k)
            worst = std::max(worst, std::fabs(absolute[k] - (origin + p)[k]));
        // Colours are stored as exact bytes.
        const auto& c = mesh.color(v);
        for (std::size_t k = 0; k < 4; ++k)
            EXPECT_EQ(d.colors[4 * i + k], c[static_cast<int>(k)]);
        // Normals (computed: the fixture leaves them zero) point outwards, 10-bit octahedral.
        const Vec3 n{d.normals[3 * i], d.normals[3 * i + 1], d.normals[3 * i + 2]};
        worst_normal = std::max(worst_normal, std::fabs(norm(n) - 1.0));
        EXPECT_GT(dot(n, normalized(p - Vec3{0.3, 0.2, -0.1})), 0.99);
    }
    EXPECT_LE(worst, 0.5 * step + 1e-5);
    EXPECT_LE(worst_normal, 1e-3);
}

// Two grids sharing the border x = 4 encoded on one explicit grid: every shared vertex decodes to the
// same float bits in both files. On their own bounding cubes they do not (checked, so that the test
// shows the grid is what makes the difference).
TEST_F(DracoFiles, shared_grid_makes_border_vertices_bit_identical)
{
    const Mesh left = grid_mesh(16, 16, 0.0, 0.0, 0.25, testing::wave);
    const Mesh right = grid_mesh(16, 16, 4.0, 0.0, 0.25, testing::wave);
    DracoOptions shared;
    shared.grid = QuantizationGrid{{-1.0, -1.0, -1.0}, 10.0};
    const Vec3 origin{1000, 2000, 30};
    std::vector<Vec3> border;
    for (const auto v : left.vertices())
        if (point(left, v).x == 4.0)
            border.push_back(point(left, v));
    ASSERT_EQ(border.size(), 17u);

    auto border_mismatches = [&](const DracoOptions& options, const std::string& tag) {
        write_drc(left, origin, scratch(tag + "_left.drc"), options);
        write_drc(right, origin, scratch(tag + "_right.drc"), options);
        const DracoDecoded a = decode_draco(read_bytes(scratch(tag + "_left.drc")), "left");
        const DracoDecoded b = decode_draco(read_bytes(scratch(tag + "_right.drc")), "right");
        const Vec3 offset_a = *a.metadata_origin - origin, offset_b = *b.metadata_origin - origin;
        std::size_t mismatches = 0;
        for (const Vec3& p : border) {
            const std::size_t i = nearest(a, p - offset_a), j = nearest(b, p - offset_b);
            EXPECT_LE(distance(decoded_point(a, i) + offset_a, p), 1e-3);
            // Absolute decoded coordinates, as a viewer computes them: offset (translation) + float.
            double pa[3], pb[3];
            for (std::size_t k = 0; k < 3; ++k) {
                pa[k] = offset_a[static_cast<int>(k)] + double(a.positions[3 * i + k]);
                pb[k] = offset_b[static_cast<int>(k)] + double(b.positions[3 * j + k]);
            }
            mismatches += std::memcmp(pa, pb, sizeof pa) != 0;
            if (options.grid) { // same offset too: the very same float bits
                EXPECT_EQ(std::memcmp(&a.positions[3 * i], &b.positions[3 * j], 3 * sizeof(float)), 0);
            }
        }
        return mismatches;
    };
    EXPECT_EQ(border_mismatches(shared, "shared"), 0u);
    EXPECT_GT(border_mismatches(DracoOptions{}, "own"), 0u);
}

// draco3d (npm) and the draco_decoder command decode our files to the same counts and bounds as
// libdraco does.
TEST_F(DracoFiles, independent_decoders_agree)
{
    const Mesh mesh = uv_sphere(12, 24, 2.0, {}, true);
    const fs::path path = scratch("clients.drc");
    write_drc(mesh, {}, path);
    const DracoDecoded d = decode_draco(read_bytes(path), path.string());
    const nlohmann::json r = testing::run_node_script("draco_check.mjs", {path.string()}).at(0);
    EXPECT_EQ(r["ok"], true) << r.dump();
    EXPECT_EQ(r["points"], d.positions.size() / 3);
    EXPECT_EQ(r["faces"], d.indices.size() / 3);
    for (std::size_t k = 0; k < 3; ++k) {
        float lo = INFINITY, hi = -INFINITY;
        for (std::size_t i = k; i < d.positions.size(); i += 3) {
            lo = std::min(lo, d.positions[i]);
            hi = std::max(hi, d.positions[i]);
        }
        EXPECT_EQ(r["min"][k].get<float>(), lo);
        EXPECT_EQ(r["max"][k].get<float>(), hi);
    }
    const fs::path ply = scratch("clients.ply");
    testing::run_command("draco_decoder -i " + testing::shell_quote(path.string()) + " -o " +
                         testing::shell_quote(ply.string()) + " >/dev/null");
    const std::string header = read_bytes(ply).substr(0, 400);
    EXPECT_NE(header.find("element vertex " + std::to_string(mesh.n_vertices()) + "\n"), std::string::npos) << header;
    EXPECT_NE(header.find("element face " + std::to_string(mesh.n_faces()) + "\n"), std::string::npos) << header;
}

// encode_draco reports what a decoder gets back without decoding (the encoder's own counts, the ids
// the attributes keep, the extremes quantized by the encoder's transform): the same counts, ids and
// bounds as decoding its bytes gives, with and without an explicit grid, with colours, and with a
// vertex where two fans touch, which Draco splits into two points.
TEST(DracoEncode, reports_what_the_decoder_gets_back)
{
    const Mesh bowtie = [] {
        Mesh m;
        std::vector<Mesh::VertexHandle> v;
        for (const auto& p : std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0.5}})
            v.push_back(m.add_vertex(to_point(p)));
        testing::add_checked_face(m, v[0], v[1], v[2]);
        testing::add_checked_face(m, v[0], v[3], v[4]);
        return m;
    }();
    const Mesh sphere = uv_sphere(12, 24, 2.0, {0.3, -0.2, 0.1}, true);
    const Mesh grid = grid_mesh(7, 5, -0.7, 0.2, 0.31, testing::wave);
    DracoOptions with_grid;
    with_grid.grid = QuantizationGrid{Vec3{-3, -3, -3}, 6.123456789}; // a range Draco keeps to six digits
    for (const Mesh* mesh : {&bowtie, &sphere, &grid})
        for (const DracoOptions& options : {DracoOptions{}, with_grid}) {
            MeshBufferOptions buffer_options;
            buffer_options.offset = draco_grid_offset(options, buffer_options.up_axis);
            const MeshBuffers buffers = make_mesh_buffers(*mesh, buffer_options);
            const DracoEncoded encoded = encode_draco(buffers, options);
            const DracoDecoded decoded = decode_draco(encoded.bytes, "round trip");
            EXPECT_EQ(encoded.vertex_count, decoded.positions.size() / 3);
            EXPECT_EQ(encoded.face_count, decoded.indices.size() / 3);
            EXPECT_EQ(encoded.position_id, 0);
            EXPECT_EQ(encoded.normal_id, 1);
            EXPECT_EQ(encoded.color_id, mesh->has_vertex_colors() ? 2 : -1);
            EXPECT_EQ(decoded.colors.empty(), !mesh->has_vertex_colors());
            for (std::size_t k = 0; k < 3; ++k) {
                float lo = INFINITY, hi = -INFINITY;
                for (std::size_t i = k; i < decoded.positions.size(); i += 3) {
                    lo = std::min(lo, decoded.positions[i]);
                    hi = std::max(hi, decoded.positions[i]);
                }
                EXPECT_EQ(encoded.min[k], lo) << "axis " << k;
                EXPECT_EQ(encoded.max[k], hi) << "axis " << k;
            }
        }
    // The bowtie's shared corner comes back as two points.
    const DracoEncoded split = encode_draco(make_mesh_buffers(bowtie), DracoOptions{});
    EXPECT_EQ(split.vertex_count, 6u);
}

// Draco keeps its options as text with six decimals, so an explicit grid's range under 5e-7 reached it
// as 0 and every vertex decoded to one point (QA round 59, a torus 1e-7 across). The range passed is
// rounded up to what Draco reads back: a sphere 2e-6 and 6e-7 across decodes within a step of the
// range it was given; a model under about a millionth of a unit is refused, not collapsed.
TEST(DracoEncode, a_tiny_model_keeps_its_grid)
{
    for (const double radius : {1e-6, 3e-7}) {
        const Mesh sphere = uv_sphere(12, 24, radius, {0, 0, 0}, true);
        DracoOptions options;
        options.grid = QuantizationGrid{Vec3{-1.1, -1.1, -1.1} * radius, 2.2 * radius};
        MeshBufferOptions buffer_options;
        buffer_options.offset = draco_grid_offset(options, buffer_options.up_axis);
        const MeshBuffers buffers = make_mesh_buffers(sphere, buffer_options);
        const DracoDecoded decoded = decode_draco(encode_draco(buffers, options).bytes, "tiny");
        ASSERT_EQ(decoded.positions.size(), buffers.positions.size()) << radius;
        double worst = 0.0;
        for (std::size_t i = 0; i < decoded.positions.size(); i += 3) {
            double nearest = INFINITY;
            for (std::size_t j = 0; j < buffers.positions.size(); j += 3)
                nearest = std::min(nearest, std::hypot(double{decoded.positions[i] - buffers.positions[j]}, double{decoded.positions[i + 1] - buffers.positions[j + 1]},
                                                       double{decoded.positions[i + 2] - buffers.positions[j + 2]}));
            worst = std::max(worst, nearest);
        }
        EXPECT_LT(worst, 2.2 * radius * std::ldexp(1.0, 2 - options.position_bits)) << radius; // a step, doubled by the rounding up
    }
    const Mesh speck = uv_sphere(12, 24, 1e-8, {0, 0, 0}, true);
    DracoOptions options;
    options.grid = QuantizationGrid{Vec3{-1.1e-8, -1.1e-8, -1.1e-8}, 2.2e-8};
    MeshBufferOptions buffer_options;
    buffer_options.offset = draco_grid_offset(options, buffer_options.up_axis);
    EXPECT_THROW(encode_draco(make_mesh_buffers(speck, buffer_options), options), InvalidInput);
}

// The writers reorder triangles for the GPU's vertex cache only where Draco keeps that order. The
// edgebreaker (default speeds) writes the same bytes whatever the face order it is given, so the
// reordering would be wasted there; the sequential coding (a speed of 10) stores faces as given, so a
// .drc written with it has its triangles in GPU order.
TEST_F(DracoFiles, face_order_is_kept_only_by_the_sequential_coding)
{
    const Mesh mesh = uv_sphere(16, 32, 1.0, {0.2, 0.1, -0.3}, false);
    MeshBufferOptions gpu, plain;
    gpu.up_axis = plain.up_axis = UpAxis::Y;
    plain.gpu_order = false;
    const MeshBuffers in_gpu_order = make_mesh_buffers(mesh, gpu);
    const MeshBuffers in_face_order = make_mesh_buffers(mesh, plain);
    ASSERT_NE(in_gpu_order.indices, in_face_order.indices);

    const DracoOptions edgebreaker;
    EXPECT_FALSE(draco_keeps_face_order(edgebreaker));
    EXPECT_EQ(encode_draco(in_gpu_order, edgebreaker).bytes, encode_draco(in_face_order, edgebreaker).bytes);

    for (const auto& [encoding, decoding] : {std::pair{10, 3}, std::pair{3, 10}, std::pair{10, 10}}) {
        DracoOptions sequential;
        sequential.encoding_speed = encoding;
        sequential.decoding_speed = decoding;
        EXPECT_TRUE(draco_keeps_face_order(sequential));
        EXPECT_EQ(decode_draco(encode_draco(in_face_order, sequential).bytes, "face order").indices,
                  in_face_order.indices);
        write_drc(mesh, {}, scratch("sequential.drc"), sequential);
        EXPECT_EQ(decode_draco(read_bytes(scratch("sequential.drc")), "sequential.drc").indices, in_gpu_order.indices)
            << encoding << "/" << decoding;
    }
    DracoOptions nine = edgebreaker;
    nine.encoding_speed = nine.decoding_speed = 9;
    EXPECT_FALSE(draco_keeps_face_order(nine));
}

TEST_F(DracoFiles, output_is_byte_deterministic)
{
    const Mesh mesh = uv_sphere(10, 20, 1.0, {}, true);
    write_drc(mesh, {1, 2, 3}, scratch("a.drc"));
    write_drc(mesh, {1, 2, 3}, scratch("b.drc"));
    EXPECT_EQ(read_bytes(scratch("a.drc")), read_bytes(scratch("b.drc")));
}

TEST(DracoEncode, rejects_bad_options_and_positions_outside_the_grid)
{
    const Mesh mesh = uv_sphere(4, 8, 1.0);
    const fs::path path = fs::path(MRTILE_BINARY_DIR) / "test_draco_encode_never_written.drc";
    for (auto change : std::vector<void (*)(DracoOptions&)>{
             [](DracoOptions& o) { o.position_bits = 0; }, [](DracoOptions& o) { o.position_bits = 31; },
             [](DracoOptions& o) { o.position_bits = kMaxPositionBits + 1; }, // gigabytes whatever the mesh (QA round 38)
             [](DracoOptions& o) { o.normal_bits = 0; }, [](DracoOptions& o) { o.encoding_speed = 11; },
             [](DracoOptions& o) { o.decoding_speed = -1; },
             [](DracoOptions& o) { o.grid = QuantizationGrid{{0, 0, 0}, 0.0}; },
             [](DracoOptions& o) { o.grid = QuantizationGrid{{-1, -1, -1}, 1.5}; }}) { // sphere reaches +1
        DracoOptions options;
        change(options);
        EXPECT_THROW(write_drc(mesh, {}, path, options), InvalidInput);
    }
    EXPECT_FALSE(fs::exists(path));
    EXPECT_THROW(decode_draco("not draco", "junk.drc"), IoError);
}

TEST(DracoEncode, bad_paths_throw_io_error_naming_the_path)
{
    const Mesh mesh = uv_sphere(4, 8, 1.0);
    for (const fs::path& path : {fs::path(MRTILE_BINARY_DIR) / "no_such_dir_for_draco" / "x.drc",
                                fs::path("/proc/mrtile_out.drc")}) {
        try {
            write_drc(mesh, {}, path);
            ADD_FAILURE() << "no exception for " << path;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(path.parent_path()) && fs::exists(path));
    }
}

} // namespace
} // namespace mrt
