// Output stage, compression: meshes cut from the hierarchy are sent to viewers, so they are Draco
// encoded (quantized positions, octahedral normals, edgebreaker connectivity). glTF accessors must
// describe what Draco actually stores (its encoder may split non-manifold vertices and reorders
// points), and min/max must be the dequantized bounds: the encoder's own counts and quantization
// transform give them without decoding the bytes again (which cost two thirds of the encode; the two
// agree, tested).
#include "formats/draco_encode.h"

#include "libmrtile/atomic_file.h"
#include "libmrtile/errors.h"

#include <draco/attributes/attribute_quantization_transform.h>
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/core/encoder_buffer.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/geometry_metadata.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <limits>
#include <memory>

namespace mrt {

namespace {

constexpr const char* kOriginEntry = "mrtile_origin";

void check_range(int value, int lo, int hi, const char* name)
{
    if (value < lo || value > hi)
        throw InvalidInput(std::string("DracoOptions::") + name + " = " + std::to_string(value) +
                           " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

void validate(const DracoOptions& options)
{
    // Draco's encoder takes memory in proportion to 2^bits whatever the mesh's size: 30 bits took 4.2 GB
    // per thread for 30 points (QA round 38), 24 bits 64 MB, a step of 6e-8 of the grid.
    check_range(options.position_bits, 1, kMaxPositionBits, "position_bits");
    check_range(options.normal_bits, 1, 30, "normal_bits");
    check_range(options.encoding_speed, 0, 10, "encoding_speed");
    check_range(options.decoding_speed, 0, 10, "decoding_speed");
    if (options.grid && !(options.grid->range > 0.0 && std::isfinite(options.grid->range) &&
                          is_finite(options.grid->min)))
        throw InvalidInput("DracoOptions::grid: range must be positive and finite, min finite");
}

// Adds an attribute with one value per point (identity mapping) copied from `values`.
int add_attribute(draco::Mesh& mesh, draco::GeometryAttribute::Type type, int components,
                  draco::DataType data_type, bool normalized, const void* values, std::size_t component_size)
{
    draco::GeometryAttribute attribute;
    const auto stride = static_cast<int64_t>(component_size) * components;
    attribute.Init(type, nullptr, static_cast<uint8_t>(components), data_type, normalized, stride, 0);
    const int id = mesh.AddAttribute(attribute, true, mesh.num_points());
    if (id < 0)
        throw InvalidInput("draco: cannot add attribute");
    draco::PointAttribute* added = mesh.attribute(id);
    const auto* bytes = static_cast<const unsigned char*>(values);
    for (uint32_t i = 0; i < mesh.num_points(); ++i)
        added->SetAttributeValue(draco::AttributeValueIndex(i), bytes + static_cast<std::size_t>(stride) * i);
    return id;
}

std::unique_ptr<draco::Mesh> decode_mesh(const char* data, std::size_t size, const std::string& what)
{
    draco::DecoderBuffer buffer;
    buffer.Init(data, size);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok())
        throw IoError(what + ": not a Draco mesh (" + decoded.status().error_msg_string() + ")");
    return std::move(decoded).value();
}

template <typename T, int N>
std::vector<T> read_attribute(const draco::Mesh& mesh, const draco::PointAttribute* attribute)
{
    std::vector<T> values;
    if (attribute == nullptr)
        return values;
    values.resize(static_cast<std::size_t>(mesh.num_points()) * N);
    for (uint32_t i = 0; i < mesh.num_points(); ++i)
        attribute->ConvertValue<T>(attribute->mapped_index(draco::PointIndex(i)), N, &values[std::size_t{i} * N]);
    return values;
}

// Draco 1.5 keeps encoder options as text with six decimals (std::to_string), so the explicit grid's
// range reaches it rounded to a millionth of a unit: under 5e-7 it was 0 and every vertex decoded to one
// point (QA round 59), and a range rounded down would leave the top vertices outside the cube. The range
// passed is the smallest whose text is not below `range`; if that coarsens the grid more than twice (a
// model under about a millionth of a unit across), the grid is refused rather than losing more than a bit.
float text_exact_range(float range)
{
    auto as_read = [](float r) { return std::stof(std::to_string(r)); };
    float r = range;
    for (int step = 0; step < 4 && as_read(r) < range; ++step)
        r = static_cast<float>((std::floor(static_cast<double>(r) * 1e6) + 1.0 + step) / 1e6);
    if (!(as_read(r) >= range) || as_read(r) > 2.0f * range) {
        char what[200];
        std::snprintf(what, sizeof what, "Draco: a model %.3g units across is too small for Draco's quantization grid (it keeps six "
                      "decimals: at least 1e-6 units); scale the points up, or leave Draco out", static_cast<double>(range));
        throw InvalidInput(what);
    }
    return r;
}

// The bounds of the positions a decoder gets back: the per-axis extremes of the input, quantized
// and dequantized by Draco's own transform with the parameters its encoder used: the explicit grid as
// the encoder reads it back from its options (which keep numbers as text with six decimals: the range
// differs from the one passed in, text_exact_range), or those it computes from the attribute. Quantizing and
// dequantizing never reorder two values, so the extremes of the decoded positions are the decoded
// extremes.
void decoded_bounds(const draco::Encoder& encoder, const draco::PointAttribute& positions, const MeshBuffers& buffers,
                    DracoEncoded& out)
{
    const auto position = draco::GeometryAttribute::POSITION;
    const auto& settings = encoder.options();
    const int bits = settings.GetAttributeInt(position, "quantization_bits", -1);
    draco::AttributeQuantizationTransform quantization;
    bool ok = false;
    if (settings.IsAttributeOptionSet(position, "quantization_range")) {
        std::array<float, 3> origin{};
        ok = settings.GetAttributeVector(position, "quantization_origin", 3, origin.data()) &&
             quantization.SetParameters(bits, origin.data(), 3, settings.GetAttributeFloat(position, "quantization_range", 1.0f));
    } else {
        ok = quantization.ComputeParameters(positions, bits);
    }
    if (!ok)
        throw InvalidInput("draco: cannot set up position quantization");
    draco::GeometryAttribute layout;
    layout.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, 3 * sizeof(float), 0);
    draco::PointAttribute extremes(layout);
    extremes.Reset(2);
    extremes.SetIdentityMapping();
    std::array<float, 3> lo, hi;
    lo.fill(std::numeric_limits<float>::infinity());
    hi.fill(-std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < buffers.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], buffers.positions[i]);
        hi[i % 3] = std::max(hi[i % 3], buffers.positions[i]);
    }
    extremes.SetAttributeValue(draco::AttributeValueIndex(0), lo.data());
    extremes.SetAttributeValue(draco::AttributeValueIndex(1), hi.data());
    const std::unique_ptr<draco::PointAttribute> quantized = quantization.InitTransformedAttribute(extremes, 2);
    draco::PointAttribute decoded(layout);
    decoded.Reset(2);
    decoded.SetIdentityMapping();
    if (!quantized || !quantization.TransformAttribute(extremes, {}, quantized.get()) ||
        !quantization.InverseTransformAttribute(*quantized, &decoded))
        throw InvalidInput("draco: cannot quantize the position bounds");
    decoded.GetValue(draco::AttributeValueIndex(0), out.min.data());
    decoded.GetValue(draco::AttributeValueIndex(1), out.max.data());
}

} // namespace

