// Tests of node_face_index.h: the closest point of a mesh_cut mesh found down the hierarchy against a
// brute-force search over every face, and the border flag on a sphere with a hole (analytic).
#include "libmrtile/node_face_index.h"

#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace mrt {
namespace {

double brute_force_distance(const Mesh& mesh, const Vec3& q)
{
    double best = std::numeric_limits<double>::infinity();
    for (const auto f : mesh.faces()) {
        std::array<Vec3, 3> c;
        std::size_t n = 0;
        for (const auto v : mesh.fv_range(f))
            c[n++] = to_vec3(mesh.point(v));
        best = std::min(best, point_triangle_distance(q, c[0], c[1], c[2]));
    }
    return best;
}

// A unit sphere whose cap above z = 0.8 is not sampled: an open surface with one border loop there.
TEST(NodeFaceIndex, closest_points_equal_brute_force_and_the_border_is_told)
{
    PointCloud c = shapes::sphere(12000);
    c.positions.erase(std::remove_if(c.positions.begin(), c.positions.end(), [](const Vec3& p) { return p.z > 0.8; }),
                      c.positions.end());
    const Hierarchy h = build_hierarchy(c);
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.005));
    ASSERT_GT(r.mesh.n_faces(), 100u);
    const NodeFaceIndex index(h, r.mesh);
    std::mt19937 rng(65);
    std::uniform_real_distribution<double> u(-1.6, 1.6);
    for (int k = 0; k < 300; ++k) {
        const Vec3 q = Vec3{u(rng), u(rng), u(rng)} - h.cloud.origin;
        EXPECT_EQ(index.closest(q).distance, brute_force_distance(r.mesh, q)) << k;
    }
    // Over the hole, the closest point is on its rim: a border, and no offset off the surface.
    for (const double z : {0.9, 1.2, 2.0}) {
        const Vec3 q = Vec3{0.0, 0.0, z} - h.cloud.origin;
        const NodeFaceIndex::Closest found = index.closest(q);
        EXPECT_TRUE(found.on_border) << z;
        EXPECT_GT(found.distance, 0.5) << z;
        EXPECT_EQ(index.off_surface(q), 0.0) << z;
    }
    // Off the sampled part, along the normal: inside the surface, and the offset is the distance.
    std::normal_distribution<double> g(0.0, 1.0);
    for (int k = 0; k < 50; ++k) {
        Vec3 d{g(rng), g(rng), -std::abs(g(rng))};
        d = normalized(d);
        const Vec3 q = d * 1.2 - h.cloud.origin;
        const NodeFaceIndex::Closest found = index.closest(q);
        EXPECT_FALSE(found.on_border) << k;
        EXPECT_NEAR(found.distance, 0.2, 0.02) << k;
        EXPECT_EQ(index.off_surface(q), found.distance) << k;
    }
}

TEST(NodeFaceIndex, a_mesh_without_the_cut_properties_is_refused)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(2000));
    Mesh bare;
    const auto a = bare.add_vertex({0, 0, 0}), b = bare.add_vertex({1, 0, 0}), c = bare.add_vertex({0, 1, 0});
    ASSERT_TRUE(bare.add_face(a, b, c).is_valid());
    EXPECT_THROW(NodeFaceIndex(h, bare), InvalidInput);
}

} // namespace
} // namespace mrt
