#pragma once
// Reads the vertices and triangles of a plain OBJ file (what the CLI writes, the shared CAD parts), for
// tests that look at a mesh file without OpenMesh: "v x y z" and "f a b c" lines ("a/t/n" corners
// too); other lines are skipped. Also uniform samples of solids given by their triangles (an OBJ's CAD
// part, the regular tetrahedron) for tests of their reconstruction.
#include "libmrtile/shapes.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace mrt::testing {

struct ObjTriangles
{
    std::vector<Vec3> vertices;
    std::vector<std::array<std::size_t, 3>> faces; // 0-based vertex indices
};

inline ObjTriangles read_obj_triangles(const std::filesystem::path& path)
{
    ObjTriangles obj;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string key;
        s >> key;
        if (key == "v") {
            Vec3 p;
            s >> p.x >> p.y >> p.z;
            obj.vertices.push_back(p);
        } else if (key == "f") {
            std::array<std::size_t, 3> f{};
            for (std::size_t& i : f) {
                std::string corner;
                s >> corner;
                i = std::stoul(corner.substr(0, corner.find('/'))) - 1;
            }
            obj.faces.push_back(f);
        }
    }
    return obj;
}

//! A uniform sample of `count` points (seeded) over the triangles of an OBJ file: what a scanner would
//! give of the CAD part it describes (shapes::mesh_surface).
inline PointCloud sampled_obj_surface(const std::filesystem::path& path, std::size_t count, std::uint32_t seed)
{
    const ObjTriangles obj = read_obj_triangles(path);
    std::vector<std::array<std::uint32_t, 3>> triangles;
    for (const auto& f : obj.faces)
        triangles.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]), static_cast<std::uint32_t>(f[2])});
    return shapes::mesh_surface(obj.vertices, triangles, count, seed);
}

//! A uniform sample of `count` points (seeded) over the regular tetrahedron with corners (1, 1, 1),
//! (1, -1, -1), (-1, 1, -1), (-1, -1, 1): its 71-degree edges crack and fold at coarse cuts.
inline PointCloud sampled_tetrahedron(std::size_t count, std::uint32_t seed)
{
    const std::vector<Vec3> corners{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    const std::vector<std::array<std::uint32_t, 3>> sides{{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    return shapes::mesh_surface(corners, sides, count, seed);
}

//! A closed shell whose wall is 3 point spacings thick: `count` points uniform over two concentric
//! spheres (radius 1 and 1 - 3 spacings, the spacing of the count over both), seeds `seed` and seed + 100.
inline PointCloud sphere_shell(std::size_t count, std::uint32_t seed)
{
    const double spacing = std::sqrt(4.0 * kPi * (1.0 + 0.95 * 0.95) / static_cast<double>(count));
    const double inner = 1.0 - 3.0 * spacing;
    const auto outer_count = static_cast<std::size_t>(static_cast<double>(count) / (1.0 + inner * inner));
    PointCloud shell = shapes::sphere(outer_count, 1.0, seed);
    const PointCloud inside = shapes::sphere(count - outer_count, inner, seed + 100);
    for (const Vec3& p : inside.positions)
        shell.positions.push_back(p + inside.origin - shell.origin);
    return shell;
}

} // namespace mrt::testing
