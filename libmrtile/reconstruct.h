#pragma once
//! \file reconstruct.h
//! \brief The one-call pipeline from a cut to a measured mesh: tiles (§4.2), surface (§4.3), quality.
//! \details
//! \code
//!   Hierarchy h = build_hierarchy(read_points("scan.ply"));          // §4.1, once
//!   Cut cut = cut_by_tolerance(h, 0.002);                             // any cut (cut.h)
//!   MeshResult r = mesh_cut(h, cut);                                  // §4.2-4.3 → OpenMesh
//!   QualityReport q = measure_quality(h, cut, r.mesh);                // numbers users can trust
//! \endcode

#include "libmrtile/cut.h"
#include "libmrtile/mesh.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/surface.h"
#include "libmrtile/tiles.h"

namespace mrt {

struct MeshOptions
{
    TileOptions tiles;       //!< tile generation (§4.2)
    SurfaceOptions surface;  //!< gap triangulation and manifold assembly (§4.3)
};

struct MeshResult
{
    Mesh mesh;
    SurfaceStats surface;
    std::size_t tiles = 0;
    double seconds = 0.0; //!< tiles + surface
};

//! Tiles the cut and meshes it. \throw InvalidInput if the cut is not a partition of the points.
MeshResult mesh_cut(const Hierarchy& h, const Cut& cut, const MeshOptions& options = {});

struct QualityReport
{
    TopologyStats topology;
    //! Paper eq. 4-6: mean distance of each point to the plane of its tile, divided by the object
    //! diameter (the bounding box's largest side, as the paper's 0.1557 for the bunny is).
    double e_rms = 0.0;
    //! Distances from every input point to the mesh, as fractions of the bounding-box diagonal.
    DistanceStats point_to_mesh;
};

QualityReport measure_quality(const Hierarchy& h, const Cut& cut, const Mesh& mesh);

//! Paper eq. 4-6 for a cut (see QualityReport::e_rms).
double e_rms(const Hierarchy& h, const Cut& cut);

} // namespace mrt
