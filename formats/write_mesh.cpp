// Mesh output (formats/): the reconstructed surface (paper §4.3) in the formats every mesh tool opens,
// for inspection and for users who want one mesh rather than 3D Tiles. OpenMesh's IO does the encoding;
// this file adds what the library promises of every writer: the origin added back, atomic replacement
// of the target, typed errors, and no console output.
#include "formats/write_mesh.h"

#include "libmrtile/atomic_file.h"
#include "libmrtile/errors.h"

#include <OpenMesh/Core/IO/MeshIO.hh>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

namespace mrt {
namespace {

enum class MeshFormat { ply, obj, off, stl, om };

MeshFormat mesh_format(const std::filesystem::path& path, std::string& ext)
{
    ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".ply") return MeshFormat::ply;
    if (ext == ".obj") return MeshFormat::obj;
    if (ext == ".off") return MeshFormat::off;
    if (ext == ".stl") return MeshFormat::stl;
    if (ext == ".om") return MeshFormat::om;
    throw InvalidInput(path.string() + ": unknown mesh extension '" + ext +
                       "'; expected .ply, .obj, .off, .stl or .om");
}

OpenMesh::IO::Options io_options(MeshFormat format, const Mesh& mesh, const WriteMeshOptions& options)
{
    using O = OpenMesh::IO::Options;
    O io;
    const bool colors = options.colors && mesh.has_vertex_colors();
    switch (format) {
    case MeshFormat::ply:
        if (options.binary)
            io += O::Binary | O::LSB;
        if (colors)
            io += O::VertexColor | O::ColorAlpha;
        break;
    case MeshFormat::off:
        if (colors)
            io += O::VertexColor | O::ColorAlpha;
        break;
    case MeshFormat::om:
        io += O::Binary;
        if (colors)
            io += O::VertexColor;
        break;
    case MeshFormat::stl:
        io += O::Binary;  // facet normals are computed by the writer; STL has no vertex normals
        break;
    case MeshFormat::obj:
        break;  // OpenMesh's OBJ writer refuses vertex colours
    }
    if (options.normals && format != MeshFormat::stl)
        io += O::VertexNormal;
    return io;
}

// Float keeps 24 bits: beyond about 16 extents from the origin it loses more than a millionth of the
// mesh's extent (a survey in UTM coordinates, 5,000 km north: half a metre). Such meshes are written with
// double coordinates (PLY, OBJ, OFF; .om always keeps doubles, STL has only floats). `shift` is added
// to every position first (the origin of a mesh stored relative to it), `fraction` is of the extent;
// `edge_fraction` (0 = not asked) of the mean edge length: the extent says nothing of the detail where
// the mesh is small parts far apart (QA round 57: two unit spheres 200 km apart, both around the origin
// at 100 km, in 1.6 cm float steps, 8 mm off the 1 mm mesh).
bool needs_doubles(const Mesh& mesh, const Mesh::Point& shift = {0, 0, 0}, double fraction = 1e-6, double edge_fraction = 0.0)
{
    double largest = 0.0;
    Mesh::Point lo(0, 0, 0), hi(0, 0, 0);
    bool first = true;
    for (const auto v : mesh.vertices()) {
        const Mesh::Point p = mesh.point(v) + shift;
        for (int a = 0; a < 3; ++a) {
            largest = std::max(largest, std::abs(p[a]));
            lo[a] = first ? p[a] : std::min(lo[a], p[a]);
            hi[a] = first ? p[a] : std::max(hi[a], p[a]);
        }
        first = false;
    }
    const double extent = (hi - lo).norm();
    const double step = largest * std::ldexp(1.0, -24);
    // Beyond the largest float a coordinate is no float at all (1e39 was written as inf).
    return step > fraction * extent || (edge_fraction > 0.0 && step > edge_fraction * mean_edge_length(mesh)) ||
           largest > std::numeric_limits<float>::max();
}

// A thousandth of the mean edge: float steps finer than that move no vertex visibly.
constexpr double kDoubleEdgeFraction = 1e-3;

// Little-endian bytes of a value, whatever the host.
template <typename T>
void put_le(std::string& out, T value)
{
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    const std::uint16_t one = 1;
    unsigned char low = 0;
    std::memcpy(&low, &one, 1);
    if (low != 1)
        std::reverse(bytes, bytes + sizeof(T));
    out.append(reinterpret_cast<const char*>(bytes), sizeof(T));
}

std::string format_number(double value, int digits)
{
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
    return buffer;
}

// The double-precision writers (PLY, OBJ, OFF) for meshes far from the origin; the layout is the one
// OpenMesh writes for near meshes, with double x y z.
std::string double_precision_file(const Mesh& m, MeshFormat format, bool binary, bool normals, bool colors)
{
    std::string out;
    // Text lines: "x y z [nx ny nz] [r g b a]" (PLY ascii and OFF alike) and "3 i j k".
    const auto vertex_line = [&](Mesh::VertexHandle v) {
        const Mesh::Point& p = m.point(v);
        std::string line = format_number(p[0], 17) + " " + format_number(p[1], 17) + " " + format_number(p[2], 17);
        if (normals) {
            const Mesh::Normal& n = m.normal(v);
            line += " " + format_number(n[0], 9) + " " + format_number(n[1], 9) + " " + format_number(n[2], 9);
        }
        if (colors) {
            const Mesh::Color& c = m.color(v);
            for (int k = 0; k < 4; ++k)
                line += " " + std::to_string(static_cast<int>(c[k]));
        }
        return line + "\n";
    };
    const auto face_line = [&](Mesh::FaceHandle f) {
        std::string line = "3";
        for (const auto v : m.fv_range(f))
            line += " " + std::to_string(v.idx());
        return line + "\n";
    };
    if (format == MeshFormat::ply) {
        out = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") + " 1.0\n";
        out += "element vertex " + std::to_string(m.n_vertices()) + "\n";
        out += "property double x\nproperty double y\nproperty double z\n";
        if (normals)
            out += "property float nx\nproperty float ny\nproperty float nz\n";
        if (colors)
            out += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
        out += "element face " + std::to_string(m.n_faces()) + "\nproperty list uchar int vertex_indices\nend_header\n";
        for (const auto v : m.vertices()) {
            if (!binary) {
                out += vertex_line(v);
                continue;
            }
            for (int a = 0; a < 3; ++a)
                put_le(out, m.point(v)[a]);
            if (normals)
                for (int a = 0; a < 3; ++a)
                    put_le(out, static_cast<float>(m.normal(v)[a]));
            if (colors)
                for (int k = 0; k < 4; ++k)
                    put_le(out, m.color(v)[k]);
        }
        for (const auto f : m.faces()) {
            if (!binary) {
                out += face_line(f);
                continue;
            }
            put_le(out, static_cast<std::uint8_t>(3));
            for (const auto v : m.fv_range(f))
                put_le(out, static_cast<std::int32_t>(v.idx()));
        }
    } else if (format == MeshFormat::obj) {
        // OBJ has no vertex colours (OpenMesh's writer refuses them too).
        for (const auto v : m.vertices()) {
            const Mesh::Point& p = m.point(v);
            out += "v " + format_number(p[0], 17) + " " + format_number(p[1], 17) + " " + format_number(p[2], 17) + "\n";
        }
        if (normals)
            for (const auto v : m.vertices()) {
                const Mesh::Normal& n = m.normal(v);
                out += "vn " + format_number(n[0], 9) + " " + format_number(n[1], 9) + " " + format_number(n[2], 9) + "\n";
            }
        for (const auto f : m.faces()) {
            out += "f";
            for (const auto v : m.fv_range(f)) {
                const std::string i = std::to_string(v.idx() + 1);
                out += " " + i + (normals ? "//" + i : "");
            }
            out += "\n";
        }
    } else { // OFF: [C][N]OFF, vertex lines x y z [nx ny nz] [r g b a]
        out = std::string(colors ? "C" : "") + (normals ? "N" : "") + "OFF\n";
        out += std::to_string(m.n_vertices()) + " " + std::to_string(m.n_faces()) + " 0\n";
        for (const auto v : m.vertices())
            out += vertex_line(v);
        for (const auto f : m.faces())
            out += face_line(f);
    }
    return out;
}

} // namespace

