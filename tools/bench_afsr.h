#pragma once
// The peer methods tools/bench compares our meshes with: CGAL's Advancing Front Surface Reconstruction
// (interpolates every input point) and meshoptimizer's simplifier (brings its mesh down to our size).
// CGAL and meshoptimizer are included only by bench_afsr.cpp.

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mrt::bench {

struct TriangleSoup
{
    std::vector<Vec3> positions;                         // may hold vertices no triangle uses
    std::vector<std::array<std::uint32_t, 3>> triangles; // indices into positions
};

// CGAL::advancing_front_surface_reconstruction with its default parameters (radius ratio bound 5,
// β = 0.52): the facets refer to the input points, which become the positions.
TriangleSoup afsr_reconstruct(const std::vector<Vec3>& points);

// meshopt_simplify (no error limit, borders may slide along themselves) aiming at `target_faces`;
// the result may keep more faces where the simplifier cannot collapse further. Unused vertices stay.
TriangleSoup meshopt_simplify_to(const TriangleSoup& soup, std::size_t target_faces);

// Every triangle with its own three vertices: OpenMesh never refuses such faces, so the distance to
// any soup (non-manifold ones included) can be measured with point_to_mesh_distance().
Mesh unshared_mesh(const TriangleSoup& soup);

} // namespace mrt::bench
