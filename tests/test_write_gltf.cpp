// Tests of write_gltf.h with real clients: every file is checked by the Khronos glTF validator, the
// Draco ones are decoded by draco3d, a few are loaded by gltf-transform, and the plain ones by
// tinygltf in this very binary (which also links libdraco.so, whose embedded old tinygltf must not
// interpose: see formats/CMakeLists.txt).
// OpenMesh copies a default-constructed (uninitialized) VectorT when a vertex is added; the fixtures set
// every value they use right after, so GCC's warning about that copy does not apply.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "formats/draco_encode.h"
#include "formats/write_gltf.h"
#include "libmrtile/errors.h"
#include "mesh_fixtures.h"
#include "npm/node_clients.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

namespace mrt {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::uv_sphere;

const Vec3 kFarOrigin{5.0e6, 5.0e6, 100.0};

std::string read_bytes(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

json glb_json(const fs::path& path)
{
    const std::string bytes = read_bytes(path);
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    return json::parse(bytes.substr(20, length));
}

// Everything the suite writes, written once per process (ctest runs each test in its own process,
// possibly in parallel: hence the per-process directory) and checked by one node run per script,
// started only by the test that needs it.
class GltfFiles : public ::testing::Test
{
protected:
    static void SetUpTestSuite()
    {
        dir_ = fs::path(MRTILE_BINARY_DIR) / ("test_write_gltf." + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        meshes_ = new std::map<std::string, Mesh>{
            {"sphere", uv_sphere(24, 48, 1.0)},
            {"far", uv_sphere(24, 48, 10.0, {0.4, -0.3, 0.0})},
            {"colors", uv_sphere(16, 32, 2.0, {}, true)},
            {"big", uv_sphere(260, 260, 3.0)}, // 67342 vertices: needs 32-bit indices
            {"lod1", uv_sphere(12, 24, 1.0)},
            {"lod2", uv_sphere(6, 12, 1.0)},
        };
        GltfOptions plain, draco, yup;
        draco.draco = true;
        yup.up_axis = UpAxis::Y;
        auto write = [&](const std::string& file, const std::string& mesh, const Vec3& origin, const GltfOptions& o) {
            write_gltf(meshes_->at(mesh), origin, dir_ / file, o);
        };
        write("sphere.glb", "sphere", {}, plain);
        write("sphere.gltf", "sphere", {}, plain);
        write("far.glb", "far", kFarOrigin, plain);
        write("colors.glb", "colors", {}, plain);
        write("big.glb", "big", {}, plain);
        write("yup.glb", "sphere", {}, yup);
        write("sphere_draco.glb", "sphere", {}, draco);
        write("colors_draco.glb", "colors", {}, draco);
        write("far_draco.gltf", "far", kFarOrigin, draco);
        write("big_draco.glb", "big", {}, draco);
        GltfOptions skirted = plain, skirted_draco = draco;
        skirted.skirt_faces = skirted_draco.skirt_faces = kSkirtFaces;
        write("skirted.glb", "far", kFarOrigin, skirted);
        write("skirted_draco.glb", "far", kFarOrigin, skirted_draco);
        const std::vector<const Mesh*> levels{&meshes_->at("sphere"), &meshes_->at("lod1"), &meshes_->at("lod2")};
        GltfLodOptions lods;
        lods.screen_coverage = {0.5, 0.2, 0.05};
        write_glb_lods(levels, kFarOrigin, dir_ / "lods.glb", lods);
        lods.gltf.draco = true;
        write_glb_lods(levels, kFarOrigin, dir_ / "lods_draco.glb", lods);

    }

    static const json& validation()
    {
        if (validation_ == nullptr)
            validation_ = new json(testing::run_node_script("validate.mjs", files(false)));
        return *validation_;
    }

    static std::vector<std::string> files(bool draco_only)
    {
        std::vector<std::string> out;
        for (const auto& entry : fs::directory_iterator(dir_))
            if (!draco_only || entry.path().filename().string().find("draco") != std::string::npos)
                out.push_back(entry.path().string());
        std::sort(out.begin(), out.end());
        return out;
    }

    static void TearDownTestSuite()
    {
        delete meshes_;
        delete validation_;
        delete draco_;
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }

    static const json& draco_result(const std::string& name)
    {
        if (draco_ == nullptr)
            draco_ = new json(testing::run_node_script("draco_check.mjs", files(true)));
        for (const json& r : *draco_)
            if (fs::path(r["file"].get<std::string>()).filename() == name)
                return r;
        throw std::runtime_error("no draco_check result for " + name);
    }

    static tinygltf::Model load(const std::string& name)
    {
        tinygltf::TinyGLTF loader;
        tinygltf::Model model;
        std::string err, warn;
        const fs::path path = dir_ / name;
        const bool ok = path.extension() == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, path.string())
                                                   : loader.LoadASCIIFromFile(&model, &err, &warn, path.string());
        EXPECT_TRUE(ok) << name << ": " << err;
        EXPECT_TRUE(warn.empty()) << warn;
        return model;
    }

    static constexpr std::size_t kSkirtFaces = 200; // "far"'s last faces, written as skirts
    static inline fs::path dir_;
    static inline std::map<std::string, Mesh>* meshes_ = nullptr;
    static inline json* validation_ = nullptr;
    static inline json* draco_ = nullptr;
};

// Zero errors and zero warnings from the Khronos validator on every file. The only infos allowed:
// this validator version implements neither KHR_draco_mesh_compression nor MSFT_lod, so it reports
// them as UNSUPPORTED_EXTENSION, the Draco bufferView (referenced only from the extension) and the
// coarser LOD nodes (referenced only through MSFT_lod ids) as UNUSED_OBJECT. Plain files: no infos.
TEST_F(GltfFiles, khronos_validator_reports_no_error_or_warning)
{
    ASSERT_EQ(validation().size(), 14u);
    for (const json& r : validation()) {
        const std::string file = r["file"];
        const bool draco = file.find("draco") != std::string::npos, lods = file.find("lods") != std::string::npos;
        EXPECT_EQ(r["errors"], 0) << r.dump(1);
        EXPECT_EQ(r["warnings"], 0) << r.dump(1);
        for (const json& m : r["messages"]) {
            const std::string code = m["code"], message = m["message"], pointer = m.value("pointer", "");
            const bool expected =
                (code == "UNSUPPORTED_EXTENSION" &&
                 ((draco && message.find("KHR_draco_mesh_compression") != std::string::npos) ||
                  (lods && message.find("MSFT_lod") != std::string::npos))) ||
                (code == "UNUSED_OBJECT" && ((draco && pointer.rfind("/bufferViews/", 0) == 0) ||
                                             (lods && pointer.rfind("/nodes/", 0) == 0)));
            EXPECT_TRUE(expected) << file << ": " << m.dump();
        }
    }
}

// draco3d decodes every Draco primitive to exactly the accessor counts and POSITION bounds, and these
// match the source mesh (manifold spheres: Draco keeps every vertex) within the quantization step.
TEST_F(GltfFiles, draco_primitives_decode_to_accessors_and_source)
{
    const std::map<std::string, std::string> sources{
        {"sphere_draco.glb", "sphere"}, {"colors_draco.glb", "colors"}, {"far_draco.gltf", "far"}, {"big_draco.glb", "big"}};
    for (const auto& [file, mesh_name] : sources) {
        const json& r = draco_result(file);
        EXPECT_TRUE(r["problems"].empty()) << r.dump(1);
        ASSERT_EQ(r["primitives"].size(), 1u) << file;
        const json& p = r["primitives"][0];
        const Mesh& mesh = meshes_->at(mesh_name);
        EXPECT_EQ(p["points"], mesh.n_vertices()) << file;
        EXPECT_EQ(p["faces"], mesh.n_faces()) << file;
        const MeshBuffers b = make_mesh_buffers(mesh);
        double extent = 0;
        for (int k = 0; k < 3; ++k)
            extent = std::max(extent, double(b.max[k]) - b.min[k]);
        const double step = extent / ((1 << DracoOptions{}.position_bits) - 1);
        for (std::size_t k = 0; k < 3; ++k) {
            EXPECT_NEAR(p["min"][k].get<double>(), b.min[k], step) << file;
            EXPECT_NEAR(p["max"][k].get<double>(), b.max[k], step) << file;
        }
    }
    const json& lods = draco_result("lods_draco.glb");
    EXPECT_TRUE(lods["problems"].empty()) << lods.dump(1);
    EXPECT_EQ(lods["primitives"].size(), 3u);
}

// A plain .glb and .gltf we write load with tinygltf and reproduce the input: positions + node
// translation equal the (rotated) absolute coordinates, far from the origin too.
TEST_F(GltfFiles, tinygltf_loads_and_reproduces_positions)
{
    struct Case { const char* file; const char* mesh; Vec3 origin; UpAxis up; int index_type; double tolerance; };
    const Case cases[] = {
        {"sphere.glb", "sphere", {}, UpAxis::Z, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 1e-7},
        {"sphere.gltf", "sphere", {}, UpAxis::Z, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 1e-7},
        {"yup.glb", "sphere", {}, UpAxis::Y, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 1e-7},
        // Absolute float32 at 5e6 would be off by up to 0.25; the offset keeps it at float(10) precision.
        {"far.glb", "far", kFarOrigin, UpAxis::Z, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 2e-6},
        {"big.glb", "big", {}, UpAxis::Z, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, 3e-7},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.file);
        const tinygltf::Model model = load(c.file);
        ASSERT_EQ(model.nodes.size(), 1u);
        const tinygltf::Node& node = model.nodes[0];
        std::vector<double> t = node.translation.empty() ? std::vector<double>{0, 0, 0} : node.translation;
        const tinygltf::Primitive& prim = model.meshes.at(static_cast<std::size_t>(node.mesh)).primitives.at(0);
        const tinygltf::Accessor& pos = model.accessors.at(static_cast<std::size_t>(prim.attributes.at("POSITION")));
        const tinygltf::Accessor& idx = model.accessors.at(static_cast<std::size_t>(prim.indices));
        EXPECT_EQ(idx.componentType, c.index_type);
        EXPECT_EQ(prim.attributes.count("NORMAL"), 1u);
        auto data = [&](const tinygltf::Accessor& a) {
            const tinygltf::BufferView& v = model.bufferViews.at(static_cast<std::size_t>(a.bufferView));
            return model.buffers.at(static_cast<std::size_t>(v.buffer)).data.data() + v.byteOffset + a.byteOffset;
        };
        const auto* positions = reinterpret_cast<const float*>(data(pos));
        const Mesh& mesh = meshes_->at(c.mesh);
        ASSERT_EQ(pos.count, mesh.n_vertices());
        ASSERT_EQ(idx.count, 3 * mesh.n_faces());
        // The writer reorders triangles for the GPU cache: compare them as a set, in their winding.
        std::vector<Vec3> absolute(pos.count);
        for (std::size_t i = 0; i < pos.count; ++i)
            for (int d = 0; d < 3; ++d)
                absolute[i][d] = t[static_cast<std::size_t>(d)] + positions[3 * i + static_cast<std::size_t>(d)];
        std::vector<std::size_t> corners(idx.count);
        for (std::size_t k = 0; k < idx.count; ++k)
            corners[k] = c.index_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT ? reinterpret_cast<const std::uint32_t*>(data(idx))[k]
                                                                              : reinterpret_cast<const std::uint16_t*>(data(idx))[k];
        const double worst = testing::worst_triangle_mismatch(
            mesh, [&](const Vec3& p) { return to_output_frame(c.origin + p, c.up); }, absolute, corners);
        EXPECT_LE(worst, c.tolerance);
    }
    const tinygltf::Model coloured = load("colors.glb");
    const tinygltf::Accessor& color =
        coloured.accessors.at(static_cast<std::size_t>(coloured.meshes[0].primitives[0].attributes.at("COLOR_0")));
    EXPECT_EQ(color.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
    EXPECT_TRUE(color.normalized);
    EXPECT_EQ(color.type, TINYGLTF_TYPE_VEC4);
}

// A mesh's last GltfOptions::skirt_faces faces (a 3D Tiles tile's skirts) are a second primitive whose
// material is single-sided, so that viewers cull a skirt seen from behind: double-sided, its back shows
// with reversed normals, and it drew dark dashes where its top edge meets the neighbour's surface (QA
// round 72). The two primitives hold the mesh's faces, in one node frame, loaded by tinygltf; Draco
// encodes each on its own (draco3d decodes them to the same counts).
TEST_F(GltfFiles, skirts_are_a_second_single_sided_primitive)
{
    const Mesh& mesh = meshes_->at("far");
    const tinygltf::Model model = load("skirted.glb");
    ASSERT_EQ(model.meshes.size(), 1u);
    const auto& primitives = model.meshes[0].primitives;
    ASSERT_EQ(primitives.size(), 2u);
    const auto material = [&](const tinygltf::Primitive& p) { return model.materials.at(static_cast<std::size_t>(p.material)); };
    EXPECT_TRUE(material(primitives[0]).doubleSided);
    EXPECT_FALSE(material(primitives[1]).doubleSided);
    // Plain: two index ranges over one set of vertex accessors (the skirts' top edges are surface
    // vertices, not written twice).
    EXPECT_EQ(primitives[0].attributes, primitives[1].attributes);
    EXPECT_EQ(model.accessors.at(static_cast<std::size_t>(primitives[0].attributes.at("POSITION"))).count, mesh.n_vertices());
    const std::vector<double> t = model.nodes.at(0).translation;
    ASSERT_EQ(t.size(), 3u);
    std::vector<Vec3> absolute;
    std::vector<std::size_t> corners;
    std::vector<std::size_t> faces;
    for (const tinygltf::Primitive& prim : primitives) {
        const tinygltf::Accessor& pos = model.accessors.at(static_cast<std::size_t>(prim.attributes.at("POSITION")));
        const tinygltf::Accessor& idx = model.accessors.at(static_cast<std::size_t>(prim.indices));
        EXPECT_EQ(prim.attributes.count("NORMAL"), 1u);
        auto data = [&](const tinygltf::Accessor& a) {
            const tinygltf::BufferView& v = model.bufferViews.at(static_cast<std::size_t>(a.bufferView));
            return model.buffers.at(static_cast<std::size_t>(v.buffer)).data.data() + v.byteOffset + a.byteOffset;
        };
        ASSERT_EQ(idx.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        const std::size_t base = absolute.size();
        const auto* positions = reinterpret_cast<const float*>(data(pos));
        for (std::size_t i = 0; i < pos.count; ++i)
            absolute.push_back(Vec3{t[0] + positions[3 * i], t[1] + positions[3 * i + 1], t[2] + positions[3 * i + 2]});
        for (std::size_t k = 0; k < idx.count; ++k)
            corners.push_back(base + reinterpret_cast<const std::uint16_t*>(data(idx))[k]);
        faces.push_back(idx.count / 3);
    }
    EXPECT_EQ(faces, (std::vector<std::size_t>{mesh.n_faces() - kSkirtFaces, kSkirtFaces}));
    const double worst = testing::worst_triangle_mismatch(
        mesh, [&](const Vec3& p) { return to_output_frame(kFarOrigin + p, UpAxis::Z); }, absolute, corners);
    EXPECT_LE(worst, 2e-6); // float(10) precision, as far.glb
    // The skirts' own faces: the surface primitive holds none of the last ones.
    MeshBufferOptions last;
    last.first_face = mesh.n_faces() - kSkirtFaces;
    EXPECT_EQ(make_mesh_buffers(mesh, last).face_count(), kSkirtFaces);

    const json& r = draco_result("skirted_draco.glb");
    EXPECT_TRUE(r["problems"].empty()) << r.dump(1);
    ASSERT_EQ(r["primitives"].size(), 2u);
    EXPECT_EQ(r["primitives"][0]["faces"], mesh.n_faces() - kSkirtFaces);
    EXPECT_EQ(r["primitives"][1]["faces"], kSkirtFaces);
    const json doc = glb_json(dir_ / "skirted_draco.glb");
    EXPECT_FALSE(doc["materials"][doc["meshes"][0]["primitives"][1]["material"].get<std::size_t>()]["doubleSided"].get<bool>());

    // Without skirts, or single-sided throughout, one material; skirts must leave a surface.
    EXPECT_EQ(glb_json(dir_ / "far.glb")["materials"].size(), 1u);
    GltfOptions one_sided;
    one_sided.double_sided = false;
    one_sided.skirt_faces = kSkirtFaces;
    const std::string bytes = glb_bytes(mesh, kFarOrigin, one_sided);
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    const json single = json::parse(bytes.substr(20, length));
    EXPECT_EQ(single["materials"].size(), 1u);
    EXPECT_EQ(single["meshes"][0]["primitives"].size(), 2u);
    GltfOptions all_skirt;
    all_skirt.skirt_faces = mesh.n_faces();
    EXPECT_THROW(glb_bytes(mesh, kFarOrigin, all_skirt), InvalidInput);
    Mesh only_skirts_left = mesh; // every face before the skirts deleted
    only_skirts_left.request_face_status();
    only_skirts_left.request_edge_status();
    only_skirts_left.request_vertex_status();
    for (std::size_t f = 0; f + kSkirtFaces < mesh.n_faces(); ++f)
        only_skirts_left.delete_face(Mesh::FaceHandle(static_cast<int>(f)), false);
    GltfOptions skirts_only;
    skirts_only.skirt_faces = kSkirtFaces;
    EXPECT_THROW(glb_bytes(only_skirts_left, kFarOrigin, skirts_only), InvalidInput);
    GltfLodOptions lods;
    lods.gltf.skirt_faces = 1;
    EXPECT_THROW(write_glb_lods({&mesh}, kFarOrigin, dir_ / "never.glb", lods), InvalidInput);
    EXPECT_FALSE(fs::exists(dir_ / "never.glb"));
}

// glTF's COLOR_0 is linear; the mesh's colours are the points' sRGB bytes. QA round 28b: the bytes
// were written as they were, so viewers (three.js, Blender, CesiumJS) showed sRGB grey 128 as 188.
// Plain and Draco primitives hold 16-bit linear values (sRGB 128 -> 0.21586, 10 -> 0.0030353, alpha
// scaled as is); a bare .drc keeps the bytes (test_draco_encode).
TEST(WriteGltf, colours_are_linear_as_gltf_defines_them)
{
    Mesh mesh = uv_sphere(6, 12, 1.0, {}, true);
    for (const auto v : mesh.vertices())
        mesh.set_color(v, Mesh::Color(128, 10, 255, 200));
    const std::vector<std::uint16_t> expected{14146, 199, 65535, 51400};
    for (const bool draco : {false, true}) {
        SCOPED_TRACE(draco ? "draco" : "plain");
        GltfOptions options;
        options.draco = draco;
        const std::string bytes = glb_bytes(mesh, {}, options);
        std::uint32_t json_length = 0, bin_length = 0;
        std::memcpy(&json_length, bytes.data() + 12, 4);
        const json doc = json::parse(bytes.substr(20, json_length));
        std::memcpy(&bin_length, bytes.data() + 20 + json_length, 4);
        const std::string bin = bytes.substr(20 + json_length + 8, bin_length);
        const json& primitive = doc["meshes"][0]["primitives"][0];
        const json& accessor = doc["accessors"][primitive["attributes"]["COLOR_0"].get<std::size_t>()];
        EXPECT_EQ(accessor["componentType"], 5123); // UNSIGNED_SHORT
        EXPECT_EQ(accessor["normalized"], true);
        std::vector<std::uint16_t> values;
        if (draco) {
            const json& view = doc["bufferViews"][primitive["extensions"]["KHR_draco_mesh_compression"]["bufferView"].get<std::size_t>()];
            const DracoDecoded d = decode_draco(bin.substr(view["byteOffset"], view["byteLength"]), "COLOR_0");
            EXPECT_TRUE(d.colors.empty());
            values = d.linear_colors;
        } else {
            const json& view = doc["bufferViews"][accessor["bufferView"].get<std::size_t>()];
            values.resize(view["byteLength"].get<std::size_t>() / 2);
            std::memcpy(values.data(), bin.data() + view["byteOffset"].get<std::size_t>(), values.size() * 2);
        }
        ASSERT_EQ(values.size(), 4 * mesh.n_vertices());
        for (std::size_t i = 0; i < values.size(); ++i)
            ASSERT_EQ(values[i], expected[i % 4]) << "value " << i;
    }
}

// The z-up input is rotated into y-up: the origin (x, y, z) becomes the node translation (x, z, -y)
// plus the rounded per-file offset (the far sphere's centre (0.4, -0.3, 0) rounds to 0).
TEST_F(GltfFiles, z_up_origin_becomes_y_up_translation)
{
    const json far = glb_json(dir_ / "far.glb");
    EXPECT_EQ(far["nodes"][0]["translation"], json::array({kFarOrigin.x, kFarOrigin.z, -kFarOrigin.y}));
    EXPECT_FALSE(glb_json(dir_ / "sphere.glb")["nodes"][0].contains("translation"));
    EXPECT_EQ(far["asset"]["generator"], "libmrtile");
    EXPECT_EQ(far["asset"]["version"], "2.0");
}

TEST_F(GltfFiles, msft_lod_links_levels_from_the_finest_node)
{
    const json doc = glb_json(dir_ / "lods.glb");
    EXPECT_EQ(doc["extensionsUsed"], json::array({"MSFT_lod"}));
    EXPECT_FALSE(doc.contains("extensionsRequired"));
    EXPECT_EQ(doc["scenes"][0]["nodes"], json::array({0}));
    EXPECT_EQ(doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"], json::array({1, 2}));
    EXPECT_EQ(doc["nodes"][0]["extras"]["MSFT_screencoverage"], json::array({0.5, 0.2, 0.05}));
    ASSERT_EQ(doc["nodes"].size(), 3u);
    for (const json& node : doc["nodes"])
        EXPECT_NEAR(node["translation"][0].get<double>(), kFarOrigin.x, 1.0);
    const json draco = glb_json(dir_ / "lods_draco.glb");
    EXPECT_EQ(draco["extensionsUsed"], json::array({"KHR_draco_mesh_compression", "MSFT_lod"}));
    EXPECT_EQ(draco["extensionsRequired"], json::array({"KHR_draco_mesh_compression"}));
}

// "4999990.4, 90, -5000009.7" or "1,106": list items are separated by ", ", thousands by ",".
std::vector<double> numbers(const std::string& text)
{
    std::string clean;
    for (std::size_t i = 0; i < text.size(); ++i)
        if (text[i] != ',')
            clean += text[i];
        else if (i + 1 < text.size() && text[i + 1] == ' ')
            clean += ' ';
    std::vector<double> out;
    std::istringstream in(clean);
    for (double v; in >> v;)
        out.push_back(v);
    return out;
}

// gltf-transform (an independent reader, with its own Draco decoder) loads the files and finds the
// vertex count of the source mesh and the scene bounds at the absolute (y-up) coordinates.
TEST_F(GltfFiles, gltf_transform_reads_plain_and_draco_files)
{
    struct Case { const char* file; const char* mesh; Vec3 origin; };
    for (const Case& c : {Case{"colors.glb", "colors", {}}, Case{"far_draco.gltf", "far", kFarOrigin},
                          Case{"lods_draco.glb", "sphere", kFarOrigin}}) {
        SCOPED_TRACE(c.file);
        const std::string report = testing::gltf_transform_inspect((dir_ / c.file).string());
        const std::vector<std::string> mesh_row = testing::markdown_row(report, "vertices", "0");
        ASSERT_GE(mesh_row.size(), 6u) << report;
        EXPECT_EQ(numbers(mesh_row[5]), std::vector<double>{double(meshes_->at(c.mesh).n_vertices())}) << report;
        const std::vector<std::string> scene_row = testing::markdown_row(report, "bboxMin", "0");
        ASSERT_GE(scene_row.size(), 5u) << report;
        const std::vector<double> lo = numbers(scene_row[3]), hi = numbers(scene_row[4]);
        ASSERT_EQ(lo.size(), 3u) << scene_row[3];
        ASSERT_EQ(hi.size(), 3u) << scene_row[4];
        const MeshBuffers b = make_mesh_buffers(meshes_->at(c.mesh));
        const Vec3 shift = to_output_frame(c.origin, UpAxis::Z) + b.offset;
        for (std::size_t k = 0; k < 3; ++k) {
            EXPECT_NEAR(lo[k], shift[static_cast<int>(k)] + b.min[k], 0.051); // printed with one decimal
            EXPECT_NEAR(hi[k], shift[static_cast<int>(k)] + b.max[k], 0.051);
        }
    }
}

TEST(WriteGltf, output_is_byte_deterministic)
{
    const Mesh mesh = uv_sphere(10, 20, 1.0, {3, 4, 5}, true);
    for (const bool draco : {false, true}) {
        GltfOptions options;
        options.draco = draco;
        const std::string a = glb_bytes(mesh, kFarOrigin, options);
        const std::string b = glb_bytes(mesh, kFarOrigin, options);
        EXPECT_EQ(a, b);
        const fs::path path = fs::path(MRTILE_BINARY_DIR) / "test_write_gltf_determinism.glb";
        write_gltf(mesh, kFarOrigin, path, options);
        EXPECT_EQ(read_bytes(path), a);
        fs::remove(path);
    }
}

TEST(WriteGltf, draco_is_much_smaller)
{
    const Mesh mesh = uv_sphere(60, 120, 1.0);
    GltfOptions draco;
    draco.draco = true;
    EXPECT_LT(glb_bytes(mesh, {}, draco).size() * 4, glb_bytes(mesh, {}).size());
}

TEST(WriteGltf, bad_paths_throw_io_error_naming_the_path_and_leave_nothing)
{
    const fs::path dir = fs::path(MRTILE_BINARY_DIR) / "test_write_gltf_bad";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const Mesh mesh = uv_sphere(4, 8, 1.0);
    const fs::path missing_parent = dir / "no" / "such" / "dir" / "out.glb";
    std::ofstream(dir / "file") << "x";
    const fs::path parent_is_file = dir / "file" / "out.glb";
    const fs::path read_only = "/proc/mrtile_out.glb"; // read-only even for root
    for (const fs::path& path : {missing_parent, parent_is_file, read_only}) {
        try {
            write_gltf(mesh, {}, path);
            ADD_FAILURE() << "no exception for " << path;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        }
    }
    std::vector<fs::path> left;
    for (const auto& entry : fs::recursive_directory_iterator(dir))
        left.push_back(entry.path());
    EXPECT_EQ(left, std::vector<fs::path>{dir / "file"});
    EXPECT_THROW(write_gltf(mesh, {}, dir / "out.obj"), InvalidInput);
    EXPECT_THROW(write_glb_lods({}, {}, dir / "out.glb"), InvalidInput);
    GltfLodOptions bad_coverage;
    bad_coverage.screen_coverage = {0.1, 0.5};
    EXPECT_THROW(write_glb_lods({&mesh, &mesh}, {}, dir / "out.glb", bad_coverage), InvalidInput);
    fs::remove_all(dir);
}

} // namespace
} // namespace mrt