bool stl_is_relative(const Mesh& mesh, const Vec3& origin)
{
    // A looser bound than for doubles in the text formats: STL readers expect absolute coordinates, so
    // only where float steps would reach a ten-thousandth of the extent (edges a few dozen steps long).
    return needs_doubles(mesh, Mesh::Point(origin.x, origin.y, origin.z), 1e-4);
}

void write_mesh(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path,
                const WriteMeshOptions& options)
{
    if (!is_finite(origin))
        throw InvalidInput(path.string() + ": the origin is not finite (every vertex would be)");
    std::string ext;
    const MeshFormat format = mesh_format(path, ext);
    // As the glTF and Draco writers do (mesh_buffers.cpp): a NaN or infinite vertex was written as
    // "nan" / "inf" text or bits, a file that viewers reject or show with a spike.
    if (const Mesh::VertexHandle v = first_non_finite_vertex(mesh); v.is_valid())
        throw InvalidInput(path.string() + ": mesh vertex " + std::to_string(v.idx()) + " has a non-finite position");

    Mesh out(mesh);
    out.garbage_collection();
    // As the glTF and Draco writers refuse one (QA round 59: a PLY/OBJ/OFF of no faces was written where
    // write_gltf said "no faces to write"); no stage of this library returns such a mesh.
    if (out.n_faces() == 0)
        throw InvalidInput(path.string() + ": the mesh has no faces to write");
    // Normals come from positions relative to the origin, where the cross products are accurate. A mesh
    // whose normals the caller released (release_vertex_normals) has them requested on the copy and
    // computed, whatever recompute_normals says: OpenMesh read a property that no longer existed (an
    // assertion in a debug build, out of bounds in a release one).
    if (options.normals) {
        const bool stored = mesh.has_vertex_normals();
        out.request_face_normals();
        out.request_vertex_normals();
        if (options.recompute_normals || !stored) {
            out.update_face_normals();
            out.update_vertex_normals();
        }
    }
    // STL has only floats: far from the origin it keeps the positions relative to it (stl_is_relative).
    const bool relative = format == MeshFormat::stl && stl_is_relative(mesh, origin);
    const Mesh::Point shift(origin.x, origin.y, origin.z);
    if (!relative)
        for (const auto v : out.vertices())
            out.set_point(v, out.point(v) + shift);
    // Finite vertices and origin can still sum to infinity (1e308 + 1e308), and STL's floats end at
    // 3.4e38: such a vertex was written as "inf" or infinite bits.
    const double largest = format == MeshFormat::stl ? std::numeric_limits<float>::max() : std::numeric_limits<double>::max();
    for (const auto v : out.vertices()) {
        const Mesh::Point p = out.point(v);
        if (!(std::abs(p[0]) <= largest && std::abs(p[1]) <= largest && std::abs(p[2]) <= largest)) {
            char where[96];
            std::snprintf(where, sizeof where, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
            throw InvalidInput(path.string() + ": mesh vertex " + std::to_string(v.idx()) + " lies at " + where +
                               (relative ? " from the origin" : "") + ", beyond the largest " +
                               (format == MeshFormat::stl ? "32-bit float STL can store (3.4e38)" : "double (1.8e308)"));
        }
    }

    const bool colors = options.colors && out.has_vertex_colors() && format != MeshFormat::obj;
    if ((format == MeshFormat::ply || format == MeshFormat::obj || format == MeshFormat::off) &&
        needs_doubles(out, {0, 0, 0}, 1e-6, kDoubleEdgeFraction)) {
        AtomicFile file(path);
        const std::string bytes = double_precision_file(out, format, options.binary, options.normals, colors);
        file.write(bytes.data(), bytes.size());
        file.commit();
        return;
    }
    const OpenMesh::IO::Options io = io_options(format, out, options);
    AtomicFile file(path);
    bool ok = false;
    {
        const QuietOpenMesh muted;
        // 9 significant digits round-trip the float coordinates of the text formats.
        ok = OpenMesh::IO::write_mesh(out, file.stream(), ext, io, 9);
    }
    if (!ok)
        throw IoError(path.string() + ": OpenMesh could not write the " + ext + " file");
    file.commit();
}

} // namespace mrt
