// Output stage, viewer format: the meshes cut from the hierarchy are delivered as glTF 2.0, the format
// web viewers and 3D Tiles load. This is the one place glTF is written (JSON with nlohmann-json, the
// binary chunk by hand), so every writer (single file, LODs, tiles) shares the same layout rules:
// 4-byte aligned buffer views, smallest index type without the primitive-restart value, exact float
// min/max on POSITION, and a node translation in double for the per-file offset.
#include "formats/write_gltf.h"

#include "libmrtile/atomic_file.h"
#include "libmrtile/errors.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>

namespace mrt {

namespace {

using Json = nlohmann::ordered_json;

// glTF enums (spec section 5): component types and buffer-view targets.
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;
constexpr int kTriangles = 4;

constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";
constexpr const char* kLodExtension = "MSFT_lod";

Json float_array(const std::array<float, 3>& v)
{
    // float -> double is exact, and nlohmann prints doubles round-trip: validators compare min/max
    // with the data exactly.
    return Json::array({static_cast<double>(v[0]), static_cast<double>(v[1]), static_cast<double>(v[2])});
}

// Collects buffer views, accessors, meshes and nodes of one glTF asset with a single binary buffer.
class GltfBuilder
{
public:
    explicit GltfBuilder(const GltfOptions& options) : options_(options) { check_up_axis(options.up_axis); }

    //! Adds a node showing `mesh`; returns its index. The node is not put in the scene.
    std::size_t add_mesh_node(const Mesh& mesh, const Vec3& origin, const std::string& name)
    {
        // A NaN would be written as JSON null, which no viewer reads as a number.
        if (!is_finite(origin) || (options_.offset && !is_finite(*options_.offset)))
            throw InvalidInput("glTF: the origin (or offset) is not finite");
        MeshBufferOptions buffer_options;
        buffer_options.up_axis = options_.up_axis;
        buffer_options.normals = options_.normals;
        buffer_options.colors = options_.colors;
        buffer_options.offset = options_.offset;
        // Draco's edgebreaker writes faces and vertices in its own order: a vertex-cache order made here
        // would be lost (draco_encode.h).
        buffer_options.gpu_order = !options_.draco || draco_keeps_face_order(options_.draco_options);
        if (options_.draco && options_.draco_options.grid)
            buffer_options.offset = draco_grid_offset(options_.draco_options, options_.up_axis);
        const std::size_t skirt_faces = options_.skirt_faces;
        if (skirt_faces > 0 && skirt_faces >= mesh.n_faces())
            throw InvalidInput("glTF: skirt_faces " + std::to_string(skirt_faces) + " is not below the mesh's " +
                               std::to_string(mesh.n_faces()) + " faces");
        const std::size_t surface_faces = mesh.n_faces() - skirt_faces;
        if (options_.draco)
            buffer_options.end_face = surface_faces;
        else
            buffer_options.split_face = surface_faces;
        const MeshBuffers buffers = make_mesh_buffers(mesh, buffer_options);
        if (buffers.split_triangle == 0) // the faces before the skirts all deleted
            throw InvalidInput("glTF: no face of the mesh before its " + std::to_string(skirt_faces) + " skirt faces");
        Json primitives = Json::array();
        if (!options_.draco) {
            // Surface and skirts as two index ranges over one set of vertex accessors (the skirts' top
            // edges are surface vertices).
            const Json attributes = plain_attributes(buffers);
            primitives.push_back(plain_primitive(attributes, buffers, 0, buffers.split_triangle, material_index(options_.double_sided)));
            if (skirt_faces > 0)
                primitives.push_back(plain_primitive(attributes, buffers, buffers.split_triangle, buffers.face_count(), material_index(false)));
        } else {
            primitives.push_back(primitive(draco_primitive(buffers), material_index(options_.double_sided)));
            if (skirt_faces > 0) {
                // A Draco stream holds its own vertices: the skirts' (their top edges copy surface
                // vertices) in the surface's frame, so that one node translation serves both.
                buffer_options.first_face = surface_faces;
                buffer_options.end_face = mesh.n_faces();
                buffer_options.offset = buffers.offset;
                primitives.push_back(primitive(draco_primitive(make_mesh_buffers(mesh, buffer_options)), material_index(false)));
            }
        }
        const std::size_t mesh_index = meshes_.size();
        meshes_.push_back(Json{{"name", name}, {"primitives", std::move(primitives)}});

        Json node{{"name", name}, {"mesh", mesh_index}};
        const Vec3 translation = to_output_frame(origin, options_.up_axis) + buffers.offset;
        if (translation != Vec3{})
            node["translation"] = Json::array({translation.x, translation.y, translation.z});
        nodes_.push_back(std::move(node));
        return nodes_.size() - 1;
    }

