// A user's first program against the installed libmrtile: a generated sphere, its exact moments and
// principal axes, a round trip through the point reader and a mesh written by the mesh writer. Exits
// non-zero (with the reason on stderr) if an answer is wrong, so the install test checks behaviour,
// not only linking.
#include "formats/read_points.h"
#include "formats/write_mesh.h"
#include "libmrtile/errors.h"
#include "libmrtile/pca.h"
#include "libmrtile/shapes.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace {

int failures = 0;

void check(bool ok, const char* what)
{
    if (!ok) {
        std::fprintf(stderr, "consumer: FAILED: %s\n", what);
        ++failures;
    }
}

} // namespace

int main()
{
    const double radius = 2.0;
    const mrt::PointCloud cloud = mrt::shapes::sphere(5000, radius, 11);
    const mrt::Moments m = mrt::compute_moments(cloud.positions.data(), cloud.size());
    const mrt::Eigen3x3 e = mrt::eigen_decomposition(m);
    std::printf("consumer: %llu points, mean (%.4f %.4f %.4f), eigenvalues/n %.4f %.4f %.4f\n",
                static_cast<unsigned long long>(m.count), m.mean.x, m.mean.y, m.mean.z, e.values[0] / m.count,
                e.values[1] / m.count, e.values[2] / m.count);
    check(m.count == 5000, "moment count");
    check(mrt::norm(m.mean) < 0.1, "mean of a sphere sample is near its centre");
    // Points on a sphere: mean squared distance to the centre is r^2, a third along each axis.
    check(std::abs(m.sum_squared_distances() / m.count + mrt::squared_norm(m.mean) - radius * radius) < 1e-9,
          "sum of squared distances equals r^2 per point");
    for (double v : e.values)
        check(std::abs(v / m.count - radius * radius / 3) < 0.15, "eigenvalues near r^2/3");

    // The formats library: write the cloud as text, read it back.
    const std::filesystem::path xyz = "sphere.xyz";
    {
        std::ofstream out(xyz);
        char line[128];
        for (const mrt::Vec3& p : cloud.positions) {
            const mrt::Vec3 a = cloud.origin + p;
            std::snprintf(line, sizeof line, "%.17g %.17g %.17g\n", a.x, a.y, a.z);
            out << line;
        }
    }
    const mrt::PointCloud back = mrt::read_points(xyz);
    check(back.size() == cloud.size(), "read_points count");
    check(back.origin + back.positions[0] == cloud.origin + cloud.positions[0], "read_points exact first point");
    bool threw = false;
    try {
        mrt::read_points("missing.ply");
    } catch (const mrt::IoError&) {
        threw = true;
    }
    check(threw, "read_points throws IoError for a missing file");

    mrt::Mesh tetra;
    const mrt::Mesh::VertexHandle v[4] = {tetra.add_vertex({0, 0, 0}), tetra.add_vertex({1, 0, 0}),
                                          tetra.add_vertex({0, 1, 0}), tetra.add_vertex({0, 0, 1})};
    check(tetra.add_face(v[0], v[2], v[1]).is_valid() && tetra.add_face(v[0], v[1], v[3]).is_valid() &&
              tetra.add_face(v[0], v[3], v[2]).is_valid() && tetra.add_face(v[1], v[2], v[3]).is_valid(),
          "tetrahedron faces");
    mrt::write_mesh(tetra, mrt::Vec3{10, 20, 30}, "tetra.ply");
    check(std::filesystem::file_size("tetra.ply") > 0, "write_mesh wrote tetra.ply");

    std::printf("consumer: %s\n", failures == 0 ? "all checks passed" : "FAILED");
    return failures == 0 ? 0 : 1;
}
