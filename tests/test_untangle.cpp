// Tests of untangle.h: a tent whose tip pokes through a sheet is pulled back within the move limit;
// on meshes of real scans (the bunny's ear tips, a fandisk edge, Igea) the pairs the surface leaves are
// gone while topology and face counts stay; a clean mesh is left as it is.
#include "formats/read_points.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/fit_vertices.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"
#include "libmrtile/untangle.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>

#include <cmath>
#include <string>
#include <vector>

namespace mrt {
namespace {

// A flat 5 x 5 sheet at z = 0 and, above it, an open hexagonal tent (rim at z = 0.1, radius 1) whose
// apex reaches 0.05 below the sheet: the tent's faces cross the sheet's.
Mesh tent_through_sheet()
{
    Mesh mesh;
    std::vector<Mesh::VertexHandle> grid;
    for (int j = 0; j <= 4; ++j)
        for (int i = 0; i <= 4; ++i)
            grid.push_back(mesh.add_vertex(Mesh::Point(i - 2.0, j - 2.0, 0.0)));
    auto at = [&](int i, int j) { return grid[static_cast<std::size_t>(j * 5 + i)]; };
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            mesh.add_face(at(i, j), at(i + 1, j), at(i + 1, j + 1));
            mesh.add_face(at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    const auto apex = mesh.add_vertex(Mesh::Point(0.1, 0.05, -0.05));
    std::vector<Mesh::VertexHandle> rim;
    for (int k = 0; k < 6; ++k)
        rim.push_back(mesh.add_vertex(Mesh::Point(std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0.1)));
    for (int k = 0; k < 6; ++k)
        mesh.add_face(apex, rim[static_cast<std::size_t>((k + 1) % 6)], rim[static_cast<std::size_t>(k)]);
    mesh.update_normals();
    return mesh;
}

// Corners of a face, sorted (the triangle whatever its handle or first corner).
std::array<int, 3> triangle(const Mesh& mesh, Mesh::FaceHandle f)
{
    std::array<int, 3> c{};
    std::size_t k = 0;
    for (const auto v : mesh.fv_range(f))
        c[k++] = v.idx();
    std::sort(c.begin(), c.end());
    return c;
}

TEST(Untangle, a_tip_through_a_sheet_is_pulled_back)
{
    Mesh mesh = tent_through_sheet();
    const std::size_t faces = mesh.n_faces();
    // Every face its own tile id: a flip tried and undone may hand the two triangles back to the two
    // handles the other way round, and the ids must follow their triangles.
    auto tile = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile);
    auto gap = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, bool>(mesh, kFaceGap);
    std::map<int, std::array<int, 3>> triangle_of_tile;
    for (const auto f : mesh.faces()) {
        tile[f] = f.idx();
        gap[f] = false;
        triangle_of_tile[f.idx()] = triangle(mesh, f);
    }
    const std::vector<std::pair<int, int>> crossing = self_intersecting_faces(mesh);
    ASSERT_FALSE(crossing.empty());
    std::vector<Mesh::Point> before;
    for (const auto v : mesh.vertices())
        before.push_back(mesh.point(v));
    const UntangleStats stats = untangle(mesh);
    EXPECT_EQ(stats.pairs_before, crossing.size());
    EXPECT_EQ(stats.pairs_after, 0u);
    EXPECT_TRUE(self_intersecting_faces(mesh).empty());
    EXPECT_GT(stats.moves, 0u);
    EXPECT_EQ(mesh.n_faces(), faces);
    std::size_t labelled = 0;
    for (const auto f : mesh.faces())
        if (tile[f] >= 0) { // -1: a kept flip across two tiles
            EXPECT_EQ(triangle(mesh, f), triangle_of_tile[tile[f]]) << f.idx();
            ++labelled;
        }
    EXPECT_GT(labelled, faces - 2 * stats.flips - 1);
    // Every vertex moved by at most max_move of its shortest edge (here at least 0.95: the grid's
    // spacing is 1, the tent's rim edges and slopes about 1).
    const double limit = UntangleOptions{}.max_move * 1.05;
    for (const auto v : mesh.vertices())
        EXPECT_LE((mesh.point(v) - before[static_cast<std::size_t>(v.idx())]).norm(), limit) << v.idx();
}

TEST(Untangle, a_clean_mesh_is_left_as_it_is)
{
    Mesh mesh = tent_through_sheet();
    for (const auto v : mesh.vertices())
        if (mesh.point(v)[2] < 0)
            mesh.point(v)[2] = 0.05; // the apex above the sheet: nothing crosses
    const Mesh original = mesh;
    const UntangleStats stats = untangle(mesh);
    EXPECT_EQ(stats.pairs_before, 0u);
    EXPECT_EQ(stats.flips + stats.moves, 0u);
    for (const auto v : mesh.vertices())
        EXPECT_EQ(mesh.point(v), original.point(v));
}

// Real cuts whose surfaces crossed themselves before this pass (a gap face through a fan at a thin
// tip): mesh_cut now leaves no pair, with the same faces and topology as without the pass.
TEST(Untangle, real_scans_lose_their_self_intersections)
{
    struct Case
    {
        std::string file;
        double tolerance;
    };
    for (const Case& c : {Case{"bun_zipper.ply", 0.005}, Case{"bun_zipper.ply", 0.001}, Case{"fandisk.obj", 0.01}}) {
        const Hierarchy h = build_hierarchy(read_points(std::string(MRTILE_SHARED_DATA) + "/" + c.file));
        const Cut cut = cut_by_tolerance(h, c.tolerance);
        MeshOptions off;
        off.untangle.max_rounds = 0;
        const MeshResult tangled = mesh_cut(h, cut, off);
        const MeshResult r = mesh_cut(h, cut);
        const std::size_t pairs = self_intersecting_faces(tangled.mesh).size();
        EXPECT_GT(pairs, 0u) << c.file << " " << c.tolerance; // the case still exercises the pass
        EXPECT_EQ(r.untangle.pairs_before, pairs) << c.file;
        EXPECT_EQ(r.untangle.pairs_after, 0u) << c.file;
        EXPECT_TRUE(self_intersecting_faces(r.mesh).empty()) << c.file << " " << c.tolerance;
        EXPECT_EQ(r.mesh.n_faces(), tangled.mesh.n_faces());
        const TopologyStats a = topology_stats(r.mesh), b = topology_stats(tangled.mesh);
        EXPECT_EQ(a.genus, b.genus);
        EXPECT_EQ(a.boundary_loops, b.boundary_loops);
        EXPECT_EQ(a.nonmanifold_edges + a.nonmanifold_vertices, 0u);
        // The moves are small: the mean distance of the points to the mesh stays within 2%.
        const double with = point_to_mesh_distance(h.cloud.positions, r.mesh).mean;
        const double without = point_to_mesh_distance(h.cloud.positions, tangled.mesh).mean;
        EXPECT_LT(with, 1.02 * without) << c.file;
    }
}

// A closed cone's rim, where the slope meets the base at 63 degrees: gap faces there fold under
// their neighbours around one vertex, and no flip or move unfolds them; collapsing an edge of the fold
// does. The cone keeps its genus and gains no loop, the vertex and tile ids follow the garbage collection, and
// pairs_after counts what is left.
TEST(Untangle, a_fold_at_a_cone_rim_is_collapsed)
{
    const Hierarchy h = build_hierarchy(shapes::cone(60000));
    const Cut cut = cut_by_tolerance(h, 0.01);
    MeshOptions on, off; // on the same cut: the crossing rounds (which refine it) off in both
    on.crossing_rounds = 0;
    off = on;
    off.untangle.max_rounds = 0;
    const MeshResult tangled = mesh_cut(h, cut, off);
    MeshResult r = mesh_cut(h, cut, on);
    const std::size_t pairs = self_intersecting_faces(tangled.mesh).size();
    ASSERT_GT(pairs, 0u);
    EXPECT_GT(r.untangle.collapses, 0u);
    EXPECT_LT(r.untangle.pairs_after, pairs / 4);
    EXPECT_EQ(self_intersecting_faces(r.mesh).size(), r.untangle.pairs_after);
    // Each collapse removes one vertex (and its two faces); nothing else is deleted but border folds.
    EXPECT_EQ(r.mesh.n_vertices(), tangled.mesh.n_vertices() - r.untangle.collapses);
    EXPECT_EQ(r.mesh.n_faces(), tangled.mesh.n_faces() - 2 * r.untangle.collapses - r.untangle.removed_faces);
    const TopologyStats a = topology_stats(r.mesh), b = topology_stats(tangled.mesh);
    EXPECT_EQ(a.genus, b.genus);
    EXPECT_EQ(a.nonmanifold_edges + a.nonmanifold_vertices, 0u);
    EXPECT_LE(a.boundary_loops, b.boundary_loops + r.untangle.removed_faces);
    // The ids live on: every vertex has a cluster of the cut, and the faces without a corner of their
    // own tile (a rim vertex merged across a gap names one of its tiles) are no more than before.
    auto misnamed = [](Mesh& mesh) {
        auto cluster = OpenMesh::getProperty<OpenMesh::VertexHandle, int>(mesh, kVertexCluster);
        auto tile = OpenMesh::getProperty<OpenMesh::FaceHandle, int>(mesh, kFaceTile);
        std::size_t count = 0;
        for (const auto v : mesh.vertices())
            EXPECT_GE(cluster[v], 0) << v.idx();
        for (const auto f : mesh.faces()) {
            bool own = tile[f] < 0;
            for (const auto v : mesh.fv_range(f))
                own = own || cluster[v] == tile[f];
            count += own ? 0 : 1;
        }
        return count;
    };
    MeshResult tangled_copy = tangled;
    EXPECT_LE(misnamed(r.mesh), misnamed(tangled_copy.mesh));
}

// A noisy sphere whose cut at 0.0005 lies below its noise floor: meshed without the pass, a crumpled
// surface with a hundred or more crossings, for the bookkeeping tests below.
Hierarchy noisy_sphere()
{
    PointCloud cloud = shapes::sphere(30000);
    shapes::add_noise(cloud, 0.01);
    BuildOptions raw; // the noise kept: a crumpled mesh is what these tests need
    raw.denoise = BuildOptions::Denoise::Off;
    Hierarchy h = build_hierarchy(cloud, raw);
    clear_noise_floor(h);
    return h;
}

MeshResult crumpled_sphere(const Hierarchy& h)
{
    MeshOptions off;
    off.untangle.max_rounds = 0;
    return mesh_cut(h, cut_by_tolerance(h, 0.0005), off);
}

TEST(Untangle, pairs_near_changed_faces_match_a_test_of_the_whole_mesh)
{
    const MeshResult r = crumpled_sphere(noisy_sphere());
    const auto all = self_intersecting_faces(r.mesh);
    ASSERT_GT(all.size(), 50u);
    // Brute force over every pair of faces with overlapping boxes agrees with CGAL's test.
    std::vector<std::pair<int, int>> brute;
    const int n = static_cast<int>(r.mesh.n_faces());
    std::vector<std::array<OpenMesh::Vec3d, 2>> box(static_cast<std::size_t>(n));
    for (const auto f : r.mesh.faces()) {
        auto& b = box[static_cast<std::size_t>(f.idx())];
        b = {OpenMesh::Vec3d(1e300), OpenMesh::Vec3d(-1e300)};
        for (const auto v : r.mesh.fv_range(f)) {
            b[0].minimize(r.mesh.point(v));
            b[1].maximize(r.mesh.point(v));
        }
    }
    for (int a = 0; a < n; ++a)
        for (int b = a + 1; b < n; ++b) {
            const auto &x = box[static_cast<std::size_t>(a)], &y = box[static_cast<std::size_t>(b)];
            if (x[1][0] < y[0][0] || y[1][0] < x[0][0] || x[1][1] < y[0][1] || y[1][1] < x[0][1] || x[1][2] < y[0][2] || y[1][2] < x[0][2])
                continue;
            if (faces_intersect(r.mesh, Mesh::FaceHandle(a), Mesh::FaceHandle(b)))
                brute.push_back({a, b});
        }
    EXPECT_EQ(brute, all);
    // The pairs with a face in a subset are those of the whole test that touch the subset.
    for (const int step : {7, 101, 1}) {
        std::vector<int> some;
        for (int f = step / 2; f < n; f += step)
            some.push_back(f);
        std::vector<char> in(static_cast<std::size_t>(n), 0);
        for (const int f : some)
            in[static_cast<std::size_t>(f)] = 1;
        std::vector<std::pair<int, int>> expected;
        for (const auto& p : all)
            if (in[static_cast<std::size_t>(p.first)] || in[static_cast<std::size_t>(p.second)])
                expected.push_back(p);
        EXPECT_EQ(intersecting_pairs_with(r.mesh, some), expected) << "every " << step << "th face";
    }
    EXPECT_TRUE(intersecting_pairs_with(r.mesh, {}).empty());
}

TEST(Untangle, starting_from_known_pairs_gives_the_same_mesh)
{
    const MeshResult r = crumpled_sphere(noisy_sphere());
    Mesh tested = r.mesh, given = r.mesh;
    const UntangleStats a = untangle(tested, {});
    const UntangleStats b = untangle(given, {}, self_intersecting_faces(given));
    ASSERT_GT(a.pairs_before, 50u);
    EXPECT_GT(a.flips + a.moves, 0u);
    EXPECT_EQ(a.pairs_before, b.pairs_before);
    EXPECT_EQ(a.pairs_after, b.pairs_after);
    EXPECT_EQ(a.flips, b.flips);
    EXPECT_EQ(a.moves, b.moves);
    // The count left after the rounds (kept up from the changed faces) is that of a whole test.
    EXPECT_EQ(a.pairs_after, self_intersecting_faces(tested).size());
    Mesh other = r.mesh;
    EXPECT_THROW(untangle(other, {}, {{0, static_cast<int>(other.n_faces())}}), InvalidInput);
    EXPECT_THROW(untangle(other, {}, {{-1, 3}}), InvalidInput);
    ASSERT_EQ(tested.n_vertices(), given.n_vertices());
    for (const auto v : tested.vertices())
        EXPECT_EQ(tested.point(v), given.point(v));
}

TEST(Untangle, the_fit_hands_on_every_pair_it_leaves)
{
    const Hierarchy h = noisy_sphere();
    MeshResult r = crumpled_sphere(h);
    // mesh_cut hands the pairs on to untangle and clears them; fit again to see them.
    const FitStats s = fit_vertices(r.mesh, h.cloud.positions);
    ASSERT_TRUE(s.pairs_known);
    EXPECT_GT(s.reverted + s.intersecting_pairs.size(), 0u);
    EXPECT_EQ(s.intersecting_pairs, self_intersecting_faces(r.mesh));
}

// A flat fan of four faces around an inner vertex pulled just past one border edge: the face on that
// edge is folded over its neighbours in the plane. Marked a gap face, it is removed last (no flip or
// move is allowed here: max_rounds 0); the mesh stays a manifold with one loop. Without f:gap, or with
// the option off, every face stays.
TEST(Untangle, a_border_gap_face_folded_in_the_plane_is_removed)
{
    auto folded = [](bool mark) {
        Mesh mesh;
        const auto a = mesh.add_vertex(Mesh::Point(0, 0, 0)), b = mesh.add_vertex(Mesh::Point(1, 0, 0));
        const auto c = mesh.add_vertex(Mesh::Point(1, 1, 0)), d = mesh.add_vertex(Mesh::Point(0, 1, 0));
        const auto w = mesh.add_vertex(Mesh::Point(0.5, -0.1, 0)); // just below the edge a b
        const auto f0 = mesh.add_face(w, a, b);
        mesh.add_face(w, b, c);
        mesh.add_face(w, c, d);
        mesh.add_face(w, d, a);
        if (mark) {
            auto gap = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, bool>(mesh, kFaceGap);
            for (const auto f : mesh.faces())
                gap[f] = f == f0;
        }
        mesh.update_normals();
        return mesh;
    };
    UntangleOptions no_edits;
    no_edits.max_rounds = 0;
    Mesh mesh = folded(true);
    ASSERT_FALSE(self_intersecting_faces(mesh).empty());
    const UntangleStats s = untangle(mesh, no_edits);
    EXPECT_EQ(s.removed_faces, 1u);
    EXPECT_EQ(s.pairs_after, 0u);
    EXPECT_EQ(mesh.n_faces(), 3u);
    EXPECT_TRUE(self_intersecting_faces(mesh).empty());
    const TopologyStats t = topology_stats(mesh);
    EXPECT_EQ(t.boundary_loops, 1u);
    EXPECT_EQ(t.nonmanifold_vertices, 0u);
    for (const bool mark : {false, true}) {
        Mesh kept = folded(mark);
        UntangleOptions o = no_edits;
        o.remove_border_folds = !mark; // unmarked: on but nothing to remove; marked: off
        EXPECT_EQ(untangle(kept, o).removed_faces, 0u);
        EXPECT_EQ(kept.n_faces(), 4u);
    }
}

// A flat 6 x 6 grid with one inner vertex pushed in the plane past its neighbours: its faces fold over
// theirs. Lifting a vertex off the plane would part the faces too, as a tent standing out of a flat
// part (an L-shaped plate got one 6% of its diagonal high); in the plane, moves toward the neighbours'
// centre undo the fold, and every vertex stays in the plane.
TEST(Untangle, a_fold_in_the_plane_is_not_lifted_out_of_it)
{
    Mesh mesh;
    std::vector<Mesh::VertexHandle> grid;
    for (int j = 0; j <= 6; ++j)
        for (int i = 0; i <= 6; ++i)
            grid.push_back(mesh.add_vertex(Mesh::Point(i, j, 0.0)));
    auto at = [&](int i, int j) { return grid[static_cast<std::size_t>(j * 7 + i)]; };
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) {
            mesh.add_face(at(i, j), at(i + 1, j), at(i + 1, j + 1));
            mesh.add_face(at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    mesh.point(at(3, 3)) = Mesh::Point(4.4, 3.3, 0.0); // past its neighbour (4, 3)
    mesh.update_normals();
    const std::size_t before = self_intersecting_faces(mesh).size();
    ASSERT_GT(before, 0u);
    const UntangleStats s = untangle(mesh);
    EXPECT_LT(s.pairs_after, before);
    for (const auto v : mesh.vertices())
        EXPECT_EQ(mesh.point(v)[2], 0.0) << "vertex " << v.idx() << " left the plane";
}

} // namespace
} // namespace mrt