std::optional<Vec3> draco_grid_offset(const DracoOptions& options, UpAxis up)
{
    if (!options.grid)
        return std::nullopt;
    const QuantizationGrid& g = *options.grid;
    const Vec3 far = g.min + Vec3{g.range, g.range, g.range};
    return min(to_output_frame(g.min, up), to_output_frame(far, up));
}

DracoEncoded encode_draco(const MeshBuffers& buffers, const DracoOptions& options,
                          const std::optional<Vec3>& metadata_origin)
{
    validate(options);
    const std::size_t n = buffers.vertex_count();
    if (n == 0 || buffers.indices.empty())
        throw InvalidInput("draco: mesh has no faces to encode");
    if (n > static_cast<std::size_t>(std::numeric_limits<int32_t>::max()))
        throw InvalidInput("draco: more than 2^31 vertices");

    draco::Mesh mesh;
    mesh.set_num_points(static_cast<uint32_t>(n));
    mesh.SetNumFaces(buffers.face_count());
    for (std::size_t f = 0; f < buffers.face_count(); ++f) {
        draco::Mesh::Face face;
        for (std::size_t k = 0; k < 3; ++k)
            face[k] = draco::PointIndex(buffers.indices[3 * f + k]);
        mesh.SetFace(draco::FaceIndex(static_cast<uint32_t>(f)), face);
    }
    add_attribute(mesh, draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, false,
                  buffers.positions.data(), sizeof(float));
    if (!buffers.normals.empty())
        add_attribute(mesh, draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32, false,
                      buffers.normals.data(), sizeof(float));
    if (!buffers.colors.empty() && options.linear_colors) {
        const std::vector<std::uint16_t> linear = linear_colors(buffers.colors);
        add_attribute(mesh, draco::GeometryAttribute::COLOR, 4, draco::DT_UINT16, true, linear.data(),
                      sizeof(std::uint16_t));
    } else if (!buffers.colors.empty()) {
        add_attribute(mesh, draco::GeometryAttribute::COLOR, 4, draco::DT_UINT8, true,
                      buffers.colors.data(), 1);
    }
    if (metadata_origin) {
        auto metadata = std::make_unique<draco::GeometryMetadata>();
        metadata->AddEntryDoubleArray(kOriginEntry, {metadata_origin->x, metadata_origin->y, metadata_origin->z});
        mesh.AddMetadata(std::move(metadata));
    }

    draco::Encoder encoder;
    encoder.SetSpeedOptions(options.encoding_speed, options.decoding_speed);
    // Chosen here, not left to Draco, so that draco_keeps_face_order is true of what we write.
    encoder.SetEncodingMethod(draco_keeps_face_order(options) ? draco::MESH_SEQUENTIAL_ENCODING
                                                              : draco::MESH_EDGEBREAKER_ENCODING);
    encoder.SetTrackEncodedProperties(true); // the points and faces a decoder will get (see below)
    if (options.grid) {
        // The buffers are relative to the grid's min corner, so the grid starts at local 0. Draco
        // quantizes round((v - origin) / step) without clamping: a value outside would wrap.
        const auto range = static_cast<float>(options.grid->range);
        for (std::size_t i = 0; i < buffers.positions.size(); ++i) {
            const float v = buffers.positions[i];
            if (!(v >= 0.0f && v <= range)) {
                char detail[160];
                std::snprintf(detail, sizeof detail, "coordinate %.9g not in [0, %.9g]", v, range);
                throw InvalidInput("DracoOptions::grid: vertex " + std::to_string(i / 3) +
                                   " lies outside the explicit quantization cube (" + detail + ")");
            }
        }
        const float grid_origin[3] = {0.0f, 0.0f, 0.0f};
        encoder.SetAttributeExplicitQuantization(draco::GeometryAttribute::POSITION, options.position_bits, 3,
                                                 grid_origin, text_exact_range(range));
    } else {
        encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.position_bits);
    }
    encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, options.normal_bits);

    draco::EncoderBuffer encoded;
    const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &encoded);
    if (!status.ok())
        throw InvalidInput("draco: encoding failed (" + status.error_msg_string() + ")");

    DracoEncoded out;
    out.bytes.assign(encoded.data(), encoded.size());
    // What a decoder gets back, without decoding: the encoder counts the points and faces it wrote,
    // splits included, and the attributes keep the unique ids they have here.
    out.vertex_count = encoder.num_encoded_points();
    out.face_count = encoder.num_encoded_faces();
    auto unique_id = [&](draco::GeometryAttribute::Type type) {
        const draco::PointAttribute* a = mesh.GetNamedAttribute(type);
        return a ? static_cast<int>(a->unique_id()) : -1;
    };
    out.position_id = unique_id(draco::GeometryAttribute::POSITION);
    out.normal_id = unique_id(draco::GeometryAttribute::NORMAL);
    out.color_id = unique_id(draco::GeometryAttribute::COLOR);
    decoded_bounds(encoder, *mesh.GetNamedAttribute(draco::GeometryAttribute::POSITION), buffers, out);
    return out;
}

