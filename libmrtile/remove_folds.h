#pragma once
//! \file remove_folds.h
//! \brief Beyond the paper: folds (two faces turned back onto each other across their edge) removed by
//! edge flips and small moves of spike tips, after the vertex fit, so that a sharp edge of the sample
//! shows as an edge and not as a row of spikes.
//! \details Where two tiles meet at a sharp edge of the surface (a box's or a CAD part's crease), the
//! gap triangles between their rims, and the fit's moves of those rims, can leave a face that turns
//! back over its neighbour: the two faces' normals more than `fold_angle_degrees` apart, a flap or a
//! spike that stands out of the edge in any viewer (QA round 72, the shared fandisk part and the demo's
//! plate). Often the other diagonal of their quad is the right one: this pass flips an edge
//! where the flip lowers the largest fold among the quad's five edges and leaves none above the
//! limit; where no flip helps, a spike's tip (a vertex whose faces' angles sum to under 1.25 pi) moves
//! the least of 1/8 to all of the way to the middle of its neighbours that clears its folds, at most
//! as far as it stands from the sample and never farther from it. A flip keeps the mesh an oriented 2-manifold with the same vertices,
//! boundary loops and genus (OpenMesh's is_flip_ok), no change makes a face without area or a cap that
//! was not there, border vertices stay, faces of `keep_pairs` (crossing faces the untangling repairs
//! next) are left alone, and a change whose faces cross another face is undone: the pass adds no
//! self-intersection.
//! \code
//!   Mesh m = mesh_cut(h, cut).mesh;        // mesh_cut runs it after the fit (MeshOptions::folds)
//!   FoldOptions o;
//!   o.fold_angle_degrees = 120;            // also flatter folds
//!   FoldStats s = remove_folds(m, o);
//! \endcode

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <cstddef>
#include <utility>
#include <vector>

namespace mrt {

struct Hierarchy;

struct FoldOptions
{
    //! An interior edge whose two faces' normals lie more than this apart (degrees) is a fold: at 150,
    //! the faces meet at 30 degrees or less, a spike or a flap, never a real edge of a scanned solid the
    //! surface can follow (its tiles cannot follow an edge that acute; Known limits). 180 = off.
    double fold_angle_degrees = 150.0;
    //! A flip may not make a face with an angle above this (degrees) unless the two old faces had one
    //! as large (as FitOptions::max_flip_angle_degrees: no new caps).
    double max_face_angle_degrees = 150.0;
    //! Keep a height field a graph over the plane normal to `axis`: both new faces must face up it
    //! (mesh_cut sets both in height-field mode, as for the fit).
    bool vertical = false;
    Vec3 axis{0, 0, 1};
    //! Passes over the mesh (a pass flips what it finds, each face at most once; the work ends earlier
    //! when a pass changes nothing).
    int passes = 4;
};

struct FoldStats
{
    std::size_t folds_before = 0; //!< interior edges folded beyond the limit before the first pass
    std::size_t flips = 0;        //!< flips kept
    std::size_t moves = 0;        //!< vertices moved to the middle of their neighbours, kept
    std::size_t undone = 0;       //!< flips and moves undone because a changed face crossed another face
    std::size_t folds_after = 0;  //!< folds left
};

//! \throw InvalidInput if an option is out of range (angles in (0, 180], passes in [0, 64], a vertical
//! pass without a non-zero axis).
void check_fold_options(const FoldOptions& options);

//! \brief Flips folded edges away and moves spike tips in (see the file comment). Deterministic;
//! updates the normals. Faces of `keep_pairs` (pairs of face indices) are left as they are. With a
//! `sample` (the hierarchy whose points the mesh stands for, in the mesh's coordinates), a tip never
//! moves farther from its nearest point: a vertex on a real corner keeps its place. On a mesh with tile
//! ids (mesh.h) a flipped face keeps its tile only if both faces had the same one, and becomes a gap
//! face otherwise. \throw InvalidInput as check_fold_options.
FoldStats remove_folds(Mesh& mesh, const FoldOptions& options = {}, const std::vector<std::pair<int, int>>* keep_pairs = nullptr,
                       const Hierarchy* sample = nullptr);

} // namespace mrt