    Json& node(std::size_t index) { return nodes_[index]; }

    void use_extension(const char* name, bool required)
    {
        if (std::find(used_.begin(), used_.end(), name) == used_.end())
            used_.push_back(name);
        if (required && std::find(required_.begin(), required_.end(), name) == required_.end())
            required_.push_back(name);
    }

    //! The whole asset as a .glb file.
    std::string glb(const std::vector<std::size_t>& scene_nodes) const
    {
        std::string json = document(scene_nodes, std::nullopt).dump();
        json.append(padding(json.size()), ' ');
        std::string bin = bin_;
        bin.append(padding(bin.size()), '\0');
        const std::size_t total = 12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size());
        if (total > std::numeric_limits<std::uint32_t>::max())
            throw InvalidInput("glTF: the asset exceeds the 4 GiB limit of a .glb file");
        std::string out;
        out.reserve(total);
        append_u32(out, 0x46546C67u); // "glTF"
        append_u32(out, 2);
        append_u32(out, static_cast<std::uint32_t>(total));
        append_u32(out, static_cast<std::uint32_t>(json.size()));
        append_u32(out, 0x4E4F534Au); // "JSON"
        out += json;
        if (!bin.empty()) {
            append_u32(out, static_cast<std::uint32_t>(bin.size()));
            append_u32(out, 0x004E4942u); // "BIN\0"
            out += bin;
        }
        return out;
    }

    //! The whole asset as a .gltf file with the buffer embedded as a base64 data URI: one file, so
    //! that it can be written atomically like every other output.
    std::string gltf(const std::vector<std::size_t>& scene_nodes) const
    {
        return document(scene_nodes, "data:application/octet-stream;base64," + base64(bin_)).dump(1) + "\n";
    }

private:
    static std::size_t padding(std::size_t size) { return (4 - size % 4) % 4; }

    static void append_u32(std::string& out, std::uint32_t value)
    {
        for (int k = 0; k < 4; ++k)
            out.push_back(static_cast<char>((value >> (8 * k)) & 0xFFu));
    }

