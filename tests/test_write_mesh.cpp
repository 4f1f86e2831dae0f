// Tests of write_mesh.h: a closed octahedron written in every format and read back with OpenMesh's
// readers (counts, positions, normals, colours), double precision in .om, determinism, atomic failure.
// GCC 12 sees OpenMesh's default-constructed (deliberately uninitialised) VectorT in PropertyT::push_back
// as maybe-uninitialised; a false positive in a library header, silenced before the first include.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "formats/draco_encode.h"
#include "formats/read_points.h"
#include "formats/write_3d_tiles.h"
#include "formats/write_gltf.h"
#include "formats/write_mesh.h"
#include "libmrtile/errors.h"
#include "tests/test_dir.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace mrt {
namespace {

namespace fs = std::filesystem;

fs::path test_dir() { return testing::fresh_test_dir("write_mesh"); }

// The regular octahedron with vertices on the axes (closed, genus 0, outward-oriented faces).
Mesh octahedron()
{
    Mesh m;
    const std::array<Mesh::VertexHandle, 6> v = {
        m.add_vertex({1, 0, 0}), m.add_vertex({-1, 0, 0}), m.add_vertex({0, 1, 0}),
        m.add_vertex({0, -1, 0}), m.add_vertex({0, 0, 1}),  m.add_vertex({0, 0, -1})};
    const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (const auto& f : faces)
        EXPECT_TRUE(m.add_face(v[f[0]], v[f[1]], v[f[2]]).is_valid());
    return m;
}

std::vector<std::array<double, 3>> sorted_points(const Mesh& m)
{
    std::vector<std::array<double, 3>> pts;
    for (const auto v : m.vertices())
        pts.push_back({m.point(v)[0], m.point(v)[1], m.point(v)[2]});
    std::sort(pts.begin(), pts.end());
    return pts;
}

std::vector<std::array<double, 3>> expected_points(const Mesh& m, const Vec3& origin)
{
    Mesh shifted(m);
    for (const auto v : shifted.vertices())
        shifted.set_point(v, shifted.point(v) + Mesh::Point(origin.x, origin.y, origin.z));
    return sorted_points(shifted);
}

Mesh read_back(const fs::path& path, OpenMesh::IO::Options& options)
{
    Mesh m;
    m.request_vertex_colors();
    const bool ok = OpenMesh::IO::read_mesh(m, path.string(), options);
    EXPECT_TRUE(ok) << path;
    return m;
}

std::string read_bytes(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<std::string> directory_listing(const fs::path& dir)
{
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

using O = OpenMesh::IO::Options;

TEST(WriteMesh, every_format_reads_back_with_counts_positions_and_normals)
{
    const fs::path dir = test_dir();
    const Mesh mesh = octahedron();
    const Vec3 origin{100, -200, 3.5};  // float-exact, so every format must reproduce it exactly
    struct Case { std::string name; bool binary; bool has_normals; };  // STL has only facet normals
    const std::vector<Case> cases = {{"a.ply", true, true},  {"b.ply", false, true}, {"c.obj", false, true},
                                     {"d.off", false, true}, {"e.stl", true, false}, {"f.OM", true, true}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        WriteMeshOptions options;
        options.binary = c.binary;
        write_mesh(mesh, origin, dir / c.name, options);
        O read_options = O::VertexNormal;
        if (c.binary)
            read_options += O::Binary;
        const Mesh back = read_back(dir / c.name, read_options);
        EXPECT_EQ(back.n_vertices(), 6u);
        EXPECT_EQ(back.n_faces(), 8u);
        EXPECT_EQ(sorted_points(back), expected_points(mesh, origin));
        if (c.has_normals) {
            EXPECT_TRUE(read_options.check(O::VertexNormal));
            // Area-weighted normals of the octahedron point along the vertex's axis.
            for (const auto v : back.vertices()) {
                const Mesh::Point axis = (back.point(v) - Mesh::Point(origin.x, origin.y, origin.z)).normalized();
                EXPECT_NEAR((back.normal(v) - axis).norm(), 0.0, 1e-6) << v.idx();
            }
        }
    }
    EXPECT_EQ(read_bytes(dir / "a.ply").rfind("ply\nformat binary_little_endian", 0), 0u);
    EXPECT_EQ(read_bytes(dir / "b.ply").rfind("ply\nformat ascii", 0), 0u);
}

// Far from the origin (a survey in UTM coordinates), float would round a northing of 4,200 km to a
// quarter metre: PLY (binary and ascii), OBJ and OFF are written with double coordinates, which our own
// reader gets back exactly (OpenMesh's readers round them to float), with colours where the format has them.
TEST(WriteMesh, far_meshes_keep_double_coordinates)
{
    const fs::path dir = test_dir();
    Mesh mesh = octahedron();
    for (const auto v : mesh.vertices())
        mesh.set_point(v, mesh.point(v) * 0.123456789);
    mesh.request_vertex_colors();
    for (const auto v : mesh.vertices())
        mesh.set_color(v, Mesh::Color(static_cast<unsigned char>(10 * v.idx()), 20, 30, 255));
    const Vec3 origin{4999999.0, 4200001.0, 312.0};
    std::vector<Vec3> expected;
    for (const auto v : mesh.vertices())
        expected.push_back(origin + to_vec3(mesh.point(v)));
    for (const char* name : {"far.ply", "far_ascii.ply", "far.obj", "far.off"}) {
        SCOPED_TRACE(name);
        WriteMeshOptions options;
        options.binary = std::string(name) != "far_ascii.ply";
        write_mesh(mesh, origin, dir / name, options);
        const PointCloud back = read_points(dir / name);
        ASSERT_EQ(back.size(), expected.size());
        for (std::size_t i = 0; i < expected.size(); ++i)
            EXPECT_EQ(back.origin + back.positions[i], expected[i]) << i;
        if (std::string(name).find(".ply") != std::string::npos) { // our OFF reader skips colours; OBJ has none
            ASSERT_EQ(back.colors.size(), expected.size());
            EXPECT_EQ(back.colors[3][0], 30);
        }
        // OpenMesh reads every one of them as a closed mesh.
        O read_options = O::VertexNormal | O::VertexColor;
        if (options.binary && std::string(name) == "far.ply")
            read_options += O::Binary;
        const Mesh m = read_back(dir / name, read_options);
        EXPECT_EQ(m.n_vertices(), 6u);
        EXPECT_EQ(m.n_faces(), 8u);
    }
    // Near the origin nothing changes: OpenMesh's float PLY as before.
    write_mesh(octahedron(), {0, 0, 0}, dir / "near.ply");
    EXPECT_NE(read_bytes(dir / "near.ply").find("property float x"), std::string::npos);
    EXPECT_NE(read_bytes(dir / "far.ply").find("property double x"), std::string::npos);
    // Small parts far apart with the origin between them (QA round 57: two unit spheres 200 km apart
    // came out in 1.6 cm float steps): the extent is large, the detail is not. Doubles, exact.
    const Mesh one = octahedron();
    Mesh pair = one;
    const std::size_t n = pair.n_vertices();
    std::vector<Mesh::VertexHandle> copy;
    for (std::size_t k = 0; k < n; ++k)
        copy.push_back(pair.add_vertex(pair.point(Mesh::VertexHandle(static_cast<int>(k))) * 0.01 + Mesh::Point(200000.3, 0, 0)));
    for (const auto f : one.faces()) {
        std::vector<Mesh::VertexHandle> corners;
        for (const auto v : one.fv_range(f))
            corners.push_back(copy[static_cast<std::size_t>(v.idx())]);
        ASSERT_TRUE(pair.add_face(corners).is_valid());
    }
    for (std::size_t k = 0; k < n; ++k)
        pair.set_point(Mesh::VertexHandle(static_cast<int>(k)), pair.point(Mesh::VertexHandle(static_cast<int>(k))) * 0.01);
    write_mesh(pair, {0, 0, 0}, dir / "pair.ply");
    EXPECT_NE(read_bytes(dir / "pair.ply").find("property double x"), std::string::npos);
    const PointCloud back = read_points(dir / "pair.ply");
    ASSERT_EQ(back.size(), 2 * n);
    for (std::size_t k = 0; k < 2 * n; ++k)
        EXPECT_EQ(back.origin + back.positions[k], to_vec3(pair.point(Mesh::VertexHandle(static_cast<int>(k)))));
}

// .om keeps double coordinates far from the origin (OpenMesh's readers round the other formats to float).
TEST(WriteMesh, om_keeps_doubles_far_from_origin)
{
    const fs::path dir = test_dir();
    Mesh mesh = octahedron();
    for (const auto v : mesh.vertices())
        mesh.set_point(v, mesh.point(v) * 0.123456789);
    const Vec3 origin{4999999.0, 4200001.0, 312.0};
    write_mesh(mesh, origin, dir / "far.om");
    write_mesh(mesh, origin, dir / "far.ply");
    O om_options, ply_options = O::Binary;
    const auto expected = expected_points(mesh, origin);
    EXPECT_EQ(sorted_points(read_back(dir / "far.om", om_options)), expected);
    const auto ply = sorted_points(read_back(dir / "far.ply", ply_options));
    auto rounded = expected;
    for (auto& p : rounded)
        for (double& x : p) {
            EXPECT_NEAR(static_cast<float>(x), x, 0.5);
            x = static_cast<float>(x);
        }
    std::sort(rounded.begin(), rounded.end());
    EXPECT_EQ(ply, rounded);
}

// STL has only floats: far out it is written relative to the origin (a georeferenced bunny had lost
// a fifth of its positions), near the origin in absolute coordinates as before.
TEST(WriteMesh, far_stl_is_written_relative_to_the_origin)
{
    const fs::path dir = test_dir();
    Mesh mesh = octahedron();
    for (const auto v : mesh.vertices())
        mesh.set_point(v, mesh.point(v) * 0.123456789);
    const Vec3 far{4999999.0, 4200001.0, 312.0}, near{100, -200, 3.5};
    EXPECT_TRUE(stl_is_relative(mesh, far));
    EXPECT_FALSE(stl_is_relative(mesh, near));
    write_mesh(mesh, far, dir / "far.stl");
    write_mesh(mesh, near, dir / "near.stl");
    O options = O::Binary;
    for (const auto& [name, shift] : {std::pair<const char*, Vec3>{"far.stl", Vec3{0, 0, 0}}, {"near.stl", near}}) {
        const Mesh back = read_back(dir / name, options);
        ASSERT_EQ(back.n_faces(), mesh.n_faces()) << name;
        const auto expected = expected_points(mesh, shift), got = sorted_points(back);
        ASSERT_EQ(got.size(), expected.size()) << name;
        for (std::size_t i = 0; i < got.size(); ++i) // every corner where it was, to float precision
            for (int a = 0; a < 3; ++a)
                EXPECT_NEAR(got[i][a], expected[i][a], 1e-7 * (1.0 + std::abs(expected[i][a]))) << name << " " << i;
    }
}

TEST(WriteMesh, colours_and_given_normals_are_written)
{
    const fs::path dir = test_dir();
    Mesh mesh = octahedron();
    mesh.request_vertex_colors();
    for (const auto v : mesh.vertices()) {
        mesh.set_color(v, Mesh::Color(static_cast<unsigned char>(40 * v.idx()), 7, 200, 255));
        mesh.set_normal(v, Mesh::Normal(0, 0, 1));  // deliberately not the geometric normal
    }
    WriteMeshOptions given;
    given.recompute_normals = false;
    for (const char* name : {"c.ply", "c.off", "c.om"}) {
        SCOPED_TRACE(name);
        write_mesh(mesh, Vec3{}, dir / name, given);
        O options = O::VertexColor | O::VertexNormal;
        if (std::string(name) != "c.off")
            options += O::Binary;
        const Mesh back = read_back(dir / name, options);
        ASSERT_TRUE(options.check(O::VertexColor));
        for (const auto v : back.vertices()) {
            EXPECT_EQ(back.color(v)[0], 40 * v.idx());
            EXPECT_EQ(back.color(v)[1], 7);
            EXPECT_EQ(back.color(v)[2], 200);
            EXPECT_EQ(back.normal(v), Mesh::Normal(0, 0, 1)) << "the mesh's own normals, not recomputed ones";
        }
    }
    WriteMeshOptions plain;
    plain.colors = false;
    plain.normals = false;
    write_mesh(mesh, Vec3{}, dir / "plain.ply", plain);
    O options = O::VertexColor | O::VertexNormal | O::Binary;
    read_back(dir / "plain.ply", options);
    EXPECT_FALSE(options.check(O::VertexColor));
    EXPECT_FALSE(options.check(O::VertexNormal));
}

TEST(WriteMesh, deleted_faces_are_not_written)
{
    const fs::path dir = test_dir();
    Mesh mesh = octahedron();
    mesh.delete_face(*mesh.faces().begin(), false);
    write_mesh(mesh, Vec3{}, dir / "open.obj");
    O options;
    const Mesh back = read_back(dir / "open.obj", options);
    EXPECT_EQ(back.n_faces(), 7u);
    EXPECT_EQ(back.n_vertices(), 6u);
}

TEST(WriteMesh, silent_deterministic_and_replaces_old_file)
{
    const fs::path dir = test_dir();
    const Mesh mesh = octahedron();
    for (const char* name : {"a.ply", "a.obj", "a.off", "a.stl", "a.om"}) {
        SCOPED_TRACE(name);
        std::ofstream(dir / name) << "old content";
        // The library never prints (OpenMesh's writers log to stdout/stderr unless muted).
        ::testing::internal::CaptureStdout();
        ::testing::internal::CaptureStderr();
        write_mesh(mesh, Vec3{1, 2, 3}, dir / name);
        EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
        EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
        const std::string first = read_bytes(dir / name);
        EXPECT_EQ(first.find("old content"), std::string::npos);
        write_mesh(mesh, Vec3{1, 2, 3}, dir / name);
        EXPECT_EQ(read_bytes(dir / name), first);
    }
    EXPECT_EQ(directory_listing(dir).size(), 5u) << "no temporary files left";
}

TEST(WriteMesh, failures_name_the_path_and_leave_nothing_behind)
{
    const fs::path dir = test_dir();
    const Mesh mesh = octahedron();
    const auto expect_error = [&](const fs::path& path, bool invalid_input) {
        SCOPED_TRACE(path.string());
        try {
            write_mesh(mesh, Vec3{}, path);
            ADD_FAILURE() << "no exception";
        } catch (const InvalidInput& e) {
            EXPECT_TRUE(invalid_input) << e.what();
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        } catch (const IoError& e) {
            EXPECT_FALSE(invalid_input) << e.what();
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        }
    };
    expect_error(dir / "mesh.gltf", true);
    expect_error(dir / "mesh", true);
    expect_error(dir / "no_such_dir" / "mesh.ply", false);
    // The target is a directory: the temporary file is written, the rename fails, the temp is removed.
    fs::create_directories(dir / "taken.obj");
    expect_error(dir / "taken.obj", false);
    EXPECT_TRUE(fs::is_directory(dir / "taken.obj"));
    EXPECT_TRUE(fs::is_empty(dir / "taken.obj"));
    EXPECT_EQ(directory_listing(dir), std::vector<std::string>{"taken.obj"});
    // A read-only file system (refuses even root).
    expect_error("/proc/mrtile_write_mesh_test.ply", false);
    EXPECT_FALSE(fs::exists("/proc/mrtile_write_mesh_test.ply"));
    // A non-finite origin would make every vertex NaN (QA, session 19: written as such); glTF, Draco
    // and 3D Tiles writers refuse it too.
    const Vec3 nan{std::nan(""), 0, 0};
    EXPECT_THROW(write_mesh(mesh, nan, dir / "nan.ply"), InvalidInput);
    EXPECT_THROW(write_gltf(mesh, nan, dir / "nan.glb"), InvalidInput);
    EXPECT_THROW(write_drc(mesh, nan, dir / "nan.drc"), InvalidInput);
    std::vector<TilesetTile> tiles(1);
    tiles[0].mesh = &mesh;
    tiles[0].box = BoundingBox{{-1, -1, -1}, {1, 1, 1}};
    EXPECT_THROW(write_3d_tiles(tiles, nan, dir / "nan_tiles", TilesetOptions{}), InvalidInput);
    EXPECT_EQ(directory_listing(dir), std::vector<std::string>{"taken.obj"});
}

// QA round qa3: a vertex the caller set to NaN or infinity was written as such into .ply, .obj, .off,
// .stl and .om files (the glTF and Draco writers refused it); now every format refuses it, naming the
// vertex, and writes nothing. A deleted vertex is not written, so it may be anything.
TEST(WriteMesh, a_non_finite_vertex_is_refused_in_every_format)
{
    const fs::path dir = test_dir();
    for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity()}) {
        Mesh mesh = octahedron();
        mesh.set_point(*mesh.vertices_begin(), Mesh::Point(bad, 0, 0));
        for (const char* name : {"v.ply", "v.obj", "v.off", "v.stl", "v.om"}) {
            try {
                write_mesh(mesh, Vec3{}, dir / name);
                ADD_FAILURE() << name << ": no exception";
            } catch (const InvalidInput& e) {
                EXPECT_NE(std::string(e.what()).find("vertex 0"), std::string::npos) << e.what();
            }
        }
    }
    EXPECT_TRUE(directory_listing(dir).empty());
    Mesh deleted = octahedron();
    deleted.delete_vertex(*deleted.vertices_begin(), false);
    deleted.set_point(*deleted.vertices_begin(), Mesh::Point(std::nan(""), 0, 0));
    EXPECT_NO_THROW(write_mesh(deleted, Vec3{}, dir / "deleted.ply"));
}

// QA round qa-left: GltfOptions::up_axis cast from an integer (static_cast<UpAxis>(42)) was taken for Y.
TEST(WriteMesh, unknown_up_axis_is_refused)
{
    const fs::path dir = test_dir();
    const Mesh mesh = octahedron();
    GltfOptions options;
    options.up_axis = static_cast<UpAxis>(42);
    const std::string message = "up_axis 42 is neither UpAxis::Y nor UpAxis::Z";
    try {
        write_gltf(mesh, Vec3{}, dir / "odd.glb", options);
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), message);
    }
    TilesetOptions tileset;
    tileset.gltf = options;
    TilesetTile root;
    root.mesh = &mesh;
    root.box = BoundingBox{{-1, -1, -1}, {1, 1, 1}};
    try {
        write_3d_tiles({root}, Vec3{}, dir / "odd_tiles", tileset);
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), message);
    }
    EXPECT_TRUE(directory_listing(dir).empty());
}

