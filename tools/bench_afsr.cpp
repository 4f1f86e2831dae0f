// The peers of our reconstruction in tools/bench (table "mesh"): CGAL's Advancing Front Surface
// Reconstruction, a Delaunay-based interpolating mesher that keeps every input point as a vertex, and
// meshoptimizer's edge-collapse simplifier, which brings that mesh down to our face count so the two
// are compared at equal size. This file is the only one that includes CGAL or meshoptimizer in tools/.
#include "tools/bench_afsr.h"

#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <meshoptimizer.h>

#include <iterator>

namespace mrt::bench {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

Mesh::Point point(const Vec3& p) { return Mesh::Point(p.x, p.y, p.z); }

} // namespace

TriangleSoup afsr_reconstruct(const std::vector<Vec3>& points)
{
    std::vector<Kernel::Point_3> cgal_points;
    cgal_points.reserve(points.size());
    for (const Vec3& p : points)
        cgal_points.emplace_back(p.x, p.y, p.z);
    std::vector<std::array<std::size_t, 3>> facets;
    CGAL::advancing_front_surface_reconstruction(cgal_points.begin(), cgal_points.end(), std::back_inserter(facets));

    TriangleSoup soup;
    soup.positions = points;
    soup.triangles.reserve(facets.size());
    for (const auto& f : facets)
        soup.triangles.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]),
                                  static_cast<std::uint32_t>(f[2])});
    return soup;
}

TriangleSoup meshopt_simplify_to(const TriangleSoup& soup, std::size_t target_faces)
{
    std::vector<float> positions;
    positions.reserve(soup.positions.size() * 3);
    for (const Vec3& p : soup.positions)
    {
        positions.push_back(static_cast<float>(p.x));
        positions.push_back(static_cast<float>(p.y));
        positions.push_back(static_cast<float>(p.z));
    }
    std::vector<unsigned int> indices;
    indices.reserve(soup.triangles.size() * 3);
    for (const auto& t : soup.triangles)
        indices.insert(indices.end(), t.begin(), t.end());

    std::vector<unsigned int> simplified(indices.size());
    // target_error 1 = the whole mesh extent: no error limit, only the face count stops the collapses.
    const std::size_t kept = meshopt_simplify(simplified.data(), indices.data(), indices.size(), positions.data(),
                                              soup.positions.size(), 3 * sizeof(float), target_faces * 3, 1.0f,
                                              0, nullptr);
    TriangleSoup out;
    out.positions = soup.positions;
    out.triangles.reserve(kept / 3);
    for (std::size_t i = 0; i + 2 < kept; i += 3)
        out.triangles.push_back({simplified[i], simplified[i + 1], simplified[i + 2]});
    return out;
}

Mesh unshared_mesh(const TriangleSoup& soup)
{
    Mesh mesh;
    mesh.reserve(soup.triangles.size() * 3, soup.triangles.size() * 3, soup.triangles.size());
    for (const auto& t : soup.triangles)
    {
        const Mesh::VertexHandle a = mesh.add_vertex(point(soup.positions[t[0]]));
        const Mesh::VertexHandle b = mesh.add_vertex(point(soup.positions[t[1]]));
        const Mesh::VertexHandle c = mesh.add_vertex(point(soup.positions[t[2]]));
        mesh.add_face(a, b, c);
    }
    return mesh;
}

} // namespace mrt::bench