DracoDecoded decode_draco(const std::string& bytes, const std::string& what)
{
    const auto mesh = decode_mesh(bytes.data(), bytes.size(), what);
    DracoDecoded out;
    out.positions = read_attribute<float, 3>(*mesh, mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION));
    out.normals = read_attribute<float, 3>(*mesh, mesh->GetNamedAttribute(draco::GeometryAttribute::NORMAL));
    const draco::PointAttribute* color = mesh->GetNamedAttribute(draco::GeometryAttribute::COLOR);
    if (color != nullptr && color->data_type() == draco::DT_UINT16)
        out.linear_colors = read_attribute<std::uint16_t, 4>(*mesh, color);
    else
        out.colors = read_attribute<std::uint8_t, 4>(*mesh, color);
    out.indices.reserve(static_cast<std::size_t>(mesh->num_faces()) * 3);
    for (uint32_t f = 0; f < mesh->num_faces(); ++f)
        for (int k = 0; k < 3; ++k)
            out.indices.push_back(mesh->face(draco::FaceIndex(f))[k].value());
    if (const draco::GeometryMetadata* metadata = mesh->GetMetadata()) {
        std::vector<double> origin;
        if (metadata->GetEntryDoubleArray(kOriginEntry, &origin) && origin.size() == 3)
            out.metadata_origin = Vec3{origin[0], origin[1], origin[2]};
    }
    return out;
}

bool draco_keeps_face_order(const DracoOptions& options)
{
    return std::max(options.encoding_speed, options.decoding_speed) == 10;
}

void write_drc(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path, const DracoOptions& options)
{
    validate(options);
    if (!is_finite(origin))
        throw InvalidInput(path.string() + ": the origin is not finite");
    MeshBufferOptions buffer_options;
    buffer_options.up_axis = UpAxis::Y; // .drc has no axis convention: keep the mesh's axes
    buffer_options.offset = draco_grid_offset(options, UpAxis::Y);
    buffer_options.gpu_order = draco_keeps_face_order(options);
    const MeshBuffers buffers = make_mesh_buffers(mesh, buffer_options);
    const DracoEncoded encoded = encode_draco(buffers, options, origin + buffers.offset);
    write_file_atomically(path, encoded.bytes);
}

} // namespace mrt
