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

} // namespace

void write_mesh(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path,
                const WriteMeshOptions& options)
{
    std::string ext;
    const MeshFormat format = mesh_format(path, ext);

    Mesh out(mesh);
    out.garbage_collection();
    // Normals come from positions relative to the origin, where the cross products are accurate.
    if (options.normals && options.recompute_normals) {
        out.update_face_normals();
        out.update_vertex_normals();
    }
    const Mesh::Point shift(origin.x, origin.y, origin.z);
    for (const auto v : out.vertices())
        out.set_point(v, out.point(v) + shift);

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
