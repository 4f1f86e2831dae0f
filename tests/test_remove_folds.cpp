// Tests of remove_folds.h: a spike pulled out of a flat grid is folded back in (border untouched,
// counts kept); on a box's mesh the folds along its edges mostly go while topology, face count and
// crossings stay and no point loses the surface by much; faces of known crossing pairs are left
// alone; a height field stays a graph; bad options are refused.
#include "libmrtile/cluster_tree.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/remove_folds.h"
#include "libmrtile/shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace mrt {
namespace {

// The largest angle between the normals of two faces sharing an edge, in degrees.
double largest_fold_degrees(const Mesh& mesh, std::size_t* beyond_150 = nullptr)
{
    double worst = 0.0;
    std::size_t count = 0;
    for (const auto e : mesh.edges()) {
        if (mesh.is_boundary(e))
            continue;
        const auto h = mesh.halfedge_handle(e, 0);
        const auto n0 = mesh.calc_face_normal(mesh.face_handle(h)), n1 = mesh.calc_face_normal(mesh.opposite_face_handle(h));
        const double degrees = std::acos(std::clamp(double(OpenMesh::dot(n0, n1)), -1.0, 1.0)) * 180.0 / M_PI;
        worst = std::max(worst, degrees);
        count += degrees > 150.0;
    }
    if (beyond_150)
        *beyond_150 = count;
    return worst;
}

// A flat 5 x 5 grid of unit squares, each cut along the same diagonal, facing +z.
Mesh flat_grid()
{
    Mesh mesh;
    std::vector<Mesh::VertexHandle> v;
    for (int y = 0; y <= 5; ++y)
        for (int x = 0; x <= 5; ++x)
            v.push_back(mesh.add_vertex(Mesh::Point(x, y, 0.0)));
    const auto at = [&](int x, int y) { return v[static_cast<std::size_t>(y * 6 + x)]; };
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x) {
            EXPECT_TRUE(mesh.add_face(at(x, y), at(x + 1, y), at(x + 1, y + 1)).is_valid());
            EXPECT_TRUE(mesh.add_face(at(x, y), at(x + 1, y + 1), at(x, y + 1)).is_valid());
        }
    return mesh;
}

TEST(RemoveFolds, a_spike_pulled_out_of_a_flat_grid_is_folded_back)
{
    Mesh mesh = flat_grid();
    // Vertex (2, 2) pulled over its neighbour (3, 3) and up a little: its faces turn back over the ones
    // beyond it, a spike.
    const Mesh::VertexHandle tip(2 * 6 + 2);
    mesh.set_point(tip, Mesh::Point(3.6, 3.4, 0.3));
    std::size_t before = 0;
    ASSERT_GT(largest_fold_degrees(mesh, &before), 150.0);
    std::vector<Mesh::Point> border;
    for (const auto v : mesh.vertices())
        if (mesh.is_boundary(v))
            border.push_back(mesh.point(v));
    const std::size_t vertices = mesh.n_vertices(), faces = mesh.n_faces();

    const FoldStats s = remove_folds(mesh);
    EXPECT_GT(s.folds_before, 0u);
    EXPECT_EQ(s.folds_after, 0u);
    EXPECT_GT(s.flips + s.moves, 0u);
    std::size_t after = 0;
    EXPECT_LE(largest_fold_degrees(mesh, &after), 150.0);
    EXPECT_EQ(after, 0u);
    EXPECT_EQ(mesh.n_vertices(), vertices);
    EXPECT_EQ(mesh.n_faces(), faces);
    std::size_t k = 0;
    for (const auto v : mesh.vertices()) {
        if (mesh.is_boundary(v)) {
            EXPECT_EQ(mesh.point(v), border[k++]); // the border is the sample's: it never moves
        }
    }
    const TopologyStats t = topology_stats(mesh);
    EXPECT_EQ(t.boundary_loops, 1u);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_TRUE(self_intersecting_faces(mesh).empty());
}

TEST(RemoveFolds, a_tip_that_stands_on_a_sample_point_keeps_its_place)
{
    Mesh mesh = flat_grid();
    const Mesh::VertexHandle tip(2 * 6 + 2);
    mesh.set_point(tip, Mesh::Point(3.6, 3.4, 0.3));
    PointCloud cloud;
    for (const auto v : mesh.vertices())
        cloud.positions.push_back(to_vec3(mesh.point(v))); // the spike is sampled: a real corner
    const Hierarchy h = build_hierarchy(std::move(cloud));
    ASSERT_EQ(h.cloud.origin, (Vec3{0, 0, 0}));
    Mesh free = mesh;
    const FoldStats unsampled = remove_folds(free);
    EXPECT_GT(unsampled.moves, 0u); // without the sample the tip moves in
    const FoldStats s = remove_folds(mesh, {}, nullptr, &h);
    EXPECT_EQ(s.moves, 0u);
    EXPECT_EQ(mesh.point(tip), Mesh::Point(3.6, 3.4, 0.3));
}

