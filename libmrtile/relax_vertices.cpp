// Beyond the paper, between the surface (§4.3) and the vertex fit: tile hull points bunch up along the
// rims and leave wide faces between; evening them out within the surface gives the least-squares fit
// better-spread vertices to place, which lowers the distance to the points on curved surfaces without
// touching sharp edges (their vertices are left where the tiles put them).
#include "libmrtile/relax_vertices.h"

#include "libmrtile/errors.h"

#include <array>
#include <cmath>
#include <vector>

namespace mrt {
namespace {

// Twice the area vector of face f (its unnormalized normal) with vertex `moved` at `at` instead of
// where it is.
Vec3 area_vector(const Mesh& mesh, Mesh::FaceHandle f, Mesh::VertexHandle moved, const Vec3& at)
{
    std::array<Vec3, 3> p;
    std::size_t k = 0;
    for (const auto v : mesh.fv_range(f))
        p[k++] = v == moved ? at : to_vec3(mesh.point(v));
    return cross(p[1] - p[0], p[2] - p[0]);
}

} // namespace

void check_relax_options(const RelaxOptions& options)
{
    if (options.iterations < 0 || options.iterations > kMaxRelaxIterations || !(options.step > 0.0 && options.step <= 1.0) ||
        !(options.crease_degrees >= 0.0 && options.crease_degrees <= 180.0) ||
        !(options.max_turn_degrees > 0.0 && options.max_turn_degrees <= 180.0) ||
        (options.vertical && !(squared_norm(options.axis) > 0.0)))
        throw InvalidInput("relax_vertices: iterations must be in [0, " + std::to_string(kMaxRelaxIterations) +
                           "], step in (0, 1], crease_degrees in [0, 180], max_turn_degrees in (0, 180], and a vertical "
                           "relaxation needs a non-zero axis");
}

RelaxStats relax_vertices(Mesh& mesh, const RelaxOptions& options)
{
    check_relax_options(options);
    RelaxStats stats;
    const double crease_cos = std::cos(radians(options.crease_degrees));
    const double turn_cos = std::cos(radians(options.max_turn_degrees));
    const Vec3 up = options.vertical ? normalized(options.axis) : Vec3{};
    std::vector<Vec3> before;
    for (int sweep = 0; sweep < options.iterations; ++sweep) {
        stats.creases = 0;
        for (const auto v : mesh.vertices()) {
            if ((mesh.has_vertex_status() && mesh.status(v).deleted()) || mesh.is_boundary(v) || mesh.is_isolated(v))
                continue;
            const Vec3 x = to_vec3(mesh.point(v));
            // Area-weighted normal and the faces' own normals, as they are now.
            Vec3 area_normal{};
            before.clear();
            for (const auto f : mesh.vf_range(v)) {
                const Vec3 n = area_vector(mesh, f, v, x);
                area_normal += n;
                before.push_back(normalized(n));
            }
            if (!(squared_norm(area_normal) > 0.0))
                continue;
            const Vec3 normal = normalized(area_normal);
            bool crease = false;
            for (const Vec3& n : before)
                crease = crease || dot(n, normal) < crease_cos;
            if (crease) {
                ++stats.creases;
                continue;
            }
            Vec3 centroid{};
            int count = 0;
            for (const auto w : mesh.vv_range(v)) {
                centroid += to_vec3(mesh.point(w));
                ++count;
            }
            Vec3 d = centroid / static_cast<double>(count) - x;
            d -= normal * dot(d, normal);
            const Vec3 target = x + d * options.step;
            bool ok = true;
            std::size_t k = 0;
            for (const auto f : mesh.vf_range(v)) {
                const Vec3 n = normalized(area_vector(mesh, f, v, target));
                ok = ok && squared_norm(n) > 0.0 && dot(n, before[k]) >= turn_cos && (!options.vertical || dot(n, up) > 0.0);
                ++k;
            }
            if (!ok) {
                ++stats.refused;
                continue;
            }
            mesh.set_point(v, Mesh::Point(target.x, target.y, target.z));
            ++stats.moves;
        }
    }
    mesh.update_normals();
    return stats;
}

} // namespace mrt
