#pragma once
//! \file write_mesh.h
//! \brief Writes a mesh in a classic mesh format, chosen by extension, through OpenMesh's IO.
//! \details Formats and what they hold:
//!  - .ply: binary little-endian (default) or ascii; float positions, vertex normals, RGBA vertex colours.
//!  - .obj: ascii; float positions, vertex normals.
//!  - .off: ascii (NOFF/CNOFF); float positions, vertex normals, RGBA vertex colours.
//!  - .stl: binary; float positions, per-facet normals computed from the triangle.
//!  - .om:  OpenMesh's binary format; **double** positions, vertex normals, vertex colours.
//! Positions are written as origin + position. OpenMesh 9 hands single-precision points to its
//! PLY/OBJ/OFF/STL writers (about 7 significant digits: ~0.5 m at 5·10⁶), so a mesh far from the
//! origin (where float would lose more than a millionth of its extent, as georeferenced meshes are) is
//! written with double coordinates by our own PLY, OBJ and OFF writers; .stl stays float (the format
//! has nothing else), .om is always double.

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <filesystem>

namespace mrt {

struct WriteMeshOptions
{
    //! .ply only: binary little-endian (true) or ascii (false).
    bool binary = true;
    //! Write per-vertex normals where the format has them (.ply, .obj, .off, .om).
    bool normals = true;
    //! With `normals`: compute area-weighted vertex normals from the faces (on a copy) before writing.
    //! Set to false only if the mesh's vertex normals were set: OpenMesh leaves them uninitialised.
    bool recompute_normals = true;
    //! Write RGBA vertex colours when the mesh has them (.ply, .off, .om).
    bool colors = true;
};

//! Whether write_mesh writes an STL file of `mesh` relative to `origin` rather than in absolute
//! coordinates: where float steps there exceed a ten-thousandth of the mesh's extent.
bool stl_is_relative(const Mesh& mesh, const Vec3& origin);

//! \brief Writes `mesh` (positions relative to `origin`) to `path`; the format follows the extension
//! (.ply, .obj, .off, .stl, .om; case-insensitive).
//! \details PLY, OBJ and OFF far from the origin (where float would lose more than a millionth of the
//! mesh's extent, as georeferenced meshes do) are written with double coordinates; STL, which has only
//! floats, is written relative to `origin` where float steps would exceed a ten-thousandth of the extent
//! (stl_is_relative; a bunny moved to UTM-sized
//! coordinates had lost 1,244 of its 5,741 positions and got 194 degenerate triangles). Atomic: the file is written next to the target under a temporary name and renamed, so a
//! failure leaves no partial file. Deleted elements are not written. Deterministic: the same mesh and
//! options give byte-identical files.
//! \throw InvalidInput for an unknown extension, a non-finite origin or vertex, a mesh without faces (as
//! write_gltf); IoError naming `path` if it cannot be written.
void write_mesh(const Mesh& mesh, const Vec3& origin, const std::filesystem::path& path,
                const WriteMeshOptions& options = {});

} // namespace mrt