// QA round qa3: a mesh whose normals the caller released (release_vertex_normals, release_face_normals)
// made write_mesh read the missing property (an OpenMesh assertion in a debug build). Now its normals
// are computed on the copy as for any mesh: the files equal those of the mesh with its normals.
TEST(WriteMesh, a_mesh_without_normal_properties_is_written_with_computed_normals)
{
    const fs::path dir = test_dir();
    const Mesh with = octahedron();
    Mesh without = with;
    without.release_vertex_normals();
    without.release_face_normals();
    ASSERT_FALSE(without.has_vertex_normals());
    const auto bytes = [](const fs::path& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    for (const std::string ext : {".ply", ".obj", ".off", ".stl", ".om"}) {
        write_mesh(with, Vec3{}, dir / ("with" + ext));
        write_mesh(without, Vec3{}, dir / ("without" + ext));
        EXPECT_EQ(bytes(dir / ("with" + ext)), bytes(dir / ("without" + ext))) << ext;
        WriteMeshOptions keep; // nothing to keep: computed all the same
        keep.recompute_normals = false;
        write_mesh(without, Vec3{}, dir / ("kept" + ext), keep);
        EXPECT_EQ(bytes(dir / ("with" + ext)), bytes(dir / ("kept" + ext))) << ext;
    }
}

// QA round qa-left: a vertex finite as a double but beyond the largest float (1e39) was written as inf
// into PLY (float properties), STL and glTF. PLY, OBJ and OFF keep doubles now; STL and glTF, which
// have only floats, refuse it naming the vertex (and the file); so does a vertex whose sum with the
// origin overflows a double. Nothing is left behind.
TEST(WriteMesh, a_vertex_beyond_the_float_range_is_kept_as_double_or_refused)
{
    const fs::path dir = test_dir();
    Mesh mesh = octahedron();
    mesh.set_point(*mesh.vertices_begin(), Mesh::Point(1e39, 0, 0));
    for (const char* name : {"big.ply", "big.obj", "big.off"}) {
        SCOPED_TRACE(name);
        write_mesh(mesh, Vec3{}, dir / name);
        std::ifstream in(dir / name, std::ios::binary);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        EXPECT_EQ(text.find("inf"), std::string::npos);
        char exact[32]; // the text formats' doubles round-trip
        std::snprintf(exact, sizeof exact, "%.17g", 1e39);
        EXPECT_NE(text.find(name == std::string("big.ply") ? "property double x" : exact), std::string::npos) << text;
        fs::remove(dir / name);
    }
    try {
        write_mesh(mesh, Vec3{}, dir / "big.stl");
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), (dir / "big.stl").string() +
                                             ": mesh vertex 0 lies at (1e+39, 0, 0) from the origin, beyond the largest 32-bit float "
                                             "STL can store (3.4e38)");
    }
    GltfOptions at_zero; // an offset of 0: vertex 0 alone is beyond the float range from it
    at_zero.offset = Vec3{0, 0, 0};
    for (const char* name : {"big.glb", "big.gltf"}) {
        try {
            write_gltf(mesh, Vec3{}, dir / name, at_zero);
            ADD_FAILURE() << name << ": no exception";
        } catch (const InvalidInput& e) {
            EXPECT_EQ(std::string(e.what()), "mesh: vertex 0 lies 1e+39 from the offset along an axis, beyond the 3.4e38 "
                                             "a 32-bit float can store");
        }
    }
    // With the offset at the box's centre every vertex is 5e38 from it; the one named is the one set
    // far, not the first found over (QA round 59 named vertex 258 of a mesh whose vertex 0 was at 1e39).
    Mesh one_far = octahedron();
    one_far.set_point(Mesh::VertexHandle(3), Mesh::Point(1e39, 0, 0));
    try {
        write_gltf(one_far, Vec3{}, dir / "one_far.glb");
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()).rfind("mesh: vertex 3 lies ", 0), 0u) << e.what();
    }
    Mesh far = octahedron();
    far.set_point(*far.vertices_begin(), Mesh::Point(1e308, 0, 0));
    try {
        write_mesh(far, Vec3{1e308, 0, 0}, dir / "sum.ply");
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), (dir / "sum.ply").string() +
                                             ": mesh vertex 0 lies at (inf, 0, 0), beyond the largest double (1.8e308)");
    }
    EXPECT_TRUE(directory_listing(dir).empty());
}