TEST(RemoveFolds, faces_of_known_crossing_pairs_are_left_alone)
{
    Mesh mesh = flat_grid();
    const Mesh::VertexHandle tip(2 * 6 + 2);
    mesh.set_point(tip, Mesh::Point(3.6, 3.4, 0.3));
    // Every face around the tip named in a pair: nothing there may change.
    std::vector<std::pair<int, int>> pairs;
    for (const auto f : mesh.vf_range(tip))
        pairs.emplace_back(f.idx(), f.idx());
    const Mesh before = mesh;
    const FoldStats s = remove_folds(mesh, {}, &pairs);
    EXPECT_EQ(mesh.point(tip), before.point(tip));
    for (const auto f : before.vf_range(tip)) {
        std::vector<int> was, now;
        for (const auto v : before.fv_range(f))
            was.push_back(v.idx());
        for (const auto v : mesh.fv_range(f))
            now.push_back(v.idx());
        EXPECT_EQ(was, now);
    }
    EXPECT_GT(s.folds_after, 0u);
}

TEST(RemoveFolds, a_height_field_stays_a_graph)
{
    Mesh mesh = flat_grid();
    mesh.set_point(Mesh::VertexHandle(2 * 6 + 2), Mesh::Point(3.6, 3.4, 0.3));
    FoldOptions o;
    o.vertical = true;
    o.axis = {0, 0, 1};
    remove_folds(mesh, o);
    mesh.update_face_normals();
    // Every face the pass changed faces up; faces it left (the spike's, if any) are counted apart.
    std::size_t down = 0;
    for (const auto f : mesh.faces())
        down += mesh.calc_face_normal(f)[2] <= 0.0;
    std::size_t folds = 0;
    largest_fold_degrees(mesh, &folds);
    EXPECT_EQ(folds, 0u);
    EXPECT_EQ(down, 0u);
}

// The folds along a uniformly sampled box's edges (gap faces between the tiles of two sides, and the
// fit's moves of their rims: spikes that every viewer shows), with the pass and without it.
TEST(RemoveFolds, most_folds_along_a_boxs_edges_go_and_nothing_else_changes)
{
    const Hierarchy h = build_hierarchy(shapes::box_surface({2, 1, 0.5}, 8000));
    MeshOptions off;
    off.folds.fold_angle_degrees = 180.0;
    const MeshResult without = mesh_at_tolerance(h, 0.002, off).result;
    const MeshResult with = mesh_at_tolerance(h, 0.002).result;
    std::size_t folds_without = 0, folds_with = 0;
    largest_fold_degrees(without.mesh, &folds_without);
    largest_fold_degrees(with.mesh, &folds_with);
    ASSERT_GT(folds_without, 10u);
    EXPECT_LE(3 * folds_with, 2 * folds_without); // session 55: 25 -> 16
    EXPECT_EQ(with.folds.folds_after, folds_with);
    EXPECT_EQ(with.mesh.n_faces(), without.mesh.n_faces());
    EXPECT_EQ(with.mesh.n_vertices(), without.mesh.n_vertices());
    const TopologyStats a = topology_stats(without.mesh), b = topology_stats(with.mesh);
    EXPECT_EQ(b.boundary_loops, a.boundary_loops);
    EXPECT_EQ(b.genus, a.genus);
    EXPECT_EQ(b.components, a.components);
    EXPECT_LE(self_intersecting_faces(with.mesh).size(), self_intersecting_faces(without.mesh).size());
    const DistanceStats da = point_to_mesh_distance(h.cloud.positions, without.mesh);
    const DistanceStats db = point_to_mesh_distance(h.cloud.positions, with.mesh);
    EXPECT_LE(db.mean, 1.01 * da.mean);
    // A tip moves at most as far as it stood from the points, never farther from them: the corners'
    // points keep the surface (moving every corner of a fold in took the farthest point 2x as far).
    EXPECT_LE(db.max, 1.01 * da.max);
}

TEST(RemoveFolds, bad_options_are_refused)
{
    Mesh mesh = flat_grid();
    for (const double angle : {0.0, -1.0, 181.0, std::nan("")}) {
        FoldOptions o;
        o.fold_angle_degrees = angle;
        EXPECT_THROW(remove_folds(mesh, o), InvalidInput);
        o = {};
        o.max_face_angle_degrees = angle;
        EXPECT_THROW(remove_folds(mesh, o), InvalidInput);
    }
    FoldOptions o;
    o.passes = 65;
    EXPECT_THROW(remove_folds(mesh, o), InvalidInput);
    o = {};
    o.vertical = true;
    o.axis = {0, 0, 0};
    EXPECT_THROW(remove_folds(mesh, o), InvalidInput);
    MeshOptions m;
    m.folds.passes = -1;
    EXPECT_THROW(check_mesh_options(m), InvalidInput);
}

} // namespace
} // namespace mrt