    static std::string base64(const std::string& bytes)
    {
        static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        std::string out;
        out.reserve((bytes.size() + 2) / 3 * 4);
        for (std::size_t i = 0; i < bytes.size(); i += 3) {
            const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
            std::uint32_t word = 0;
            for (std::size_t k = 0; k < 3; ++k)
                word = (word << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
            for (std::size_t k = 0; k < 4; ++k)
                out.push_back(k <= n ? alphabet[(word >> (18 - 6 * k)) & 0x3Fu] : '=');
        }
        return out;
    }

    std::size_t add_view(const void* data, std::size_t size, std::optional<int> target)
    {
        bin_.append(padding(bin_.size()), '\0'); // 4-byte alignment for every accessor type
        Json view{{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", size}};
        if (target)
            view["target"] = *target;
        bin_.append(static_cast<const char*>(data), size);
        views_.push_back(std::move(view));
        return views_.size() - 1;
    }

    std::size_t add_accessor(Json accessor)
    {
        accessors_.push_back(std::move(accessor));
        return accessors_.size() - 1;
    }

    static int index_type(std::size_t vertex_count)
    {
        // 65535 is the primitive-restart value, which glTF forbids as an index; UNSIGNED_BYTE indices
        // are legal but a performance warning in the Khronos validator and slow on some GPUs.
        return vertex_count <= 65535 ? kUnsignedShort : kUnsignedInt;
    }

    Json plain_attributes(const MeshBuffers& b)
    {
        const std::size_t n = b.vertex_count();
        Json attributes;
        attributes["POSITION"] = add_accessor(
            Json{{"bufferView", add_view(b.positions.data(), b.positions.size() * sizeof(float), kArrayBuffer)},
                 {"componentType", kFloat},
                 {"count", n},
                 {"type", "VEC3"},
                 {"min", float_array(b.min)},
                 {"max", float_array(b.max)}});
        if (!b.normals.empty())
            attributes["NORMAL"] = add_accessor(
                Json{{"bufferView", add_view(b.normals.data(), b.normals.size() * sizeof(float), kArrayBuffer)},
                     {"componentType", kFloat},
                     {"count", n},
                     {"type", "VEC3"}});
        if (!b.colors.empty()) {
            // COLOR_0 is linear in glTF; the mesh's colours are sRGB bytes (linear_colors).
            const std::vector<std::uint16_t> linear = linear_colors(b.colors);
            attributes["COLOR_0"] = add_accessor(
                Json{{"bufferView", add_view(linear.data(), linear.size() * sizeof(std::uint16_t), kArrayBuffer)},
                     {"componentType", kUnsignedShort},
                     {"normalized", true},
                     {"count", n},
                     {"type", "VEC4"}});
        }
        return attributes;
    }

    // Triangles [first, end) of `b` drawn with `attributes` (plain_attributes of b) and `material`.
    Json plain_primitive(const Json& attributes, const MeshBuffers& b, std::size_t first, std::size_t end, std::size_t material)
    {
        const int type = index_type(b.vertex_count());
        assert(first < end && 3 * end <= b.indices.size());
        const std::uint32_t* begin = b.indices.data() + 3 * first;
        const std::uint32_t* stop = b.indices.data() + 3 * end;
        std::size_t view;
        if (type == kUnsignedShort) {
            std::vector<std::uint16_t> narrow(begin, stop);
            view = add_view(narrow.data(), narrow.size() * sizeof(std::uint16_t), kElementArrayBuffer);
        } else {
            view = add_view(begin, static_cast<std::size_t>(stop - begin) * sizeof(std::uint32_t), kElementArrayBuffer);
        }
        const std::size_t indices = add_accessor(
            Json{{"bufferView", view}, {"componentType", type}, {"count", 3 * (end - first)}, {"type", "SCALAR"}});
        return primitive(Json{{"attributes", attributes}, {"indices", indices}}, material);
    }

    Json draco_primitive(const MeshBuffers& b)
    {
        DracoOptions draco_options = options_.draco_options;
        draco_options.linear_colors = true; // COLOR_0 is linear in glTF
        const DracoEncoded encoded = encode_draco(b, draco_options);
        use_extension(kDracoExtension, true);
        // Accessors without bufferView: the counts and bounds are those of the decoded Draco mesh.
        Json attributes, draco_attributes;
        attributes["POSITION"] = add_accessor(Json{{"componentType", kFloat},
                                                   {"count", encoded.vertex_count},
                                                   {"type", "VEC3"},
                                                   {"min", float_array(encoded.min)},
                                                   {"max", float_array(encoded.max)}});
        draco_attributes["POSITION"] = encoded.position_id;
        if (encoded.normal_id >= 0) {
            attributes["NORMAL"] = add_accessor(
                Json{{"componentType", kFloat}, {"count", encoded.vertex_count}, {"type", "VEC3"}});
            draco_attributes["NORMAL"] = encoded.normal_id;
        }
        if (encoded.color_id >= 0) {
            attributes["COLOR_0"] = add_accessor(Json{
                {"componentType", kUnsignedShort}, {"normalized", true}, {"count", encoded.vertex_count}, {"type", "VEC4"}});
            draco_attributes["COLOR_0"] = encoded.color_id;
        }
        const std::size_t indices = add_accessor(Json{{"componentType", index_type(encoded.vertex_count)},
                                                      {"count", encoded.face_count * 3},
                                                      {"type", "SCALAR"}});
        const std::size_t view = add_view(encoded.bytes.data(), encoded.bytes.size(), std::nullopt);
        Json primitive{{"attributes", attributes}, {"indices", indices}};
        primitive["extensions"][kDracoExtension] = Json{{"bufferView", view}, {"attributes", draco_attributes}};
        return primitive;
    }

    // The material of that sidedness, added at first use (so a file without skirts has one).
    std::size_t material_index(bool double_sided)
    {
        const char* name = double_sided == options_.double_sided ? "libmrtile" : "libmrtile skirts";
        for (std::size_t i = 0; i < materials_.size(); ++i)
            if (materials_[i]["doubleSided"] == double_sided)
                return i;
        // metallicFactor defaults to 1, which renders black without an environment map.
        materials_.push_back(Json{{"name", name},
                                  {"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}},
                                  {"doubleSided", double_sided}});
        return materials_.size() - 1;
    }

    static Json primitive(Json out, std::size_t material)
    {
        out["material"] = material;
        out["mode"] = kTriangles;
        return out;
    }

    Json document(const std::vector<std::size_t>& scene_nodes, const std::optional<std::string>& uri) const
    {
        Json doc;
        doc["asset"] = Json{{"version", "2.0"}, {"generator", "libmrtile"}};
        if (!used_.empty())
            doc["extensionsUsed"] = used_;
        if (!required_.empty())
            doc["extensionsRequired"] = required_;
        doc["scene"] = 0;
        doc["scenes"] = Json::array({Json{{"nodes", scene_nodes}}});
        doc["nodes"] = nodes_;
        doc["meshes"] = meshes_;
        doc["materials"] = materials_;
        doc["accessors"] = accessors_;
        doc["bufferViews"] = views_;
        Json buffer{{"byteLength", bin_.size() + padding(bin_.size())}};
        if (uri) {
            // The data URI holds exactly byteLength bytes.
            buffer["byteLength"] = bin_.size();
            buffer["uri"] = *uri;
        }
        doc["buffers"] = Json::array({buffer});
        return doc;
    }

    GltfOptions options_;
    std::string bin_;
    Json views_ = Json::array(), accessors_ = Json::array(), meshes_ = Json::array(), nodes_ = Json::array(),
         materials_ = Json::array();
    std::vector<std::string> used_, required_;
};

enum class Container { Glb, Gltf };

Container container_of(const std::filesystem::path& path)
{
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".glb")
        return Container::Glb;
    if (ext == ".gltf")
        return Container::Gltf;
    throw InvalidInput(path.string() + ": unknown glTF file extension (use .glb or .gltf)");
}

} // namespace

std::string glb_bytes(const Mesh& mesh, const Vec3& origin, const GltfOptions& options)
{
    GltfBuilder builder(options);
    const std::size_t node = builder.add_mesh_node(mesh, origin, "mesh");
    return builder.glb({node});
}

void write_gltf(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path, const GltfOptions& options)
{
    const Container container = container_of(path);
    GltfBuilder builder(options);
    const std::size_t node = builder.add_mesh_node(mesh, origin, "mesh");
    write_file_atomically(path, container == Container::Glb ? builder.glb({node}) : builder.gltf({node}));
}

void write_glb_lods(const std::vector<const Mesh*>& levels_fine_to_coarse, const Vec3& origin,
                    const std::filesystem::path& path, const GltfLodOptions& options)
{
    const Container container = container_of(path);
    const auto& levels = levels_fine_to_coarse;
    if (levels.empty())
        throw InvalidInput("write_glb_lods: no levels given");
    if (options.gltf.skirt_faces != 0)
        throw InvalidInput("write_glb_lods: GltfOptions::skirt_faces must be 0 (it names faces of one mesh)");
    const auto& coverage = options.screen_coverage;
    if (!coverage.empty()) {
        if (coverage.size() != levels.size())
            throw InvalidInput("GltfLodOptions::screen_coverage: " + std::to_string(coverage.size()) +
                               " values for " + std::to_string(levels.size()) + " levels");
        for (std::size_t i = 0; i < coverage.size(); ++i)
            if (!std::isfinite(coverage[i]) || coverage[i] < 0.0 || (i > 0 && coverage[i] > coverage[i - 1]))
                throw InvalidInput("GltfLodOptions::screen_coverage: values must be finite, >= 0 and decreasing");
    }
    GltfBuilder builder(options.gltf);
    std::vector<std::size_t> nodes;
    for (std::size_t i = 0; i < levels.size(); ++i) {
        if (levels[i] == nullptr)
            throw InvalidInput("write_glb_lods: level " + std::to_string(i) + " is null");
        nodes.push_back(builder.add_mesh_node(*levels[i], origin, "lod" + std::to_string(i)));
    }
    if (levels.size() > 1) {
        builder.use_extension(kLodExtension, false);
        Json& finest = builder.node(nodes[0]);
        finest["extensions"][kLodExtension] = Json{{"ids", std::vector<std::size_t>(nodes.begin() + 1, nodes.end())}};
        if (!coverage.empty())
            finest["extras"]["MSFT_screencoverage"] = coverage;
    }
    write_file_atomically(path, container == Container::Glb ? builder.glb({nodes[0]}) : builder.gltf({nodes[0]}));
}

} // namespace mrt
