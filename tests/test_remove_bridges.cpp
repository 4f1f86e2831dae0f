// Tubes across empty space cut (remove_bridges.h): two tetrahedra facing each other across a gap,
// joined by a hand-made tube of six gap faces, come apart into two closed tetrahedra; the same tube
// over sampled surface (a prism the points cover) stays; and two linked rings 5 point spacings apart,
// which the gap triangulation joined by such a tube in some seeds (QA round 80), mesh as two rings.

#include "libmrtile/remove_bridges.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"
#include "mesh_fixtures.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <unordered_map>
#include <vector>

namespace mrt {
namespace {

constexpr double kSpacing = 0.05; // of the tetrahedra's sample

// Corners of tetrahedron A (its face 0-1-2 in the plane z = 0, its apex below) and B (the mirror image
// above z = `gap`, its face 0-1-2 facing A's).
std::array<Vec3, 4> corners(bool upper, double gap)
{
    const double h = std::sqrt(2.0 / 3.0);
    if (!upper)
        return {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0.5, std::sqrt(0.75), 0}, Vec3{0.5, std::sqrt(0.75) / 3, -h}};
    return {Vec3{0, 0, gap}, Vec3{1, 0, gap}, Vec3{0.5, std::sqrt(0.75), gap}, Vec3{0.5, std::sqrt(0.75) / 3, gap + h}};
}

// Random points about kSpacing apart on the triangle a, b, c.
void sample_triangle(const Vec3& a, const Vec3& b, const Vec3& c, std::mt19937& rng, std::vector<Vec3>& out)
{
    const double area = 0.5 * norm(cross(b - a, c - a));
    const auto count = static_cast<std::size_t>(area / (kSpacing * kSpacing));
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (std::size_t i = 0; i < count; ++i) {
        double u = unit(rng), v = unit(rng);
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        out.push_back(a + (b - a) * u + (c - a) * v);
    }
}

// The two tetrahedra without their facing faces, joined by a tube of six gap faces from A's open face
// to B's; every vertex of node 0. `sampled_tube`: the points cover the tube's faces too (a prism).
struct Bridged
{
    Mesh mesh;
    Hierarchy h;
};

Bridged bridged_tetrahedra(double gap, bool sampled_tube)
{
    Bridged out;
    const std::array<Vec3, 4> a = corners(false, gap), b = corners(true, gap);
    std::array<Mesh::VertexHandle, 4> va, vb;
    for (std::size_t k = 0; k < 4; ++k) {
        va[k] = out.mesh.add_vertex(to_point(a[k]));
        vb[k] = out.mesh.add_vertex(to_point(b[k]));
    }
    // Outward: A's sides seen from outside turn counter-clockwise, B's are their mirror images.
    using testing::add_checked_face;
    add_checked_face(out.mesh, va[0], va[3], va[1]);
    add_checked_face(out.mesh, va[1], va[3], va[2]);
    add_checked_face(out.mesh, va[2], va[3], va[0]);
    add_checked_face(out.mesh, vb[0], vb[1], vb[3]);
    add_checked_face(out.mesh, vb[1], vb[2], vb[3]);
    add_checked_face(out.mesh, vb[2], vb[0], vb[3]);
    testing::mark_as_one_tile(out.mesh, 0);
    OpenMesh::FPropHandleT<int> tile;
    OpenMesh::FPropHandleT<bool> is_gap;
    out.mesh.get_property_handle(tile, kFaceTile);
    out.mesh.get_property_handle(is_gap, kFaceGap);
    for (std::size_t k = 0; k < 3; ++k) {
        const std::size_t next = (k + 1) % 3;
        for (const auto& t : {std::array<Mesh::VertexHandle, 3>{va[k], va[next], vb[next]}, std::array<Mesh::VertexHandle, 3>{va[k], vb[next], vb[k]}}) {
            const Mesh::FaceHandle f = out.mesh.add_face(t[0], t[1], t[2]);
            if (!f.is_valid())
                throw std::logic_error("fixture: OpenMesh refused a tube face");
            out.mesh.property(tile, f) = -1;
            out.mesh.property(is_gap, f) = true;
        }
    }
    std::mt19937 rng(5);
    std::vector<Vec3> points;
    for (const auto& c : {a, b}) // every face of both, the facing ones too
        for (const auto& f : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 3, 1}, std::array<int, 3>{1, 3, 2}, std::array<int, 3>{2, 3, 0}})
            sample_triangle(c[f[0]], c[f[1]], c[f[2]], rng, points);
    if (sampled_tube)
        for (std::size_t k = 0; k < 3; ++k) {
            const std::size_t next = (k + 1) % 3;
            sample_triangle(a[k], a[next], b[next], rng, points);
            sample_triangle(a[k], b[next], b[k], rng, points);
        }
    PointCloud cloud;
    cloud.positions = points;
    out.h = build_hierarchy(cloud);
    // The mesh in the hierarchy's coordinates (relative to its origin), as meshes of mesh_cut are.
    for (const auto v : out.mesh.vertices())
        out.mesh.set_point(v, to_point(to_vec3(out.mesh.point(v)) - out.h.cloud.origin));
    return out;
}

const std::unordered_map<std::int32_t, double> kSpacingOf{{0, kSpacing}};