// A mesh without faces is refused by every writer alike (QA round 59: write_mesh wrote a 0-face PLY, OBJ
// or OFF where write_gltf said "no faces to write"), and leaves no file; so is one whose faces were all
// deleted.
TEST(WriteMesh, a_mesh_without_faces_is_refused_as_by_the_gltf_writer)
{
    const auto dir = testing::fresh_test_dir("write_mesh");
    Mesh points_only;
    points_only.add_vertex(Mesh::Point(0, 0, 0));
    points_only.add_vertex(Mesh::Point(1, 0, 0));
    for (const char* name : {"e.ply", "e.obj", "e.off", "e.stl", "e.om"}) {
        EXPECT_THROW(write_mesh(points_only, Vec3{0, 0, 0}, dir / name), InvalidInput) << name;
        EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
    }
    EXPECT_THROW(write_gltf(points_only, Vec3{0, 0, 0}, dir / "e.glb"), InvalidInput);
    Mesh one;
    const auto a = one.add_vertex(Mesh::Point(0, 0, 0)), b = one.add_vertex(Mesh::Point(1, 0, 0)), c = one.add_vertex(Mesh::Point(0, 1, 0));
    one.add_face(a, b, c);
    EXPECT_NO_THROW(write_mesh(one, Vec3{0, 0, 0}, dir / "one.ply"));
    one.request_face_status();
    one.request_edge_status();
    one.request_vertex_status();
    one.request_halfedge_status();
    one.delete_face(Mesh::FaceHandle(0), false);
    EXPECT_THROW(write_mesh(one, Vec3{0, 0, 0}, dir / "deleted.ply"), InvalidInput);
}

} // namespace
} // namespace mrt