TEST(RemoveBridges, a_tube_across_empty_space_is_cut_and_both_ends_capped)
{
    Bridged b = bridged_tetrahedra(0.5, false); // the gap 10 spacings
    ASSERT_EQ(topology_stats(b.mesh).components, 1u);
    ASSERT_EQ(b.mesh.n_faces(), 12u);
    const BridgeStats stats = remove_bridges(b.mesh, b.h, kSpacingOf);
    EXPECT_EQ(stats.tubes, 1u);
    EXPECT_EQ(stats.removed, 6u);
    EXPECT_EQ(stats.caps, 2u);
    EXPECT_EQ(stats.long_faces, 6u); // the tube's faces, the only gap faces
    EXPECT_EQ(stats.judged, 6u);
    const TopologyStats t = topology_stats(b.mesh);
    EXPECT_EQ(t.components, 2u);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.genus, 0);
    EXPECT_EQ(t.nonmanifold_edges + t.nonmanifold_vertices, 0u);
    EXPECT_TRUE(t.consistently_oriented);
    EXPECT_EQ(b.mesh.n_faces(), 8u); // two closed tetrahedra
    // Each cap is a gap face on its tetrahedron's open face: all three corners at z = 0 or at the gap.
    OpenMesh::FPropHandleT<bool> is_gap;
    ASSERT_TRUE(b.mesh.get_property_handle(is_gap, kFaceGap));
    std::size_t caps = 0;
    for (const auto f : b.mesh.faces())
        if (b.mesh.property(is_gap, f)) {
            ++caps;
            const std::array<Vec3, 3> p = face_corners(b.mesh, f);
            const double z = p[0].z + b.h.cloud.origin.z;
            EXPECT_TRUE(std::abs(z) < 1e-12 || std::abs(z - 0.5) < 1e-12) << z;
            EXPECT_DOUBLE_EQ(p[1].z, p[0].z);
            EXPECT_DOUBLE_EQ(p[2].z, p[0].z);
        }
    EXPECT_EQ(caps, 2u);
}

TEST(RemoveBridges, a_tube_over_sampled_surface_stays)
{
    Bridged b = bridged_tetrahedra(0.5, true);
    const BridgeStats stats = remove_bridges(b.mesh, b.h, kSpacingOf);
    EXPECT_EQ(stats.tubes, 0u);
    EXPECT_EQ(b.mesh.n_faces(), 12u);
    EXPECT_EQ(topology_stats(b.mesh).components, 1u);
    // Nor is a tube cut whose faces are short against the spacing the tiles report.
    Bridged c = bridged_tetrahedra(0.5, false);
    const BridgeStats coarse = remove_bridges(c.mesh, c.h, {{0, 0.5}});
    EXPECT_EQ(coarse.tubes, 0u);
    EXPECT_EQ(c.mesh.n_faces(), 12u);
    // Off: nothing.
    BridgeOptions off;
    off.max_loop_edges = 0;
    EXPECT_EQ(remove_bridges(c.mesh, c.h, kSpacingOf, off).tubes, 0u);
    EXPECT_EQ(c.mesh.n_faces(), 12u);
}

TEST(RemoveBridges, options_out_of_range_and_a_mesh_without_properties_are_refused)
{
    Bridged b = bridged_tetrahedra(0.5, false);
    BridgeOptions o;
    o.max_loop_edges = 5;
    EXPECT_THROW(remove_bridges(b.mesh, b.h, kSpacingOf, o), InvalidInput);
    o = {};
    o.off_share = std::nan("");
    EXPECT_THROW(remove_bridges(b.mesh, b.h, kSpacingOf, o), InvalidInput);
    MeshOptions mesh_options;
    mesh_options.bridges.reach_spacings = 0.0;
    EXPECT_THROW(mesh_cut(b.h, {0}, mesh_options), InvalidInput);
    Mesh bare;
    bare.add_vertex({0, 0, 0});
    EXPECT_THROW(remove_bridges(bare, b.h, kSpacingOf), InvalidInput);
}

// A coarse cut of a dense sample is all long gap faces (each thousands of spots at a third of the
// reach apart); their chords lie off the curved surface by their sagitta, not by half a gap, and are
// not judged spot by spot. The counts are the pass's work, the same on every machine.
TEST(RemoveBridges, chords_of_a_coarse_cut_are_not_judged)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(100000));
    for (const double tolerance : {0.02, 0.005}) {
        SCOPED_TRACE("tolerance " + std::to_string(tolerance));
        const MeshResult m = mesh_cut(h, cut_by_tolerance(h, tolerance));
        EXPECT_GT(m.bridges.long_faces, 50u);
        EXPECT_LE(m.bridges.judged * 20, m.bridges.long_faces);
        EXPECT_EQ(m.bridges.tubes, 0u);
        EXPECT_EQ(topology_stats(m.mesh).genus, 0);
    }
}

TEST(RemoveBridges, linked_rings_five_spacings_apart_mesh_as_two_rings)
{
    // 41,000 points per ring: a spacing of 0.012, the gap 5 of them, the tubes 25 across. Seeds 12 and
    // 14 had the two rings joined by a tube at the default tolerance (one piece) before the pass.
    for (const std::uint32_t seed : {12u, 14u}) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        const Hierarchy h = build_hierarchy(shapes::linked_tori(41000, 1.0, 0.15, 0.06, seed));
        const MendedMeshResult m = mesh_at_tolerance(h, 0.002);
        const TopologyStats t = topology_stats(m.result.mesh);
        EXPECT_EQ(t.components, 2u);
        EXPECT_EQ(t.genus, 2); // one handle each
        EXPECT_EQ(t.boundary_loops, 0u);
        EXPECT_EQ(t.nonmanifold_edges + t.nonmanifold_vertices, 0u);
        EXPECT_TRUE(self_intersecting_faces(m.result.mesh).empty());
    }
}

} // namespace
} // namespace mrt
