// Tests of mesh_stats.h: exact topology on analytic meshes (Platonic solids, torus grids, voxel
// surfaces of known genus, non-manifold soups) and distances against closed forms and brute force.
// GCC 12 at -O2 warns inside OpenMesh's PropertyT<Vec3d>::push_back (instantiated at the end of this
// file) that it copies a default, deliberately uninitialised normal. The copy is harmless; the warning is
// attributed to a standard header line, so it can only be silenced before the first include.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "libmrtile/mesh_stats.h"

#include "libmrtile/cluster_tree.h"
#include "libmrtile/errors.h"
#include "tests/mesh_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <tuple>

namespace mrt {
namespace {

using Triangles = std::vector<std::array<std::uint32_t, 3>>;

struct Soup
{
    std::vector<Vec3> positions;
    Triangles triangles;
};

TopologyStats stats(const Soup& s) { return topology_stats(s.positions, s.triangles); }

Mesh to_mesh(const Soup& s)
{
    Mesh mesh;
    std::vector<Mesh::VertexHandle> handles;
    for (const Vec3& p : s.positions)
        handles.push_back(mesh.add_vertex(Mesh::Point(p.x, p.y, p.z)));
    for (const auto& t : s.triangles) {
        const auto fh = mesh.add_face(handles[t[0]], handles[t[1]], handles[t[2]]);
        EXPECT_TRUE(fh.is_valid()) << "OpenMesh refused a face of a test mesh";
    }
    return mesh;
}

void append(Soup& to, const Soup& from, const Vec3& offset = {})
{
    const auto base = static_cast<std::uint32_t>(to.positions.size());
    for (const Vec3& p : from.positions)
        to.positions.push_back(p + offset);
    for (const auto& t : from.triangles)
        to.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

// Outward-oriented (counter-clockwise seen from outside) Platonic solids.
Soup tetrahedron()
{
    return {{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}}, {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}};
}

Soup octahedron()
{
    return {{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
            {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}}};
}

Soup icosahedron()
{
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    return {{{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
             {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}},
            {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2},
             {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5},
             {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}}};
}

// Signed volume: positive iff the closed mesh is oriented outwards (checks the fixtures themselves).
double signed_volume(const Soup& s)
{
    double v = 0.0;
    for (const auto& t : s.triangles)
        v += dot(s.positions[t[0]], cross(s.positions[t[1]], s.positions[t[2]])) / 6.0;
    return v;
}

// Grid of nu x nv quads, each split in two; `wrap_u`/`wrap_v` glue opposite sides (both: a torus).
Soup grid(int nu, int nv, bool wrap_u, bool wrap_v, double R = 1.0, double r = 0.4)
{
    Soup s;
    const int cu = wrap_u ? nu : nu + 1, cv = wrap_v ? nv : nv + 1;
    for (int j = 0; j < cv; ++j)
        for (int i = 0; i < cu; ++i) {
            if (wrap_u && wrap_v) {
                const double a = 2 * M_PI * i / nu, b = 2 * M_PI * j / nv;
                s.positions.push_back({(R + r * std::cos(b)) * std::cos(a), (R + r * std::cos(b)) * std::sin(a),
                                       r * std::sin(b)});
            } else {
                s.positions.push_back({double(i), double(j), 0.0});
            }
        }
    auto id = [&](int i, int j) { return static_cast<std::uint32_t>((j % cv) * cu + (i % cu)); };
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return s;
}

// Boundary of a set of unit voxels, outward oriented; vertices shared through their grid coordinates.
Soup voxel_surface(const std::set<std::tuple<int, int, int>>& voxels)
{
    Soup s;
    std::map<std::tuple<int, int, int>, std::uint32_t> index;
    auto vertex = [&](int x, int y, int z) {
        const auto key = std::make_tuple(x, y, z);
        const auto it = index.find(key);
        if (it != index.end())
            return it->second;
        const auto i = static_cast<std::uint32_t>(s.positions.size());
        s.positions.push_back({double(x), double(y), double(z)});
        index.emplace(key, i);
        return i;
    };
    for (const auto& [x, y, z] : voxels)
        for (int axis = 0; axis < 3; ++axis)
            for (const int side : {0, 1}) {
                int n[3] = {x, y, z};
                n[axis] += side ? 1 : -1;
                if (voxels.count({n[0], n[1], n[2]}))
                    continue;
                // Quad corners in the face plane, ordered counter-clockwise seen from outside.
                const int u = (axis + 1) % 3, w = (axis + 2) % 3;
                int c[4][3];
                const int du[4] = {0, 1, 1, 0}, dw[4] = {0, 0, 1, 1};
                for (int k = 0; k < 4; ++k) {
                    c[k][axis] = (axis == 0 ? x : axis == 1 ? y : z) + side;
                    c[k][u] = (u == 0 ? x : u == 1 ? y : z) + du[k];
                    c[k][w] = (w == 0 ? x : w == 1 ? y : z) + dw[k];
                }
                std::uint32_t q[4];
                for (int k = 0; k < 4; ++k)
                    q[k] = vertex(c[k][0], c[k][1], c[k][2]);
                if (side) {
                    s.triangles.push_back({q[0], q[1], q[2]});
                    s.triangles.push_back({q[0], q[2], q[3]});
                } else {
                    s.triangles.push_back({q[0], q[2], q[1]});
                    s.triangles.push_back({q[0], q[3], q[2]});
                }
            }
    return s;
}

// A one-voxel-thick plate of w x 3 voxels with the given x positions (at y = 1) drilled through.
Soup plate_with_holes(int w, const std::vector<int>& holes)
{
    std::set<std::tuple<int, int, int>> voxels;
    for (int x = 0; x < w; ++x)
        for (int y = 0; y < 3; ++y)
            if (y != 1 || std::find(holes.begin(), holes.end(), x) == holes.end())
                voxels.insert({x, y, 0});
    return voxel_surface(voxels);
}

void expect_closed_genus(const TopologyStats& t, int genus, std::size_t components = 1)
{
    EXPECT_EQ(t.genus, genus);
    EXPECT_EQ(t.euler_characteristic, long(2 * components) - 2 * genus);
    EXPECT_EQ(t.components, components);
    EXPECT_EQ(t.boundary_edges, 0u);
    EXPECT_EQ(t.boundary_loops, 0u);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.nonmanifold_vertices, 0u);
    EXPECT_EQ(t.duplicate_faces, 0u);
    EXPECT_EQ(t.degenerate_faces, 0u);
    EXPECT_EQ(t.isolated_vertices, 0u);
    EXPECT_TRUE(t.consistently_oriented);
    EXPECT_EQ(2 * t.edges, 3 * t.faces);  // closed triangle mesh
}

void expect_same(const TopologyStats& a, const TopologyStats& b)
{
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.faces, b.faces);
    EXPECT_EQ(a.edges, b.edges);
    EXPECT_EQ(a.boundary_edges, b.boundary_edges);
    EXPECT_EQ(a.boundary_loops, b.boundary_loops);
    EXPECT_EQ(a.components, b.components);
    EXPECT_EQ(a.euler_characteristic, b.euler_characteristic);
    EXPECT_EQ(a.genus, b.genus);
    EXPECT_EQ(a.nonmanifold_edges, b.nonmanifold_edges);
    EXPECT_EQ(a.nonmanifold_vertices, b.nonmanifold_vertices);
    EXPECT_EQ(a.duplicate_faces, b.duplicate_faces);
    EXPECT_EQ(a.degenerate_faces, b.degenerate_faces);
    EXPECT_EQ(a.isolated_vertices, b.isolated_vertices);
    EXPECT_EQ(a.consistently_oriented, b.consistently_oriented);
}

TEST(TopologyStats, platonic_solids_are_closed_spheres)
{
    const Soup solids[] = {tetrahedron(), octahedron(), icosahedron()};
    const std::size_t expected[][3] = {{4, 6, 4}, {6, 12, 8}, {12, 30, 20}};  // V, E, F
    for (int i = 0; i < 3; ++i) {
        SCOPED_TRACE(i);
        ASSERT_GT(signed_volume(solids[i]), 0.0);
        const TopologyStats t = stats(solids[i]);
        expect_closed_genus(t, 0);
        EXPECT_EQ(t.vertices, expected[i][0]);
        EXPECT_EQ(t.edges, expected[i][1]);
        EXPECT_EQ(t.faces, expected[i][2]);
        expect_same(topology_stats(to_mesh(solids[i])), t);
    }
}

TEST(TopologyStats, torus_grid_has_genus_one)
{
    const Soup torus = grid(20, 12, true, true);
    ASSERT_GT(signed_volume(torus), 0.0);
    const TopologyStats t = stats(torus);
    expect_closed_genus(t, 1);
    EXPECT_EQ(t.vertices, 240u);
    EXPECT_EQ(t.faces, 480u);
    expect_same(topology_stats(to_mesh(torus)), t);
}

TEST(TopologyStats, voxel_surfaces_have_the_genus_of_their_holes)
{
    const Soup cube = voxel_surface({{0, 0, 0}});
    ASSERT_GT(signed_volume(cube), 0.0);
    expect_closed_genus(stats(cube), 0);
    for (int holes = 1; holes <= 3; ++holes) {
        SCOPED_TRACE(holes);
        std::vector<int> at;
        for (int h = 0; h < holes; ++h)
            at.push_back(1 + 2 * h);
        const Soup plate = plate_with_holes(7, at);
        ASSERT_GT(signed_volume(plate), 0.0);
        const TopologyStats t = stats(plate);
        expect_closed_genus(t, holes);
        expect_same(topology_stats(to_mesh(plate)), t);
    }
}

TEST(TopologyStats, genus_adds_over_components)
{
    Soup s = plate_with_holes(7, {1, 3, 5});
    append(s, grid(8, 6, true, true), {20, 0, 0});
    append(s, icosahedron(), {-20, 0, 0});
    expect_closed_genus(stats(s), 4, 3);
}

TEST(TopologyStats, open_patches_count_boundary_loops)
{
    const TopologyStats one = stats({{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}});
    EXPECT_EQ(one.boundary_loops, 1u);
    EXPECT_EQ(one.boundary_edges, 3u);
    EXPECT_EQ(one.euler_characteristic, 1);
    EXPECT_EQ(one.genus, 0);
    EXPECT_TRUE(one.consistently_oriented);

    const Soup patch = grid(5, 4, false, false);
    const TopologyStats p = stats(patch);
    EXPECT_EQ(p.boundary_loops, 1u);
    EXPECT_EQ(p.boundary_edges, 18u);
    EXPECT_EQ(p.euler_characteristic, 1);
    EXPECT_EQ(p.genus, 0);
    EXPECT_EQ(p.components, 1u);
    expect_same(topology_stats(to_mesh(patch)), p);

    // Remove the two triangles of the interior quad (i=2, j=1): an annulus.
    Soup annulus = patch;
    const std::size_t quad = 1 * 5 + 2;
    annulus.triangles.erase(annulus.triangles.begin() + 2 * quad, annulus.triangles.begin() + 2 * quad + 2);
    const TopologyStats a = stats(annulus);
    EXPECT_EQ(a.boundary_loops, 2u);
    EXPECT_EQ(a.boundary_edges, 22u);
    EXPECT_EQ(a.euler_characteristic, 0);
    EXPECT_EQ(a.genus, 0);
    expect_same(topology_stats(to_mesh(annulus)), a);

    // A cylinder (grid glued along one direction) has two loops; a torus with one quad removed one.
    const TopologyStats c = stats(grid(6, 3, true, false));
    EXPECT_EQ(c.boundary_loops, 2u);
    EXPECT_EQ(c.genus, 0);
    Soup punctured = grid(10, 6, true, true);
    punctured.triangles.resize(punctured.triangles.size() - 2);
    const TopologyStats pt = stats(punctured);
    EXPECT_EQ(pt.boundary_loops, 1u);
    EXPECT_EQ(pt.euler_characteristic, -1);
    EXPECT_EQ(pt.genus, 1);
}

TEST(TopologyStats, three_triangles_on_one_edge_make_a_nonmanifold_edge)
{
    const Soup s{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}};
    const TopologyStats t = stats(s);
    EXPECT_EQ(t.nonmanifold_edges, 1u);
    EXPECT_EQ(t.edges, 7u);
    EXPECT_EQ(t.boundary_edges, 6u);
    // The two end points have three separate fans each (the edge does not join them).
    EXPECT_EQ(t.nonmanifold_vertices, 2u);
    EXPECT_EQ(t.genus, -1);
    EXPECT_EQ(t.components, 1u);
    EXPECT_EQ(t.euler_characteristic, 5 - 7 + 3);
}

TEST(TopologyStats, bow_tie_is_a_nonmanifold_vertex)
{
    const Soup s{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {{0, 1, 2}, {0, 3, 4}}};
    const TopologyStats t = stats(s);
    EXPECT_EQ(t.nonmanifold_vertices, 1u);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.boundary_loops, 2u);  // each triangle keeps its own loop through the pinch
    EXPECT_EQ(t.components, 1u);
    EXPECT_EQ(t.genus, -1);
    expect_same(topology_stats(to_mesh(s)), t);  // OpenMesh can hold a bow-tie

    // Two cubes touching along one edge: that edge has four faces.
    const TopologyStats cubes = stats(voxel_surface({{0, 0, 0}, {1, 1, 0}}));
    EXPECT_EQ(cubes.nonmanifold_edges, 1u);
    EXPECT_EQ(cubes.genus, -1);
    EXPECT_TRUE(cubes.consistently_oriented);  // the shared edge is used twice in each direction
}

TEST(TopologyStats, flipped_face_breaks_orientation_but_not_genus)
{
    Soup s = icosahedron();
    std::swap(s.triangles[7][1], s.triangles[7][2]);
    const TopologyStats t = stats(s);
    EXPECT_FALSE(t.consistently_oriented);
    EXPECT_EQ(t.genus, 0);  // still an orientable sphere
    EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(TopologyStats, moebius_strip_is_not_orientable)
{
    // A strip of 8 quads whose last edge is glued to the first with a half twist.
    const int n = 8;
    Soup s;
    for (int i = 0; i < n; ++i) {
        const double a = 2 * M_PI * i / n;
        for (const double h : {-0.2, 0.2}) {
            const double rr = 1.0 + h * std::cos(a / 2);
            s.positions.push_back({rr * std::cos(a), rr * std::sin(a), h * std::sin(a / 2)});
        }
    }
    for (std::uint32_t i = 0; i < n; ++i) {
        const std::uint32_t a0 = 2 * i, a1 = 2 * i + 1;
        std::uint32_t b0 = (2 * i + 2) % (2 * n), b1 = (2 * i + 3) % (2 * n);
        if (i == n - 1)
            std::swap(b0, b1);  // the half twist
        s.triangles.push_back({a0, b0, b1});
        s.triangles.push_back({a0, b1, a1});
    }
    const TopologyStats t = stats(s);
    EXPECT_EQ(t.boundary_loops, 1u);
    EXPECT_EQ(t.euler_characteristic, 0);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.nonmanifold_vertices, 0u);
    EXPECT_FALSE(t.consistently_oriented);
    EXPECT_EQ(t.genus, -1);
}

TEST(TopologyStats, duplicate_degenerate_and_isolated_are_counted)
{
    Soup s = tetrahedron();
    s.triangles.push_back({s.triangles[2][1], s.triangles[2][2], s.triangles[2][0]});  // same set, rotated
    TopologyStats t = stats(s);
    EXPECT_EQ(t.duplicate_faces, 1u);
    EXPECT_EQ(t.nonmanifold_edges, 3u);
    EXPECT_EQ(t.degenerate_faces, 0u);

    Soup z = grid(3, 3, false, false);
    const auto mid = static_cast<std::uint32_t>(z.positions.size());
    z.positions.push_back({3.5, 0, 0});                     // on the x axis: collinear with 0 and 1
    z.positions.push_back({9, 9, 9});                       // isolated
    z.triangles.push_back({0, 1, mid});                     // zero area, distinct indices
    z.triangles.push_back({5, 5, 6});                       // repeated index
    t = stats(z);
    EXPECT_EQ(t.degenerate_faces, 2u);
    EXPECT_EQ(t.isolated_vertices, 1u);
    EXPECT_EQ(t.faces, 20u);
    EXPECT_EQ(t.vertices, 18u);
    EXPECT_EQ(t.duplicate_faces, 0u);
    // The repeated-index face adds nothing; the zero-area one adds a vertex, two edges and a face.
    EXPECT_EQ(t.edges, 33u + 2u);
    EXPECT_EQ(t.euler_characteristic, 1);
}

TEST(TopologyStats, empty_and_invalid_input)
{
    const TopologyStats e = topology_stats(std::vector<Vec3>{{0, 0, 0}}, {});
    EXPECT_EQ(e.isolated_vertices, 1u);
    EXPECT_EQ(e.components, 0u);
    EXPECT_EQ(e.genus, 0);
    EXPECT_THROW(topology_stats(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}}, {{0, 1, 2}}), InvalidInput);

    // Deleted faces and vertices of a mesh are ignored.
    Mesh mesh = to_mesh(octahedron());
    mesh.delete_vertex(mesh.vertex_handle(5));
    const TopologyStats t = topology_stats(mesh);
    EXPECT_EQ(t.vertices, 5u);
    EXPECT_EQ(t.faces, 4u);
    EXPECT_EQ(t.boundary_loops, 1u);
}

// ---- distances ----------------------------------------------------------------------------------

// Self-intersections: a closed UV sphere has none; pushing one vertex through the opposite side makes
// its faces cross the far ones (and only pairs that really cross are reported, sorted, smaller index first).
TEST(MeshStats, self_intersecting_faces_of_a_sphere)
{
    Mesh sphere = mrt::testing::uv_sphere(8, 12, 1.0);
    EXPECT_TRUE(self_intersecting_faces(sphere).empty());
    const Mesh::VertexHandle north(0);
    sphere.set_point(north, Mesh::Point(0, 0, -1.5)); // the pole pushed through the south cap
    const auto pairs = self_intersecting_faces(sphere);
    ASSERT_FALSE(pairs.empty());
    EXPECT_TRUE(std::is_sorted(pairs.begin(), pairs.end()));
    for (const auto& [a, b] : pairs) {
        EXPECT_LT(a, b);
        bool touches_north = false;
        for (const int f : {a, b})
            for (const auto v : sphere.fv_range(Mesh::FaceHandle(f)))
                touches_north = touches_north || v == north;
        EXPECT_TRUE(touches_north) << "faces " << a << ", " << b << " do not move";
    }
    // A subset: every face gives the same pairs; the pole's own faces alone cross nothing among themselves.
    std::vector<int> all, at_north;
    for (const auto f : sphere.faces()) {
        all.push_back(f.idx());
        for (const auto v : sphere.fv_range(f))
            if (v == north)
                at_north.push_back(f.idx());
    }
    EXPECT_EQ(self_intersecting_faces(sphere, &all), pairs);
    EXPECT_TRUE(self_intersecting_faces(sphere, &at_north).empty());
}

// A flat fan on a plane tilted off the axes (one tile of an exactly planar cloud) crosses nothing:
// with inexact predicates, faces sharing only the centre were counted as crossing pairs (QA round 28:
// 2-8 pairs in the stats of each of five random tilted planes; faces_intersect found none).
TEST(MeshStats, flat_tilted_fans_do_not_self_intersect)
{
    std::mt19937 rng(28);
    std::uniform_real_distribution<double> unit(0.0, 1.0), slope(-1.0, 1.0);
    std::size_t reported = 0;
    for (int fan = 0; fan < 40; ++fan) {
        const double a = slope(rng), b = slope(rng);
        const auto on_plane = [&](double x, double y) { return Vec3{x, y, a * x + b * y}; };
        // Outline points near the unit square's sides, sorted by angle around the centre.
        std::vector<std::pair<double, Vec3>> rim;
        for (int k = 0; k < 24; ++k) {
            const double t = unit(rng), inset = 0.003 * unit(rng);
            const double x = k % 4 == 0 ? inset : k % 4 == 1 ? 1 - inset : t;
            const double y = k % 4 == 2 ? inset : k % 4 == 3 ? 1 - inset : t;
            rim.push_back({std::atan2(y - 0.5, x - 0.5), on_plane(x, y)});
        }
        std::sort(rim.begin(), rim.end(), [](const auto& p, const auto& q) { return p.first < q.first; });
        Soup soup;
        soup.positions.push_back(on_plane(0.5 + 0.02 * unit(rng), 0.5 + 0.02 * unit(rng)));
        for (const auto& r : rim)
            soup.positions.push_back(r.second);
        const auto n = static_cast<std::uint32_t>(rim.size());
        for (std::uint32_t k = 0; k < n; ++k)
            soup.triangles.push_back({0, 1 + k, 1 + (k + 1) % n});
        const Mesh mesh = to_mesh(soup);
        const auto pairs = self_intersecting_faces(mesh);
        reported += pairs.size();
        for (const auto& [f, g] : pairs)
            EXPECT_FALSE(faces_intersect(mesh, Mesh::FaceHandle(f), Mesh::FaceHandle(g))) << fan;
    }
    EXPECT_EQ(reported, 0u);
}

// vec3.h's closest_point_on_triangle (Ericson's Voronoi regions) against brute force: the closest of a
// dense barycentric grid over the triangle is never closer than it, and at most a grid cell farther.
TEST(MeshStats, closest_point_on_triangle_matches_dense_sampling)
{
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const int n = 200;
    for (int trial = 0; trial < 200; ++trial) {
        const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)}, c{u(rng), u(rng), u(rng)};
        const Vec3 p{2 * u(rng), 2 * u(rng), 2 * u(rng)};
        const double exact = distance(p, closest_point_on_triangle(p, a, b, c));
        double sampled = std::numeric_limits<double>::infinity();
        for (int i = 0; i <= n; ++i)
            for (int j = 0; i + j <= n; ++j) {
                const double s = double(i) / n, t = double(j) / n;
                sampled = std::min(sampled, distance(p, a + (b - a) * s + (c - a) * t));
            }
        const double cell = std::max({distance(a, b), distance(b, c), distance(a, c)}) / n;
        EXPECT_LE(exact, sampled + 1e-12);
        EXPECT_GE(exact, sampled - cell);
    }
}

// A closed, randomly bumpy sphere: a twice-subdivided icosahedron with random radii.
Soup bumpy_sphere(std::uint32_t seed)
{
    Soup s = icosahedron();
    for (int level = 0; level < 2; ++level) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
        auto mid = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            const auto it = midpoint.find(key);
            if (it != midpoint.end())
                return it->second;
            const auto i = static_cast<std::uint32_t>(s.positions.size());
            s.positions.push_back(normalized(s.positions[a] + s.positions[b]));
            midpoint.emplace(key, i);
            return i;
        };
        Triangles next;
        for (const auto& t : s.triangles) {
            const std::uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
            next.push_back({t[0], ab, ca});
            next.push_back({t[1], bc, ab});
            next.push_back({t[2], ca, bc});
            next.push_back({ab, bc, ca});
        }
        s.triangles = next;
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> radius(0.7, 1.3);
    for (Vec3& p : s.positions)
        p = normalized(p) * radius(rng);
    return s;
}

// Mean, max and rms of brute-force squared distances, relative to the reported diagonal.
void expect_stats_of(const DistanceStats& d, const std::vector<double>& squared)
{
    double sum = 0, sum_sq = 0, largest = 0;
    for (const double d2 : squared) {
        sum += std::sqrt(d2);
        sum_sq += d2;
        largest = std::max(largest, std::sqrt(d2));
    }
    const double n = static_cast<double>(squared.size());
    EXPECT_NEAR(d.mean, sum / n / d.diagonal, 1e-12);
    EXPECT_NEAR(d.max, largest / d.diagonal, 1e-12);
    EXPECT_NEAR(d.rms, std::sqrt(sum_sq / n) / d.diagonal, 1e-12);
}

TEST(Distance, points_on_the_surface_are_at_zero)
{
    const Soup s = bumpy_sphere(3);
    expect_closed_genus(stats(s), 0);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<Vec3> points;
    for (const auto& t : s.triangles)
        for (int k = 0; k < 3; ++k) {
            double a = u(rng), b = u(rng);
            if (a + b > 1)
                a = 1 - a, b = 1 - b;
            const Vec3& p0 = s.positions[t[0]];
            points.push_back(p0 + (s.positions[t[1]] - p0) * a + (s.positions[t[2]] - p0) * b);
        }
    const DistanceStats d = point_to_mesh_distance(points, to_mesh(s));
    EXPECT_GT(d.diagonal, 2.0);
    EXPECT_LE(d.max, 1e-12);
    EXPECT_LE(d.mean, d.max);
    EXPECT_LE(d.rms, d.max);
}

TEST(Distance, offset_from_a_flat_square_is_exact)
{
    const Soup square{{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}}, {{0, 1, 2}, {0, 2, 3}}};
    const Mesh mesh = to_mesh(square);
    const double offset = 0.0375;
    std::vector<Vec3> points;
    for (int j = 0; j <= 10; ++j)
        for (int i = 0; i <= 10; ++i)
            points.push_back({0.2 * i, 0.2 * j, (i + j) % 2 ? offset : -offset});
    const DistanceStats d = point_to_mesh_distance(points, mesh);
    const double diagonal = std::sqrt(8.0 + 4 * offset * offset);
    EXPECT_NEAR(d.diagonal, diagonal, 1e-15);
    EXPECT_NEAR(d.mean, offset / diagonal, 1e-12);
    EXPECT_NEAR(d.max, offset / diagonal, 1e-12);
    EXPECT_NEAR(d.rms, offset / diagonal, 1e-12);

    // Beside the square the closest point is on an edge or a corner, not the plane.
    points.push_back({3, 1, 0});   // 1 from the edge x = 2
    points.push_back({-3, -4, 0}); // 5 from the corner (0, 0, 0)
    const DistanceStats e = point_to_mesh_distance(points, mesh);
    const Vec3 lo{-3, -4, -offset}, hi{3, 2, offset};
    EXPECT_NEAR(e.diagonal, norm(hi - lo), 1e-15);
    EXPECT_NEAR(e.max, 5.0 / e.diagonal, 1e-12);
    EXPECT_NEAR(e.mean, (121 * offset + 1 + 5) / 123 / e.diagonal, 1e-12);
}

// Far points: past 5% of the diagonal and `beyond` they are counted far and left out of near_mean; the
// flags found say which; given flags replace the bound, so that two meshes are compared over the same
// points (lods' levels).
TEST(Distance, far_points_are_found_or_given)
{
    const Soup square{{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}}, {{0, 1, 2}, {0, 2, 3}}};
    const Mesh mesh = to_mesh(square);
    // Heights 0.1 and 0.2 over the plane, then 1 and 5 beside it (diagonal sqrt(61 + 0.04), 5% = 0.39).
    const std::vector<Vec3> points{{0.5, 0.5, 0.1}, {1.5, 1.5, 0.2}, {3, 1, 0}, {-3, -4, 0}};
    std::vector<char> found;
    FarPoints far;
    far.found = &found;
    const DistanceStats d = point_to_mesh_distance(points, mesh, far);
    EXPECT_EQ(d.far, 2u);
    EXPECT_EQ(found, (std::vector<char>{0, 0, 1, 1}));
    EXPECT_NEAR(d.near_mean, 0.15 / d.diagonal, 1e-12);
    EXPECT_NEAR(d.mean, 6.3 / 4 / d.diagonal, 1e-12);

    far.beyond = 1.5; // raises the bound over the point 1 away
    const DistanceStats raised = point_to_mesh_distance(points, mesh, far);
    EXPECT_EQ(raised.far, 1u);
    EXPECT_EQ(found, (std::vector<char>{0, 0, 0, 1}));
    EXPECT_NEAR(raised.near_mean, 1.3 / 3 / raised.diagonal, 1e-12);

    const std::vector<char> given{0, 1, 0, 0}; // whatever the distances
    far.given = &given;
    const DistanceStats chosen = point_to_mesh_distance(points, mesh, far);
    EXPECT_EQ(chosen.far, 1u);
    EXPECT_EQ(found, given);
    EXPECT_NEAR(chosen.near_mean, 6.1 / 3 / chosen.diagonal, 1e-12);
    EXPECT_NEAR(chosen.max, 5.0 / chosen.diagonal, 1e-12);

    const std::vector<char> short_flags{0, 1};
    far.given = &short_flags;
    EXPECT_THROW(point_to_mesh_distance(points, mesh, far), InvalidInput);
}

// Median and 99th percentile are order statistics of the distances: 101 points at heights 0, 0.001, …,
// 0.1 over the square (shuffled in x, y) put them at exactly 0.050 and 0.099.
TEST(Distance, median_and_p99_are_exact_order_statistics)
{
    const Mesh mesh = to_mesh(Soup{{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}}, {{0, 1, 2}, {0, 2, 3}}});
    std::vector<Vec3> points;
    for (int k = 0; k <= 100; ++k)
        points.push_back({0.1 + 0.018 * ((k * 37) % 101), 0.1 + 0.018 * ((k * 59) % 101), 0.001 * k});
    const DistanceStats d = point_to_mesh_distance(points, mesh);
    EXPECT_NEAR(d.median, 0.050 / d.diagonal, 1e-12);
    EXPECT_NEAR(d.p99, 0.099 / d.diagonal, 1e-12);
    EXPECT_NEAR(d.max, 0.100 / d.diagonal, 1e-12);
}

TEST(Distance, matches_brute_force_on_a_random_closed_mesh)
{
    const Soup s = bumpy_sphere(11);
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> u(-1.6, 1.6);
    std::vector<Vec3> points(200);
    for (Vec3& p : points)
        p = {u(rng), u(rng), u(rng)};
    std::vector<double> squared;
    for (const Vec3& p : points) {
        double best = INFINITY;
        for (const auto& t : s.triangles)
            best = std::min(best, squared_distance(p, closest_point_on_triangle(p, s.positions[t[0]],
                                                                                s.positions[t[1]],
                                                                                s.positions[t[2]])));
        squared.push_back(best);
    }
    const DistanceStats d = point_to_mesh_distance(points, to_mesh(s));
    const Vec3 lo = std::accumulate(points.begin(), points.end(), points[0], [](Vec3 a, Vec3 b) { return min(a, b); });
    const Vec3 hi = std::accumulate(points.begin(), points.end(), points[0], [](Vec3 a, Vec3 b) { return max(a, b); });
    EXPECT_DOUBLE_EQ(d.diagonal, norm(hi - lo));
    EXPECT_GT(*std::max_element(squared.begin(), squared.end()), 0.01);  // the check is not vacuous
    expect_stats_of(d, squared);
}

// What mesh_to_point_distance measures from: the mesh's vertices and face centroids.
std::vector<Vec3> samples_of(const Soup& s)
{
    std::vector<Vec3> samples = s.positions;
    for (const auto& t : s.triangles)
        samples.push_back((s.positions[t[0]] + s.positions[t[1]] + s.positions[t[2]]) / 3.0);
    return samples;
}

// The squared distance of each sample to its nearest point, every pair tried.
std::vector<double> brute_force_nearest(const std::vector<Vec3>& samples, const std::vector<Vec3>& points)
{
    std::vector<double> squared;
    for (const Vec3& q : samples) {
        double best = INFINITY;
        for (const Vec3& p : points)
            best = std::min(best, squared_distance(p, q));
        squared.push_back(best);
    }
    return squared;
}

TEST(Distance, mesh_to_points_matches_brute_force)
{
    const Soup s = bumpy_sphere(17);
    const Mesh mesh = to_mesh(s);
    // The mesh's own vertices and centroids are all at distance zero.
    const std::vector<Vec3> samples = samples_of(s);
    EXPECT_EQ(mesh_to_point_distance(mesh, samples).max, 0.0);

    std::mt19937 rng(19);
    std::uniform_real_distribution<double> u(-1.4, 1.4);
    std::vector<Vec3> points(300);
    for (Vec3& p : points)
        p = {u(rng), u(rng), u(rng)};
    expect_stats_of(mesh_to_point_distance(mesh, points), brute_force_nearest(samples, points));
}

// 3,000 points near the unit sphere and scattered around it, in a hierarchy of leaves of a few points.
Hierarchy sphere_and_scatter(std::mt19937& rng)
{
    std::uniform_real_distribution<double> u(-1.4, 1.4);
    PointCloud cloud;
    for (int i = 0; i < 3000; ++i) {
        const Vec3 p{u(rng), u(rng), u(rng)};
        cloud.positions.push_back(i % 3 == 0 ? p : p / norm(p) * (1.0 + 0.02 * u(rng)));
    }
    BuildOptions options;
    options.denoise = BuildOptions::Denoise::Off;
    return build_hierarchy(cloud, options);
}

TEST(Distance, mesh_to_points_through_a_hierarchy_matches_brute_force)
{
    const Soup s = bumpy_sphere(17);
    const Mesh mesh = to_mesh(s);
    const std::vector<Vec3> samples = samples_of(s);
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> u(-1.4, 1.4);
    const Hierarchy h = sphere_and_scatter(rng);
    ASSERT_GT(h.nodes.size(), 100u);
    expect_stats_of(mesh_to_point_distance(mesh, h, h.cloud.positions), brute_force_nearest(samples, h.cloud.positions));
    // Other positions of the same points (as raw_positions are), moved out of the stored boxes: the
    // search must bound them by their own.
    std::vector<Vec3> moved = h.cloud.positions;
    for (Vec3& p : moved)
        p = p * 1.3 + Vec3{0.2 * u(rng), 0.0, 0.0};
    expect_stats_of(mesh_to_point_distance(mesh, h, moved), brute_force_nearest(samples, moved));
    EXPECT_THROW(mesh_to_point_distance(mesh, h, std::vector<Vec3>(moved.begin(), moved.end() - 1)), InvalidInput);
}

// squared_nearest_point_distances, per query: the nearest point's squared distance (brute force);
// with a near-enough bound, any point's within it where the nearest lies within it, and the nearest's
// exactly where it does not (the tile-error floor of lod_set.cpp reads only how far beyond a bound).
TEST(Distance, nearest_points_through_a_hierarchy_with_and_without_a_bound)
{
    std::mt19937 rng(50);
    std::uniform_real_distribution<double> u(-1.4, 1.4);
    const Hierarchy h = sphere_and_scatter(rng);
    std::vector<Vec3> queries(500);
    for (Vec3& q : queries)
        q = Vec3{u(rng), u(rng), u(rng)} * 1.5;
    const std::vector<double> exact = brute_force_nearest(queries, h.cloud.positions);
    EXPECT_EQ(squared_nearest_point_distances(h, h.cloud.positions, queries, 1), exact);
    EXPECT_EQ(squared_nearest_point_distances(h, h.cloud.positions, queries, 3), exact);
    std::vector<double> bound(queries.size());
    for (std::size_t k = 0; k < queries.size(); ++k)
        bound[k] = exact[k] * (k % 2 == 0 ? 3.0 : 0.5); // half within reach, half beyond
    const std::vector<double> bounded = squared_nearest_point_distances(h, h.cloud.positions, queries, 2, &bound);
    std::size_t early = 0;
    for (std::size_t k = 0; k < queries.size(); ++k) {
        if (exact[k] <= bound[k]) {
            EXPECT_LE(bounded[k], bound[k]) << k;
            EXPECT_GE(bounded[k], exact[k]) << k;
            early += bounded[k] > exact[k] ? 1 : 0;
        } else {
            EXPECT_EQ(bounded[k], exact[k]) << k;
        }
    }
    EXPECT_GT(early, 0u); // some searches did end before the nearest point
    // Started at a node of each query's (its nearest point's leaf, one of its ancestors, a node
    // elsewhere, or none): the same guarantees, with the bound and without.
    std::vector<std::int32_t> leaf_of(h.cloud.size(), -1);
    for (std::size_t id = 0; id < h.nodes.size(); ++id)
        if (h.nodes[id].is_leaf())
            for (std::uint32_t i = h.nodes[id].begin; i < h.nodes[id].end; ++i)
                leaf_of[i] = static_cast<std::int32_t>(id);
    std::vector<std::int32_t> first(queries.size());
    for (std::size_t k = 0; k < queries.size(); ++k) {
        std::size_t nearest = 0;
        for (std::size_t i = 1; i < h.cloud.size(); ++i)
            if (squared_norm(h.cloud.positions[i] - queries[k]) < squared_norm(h.cloud.positions[nearest] - queries[k]))
                nearest = i;
        std::int32_t node = leaf_of[nearest];
        if (k % 4 == 1)
            node = h.nodes[static_cast<std::size_t>(node)].parent;
        first[k] = k % 4 == 2 ? static_cast<std::int32_t>(h.nodes.size() - 1 - k % 7) : k % 4 == 3 ? -1 : node;
    }
    EXPECT_EQ(squared_nearest_point_distances(h, h.cloud.positions, queries, 2, nullptr, &first), exact);
    const std::vector<double> started = squared_nearest_point_distances(h, h.cloud.positions, queries, 1, &bound, &first);
    for (std::size_t k = 0; k < queries.size(); ++k) {
        if (exact[k] <= bound[k]) {
            EXPECT_LE(started[k], bound[k]) << k;
            EXPECT_GE(started[k], exact[k]) << k;
        } else {
            EXPECT_EQ(started[k], exact[k]) << k; // a node elsewhere: found from the root
        }
    }
    // A copy of the cloud's positions takes the other path (each node's box computed from the points
    // given, not the one stored with it): the same results, to the bit.
    const std::vector<Vec3> copy = h.cloud.positions;
    EXPECT_EQ(squared_nearest_point_distances(h, copy, queries, 1, &bound, &first), started);
    EXPECT_EQ(squared_nearest_point_distances(h, copy, queries, 2, &bound), bounded);
    std::vector<std::int32_t> wrong = first;
    wrong[3] = static_cast<std::int32_t>(h.nodes.size());
    EXPECT_THROW(squared_nearest_point_distances(h, h.cloud.positions, queries, 1, &bound, &wrong), InvalidInput);
    wrong.pop_back();
    EXPECT_THROW(squared_nearest_point_distances(h, h.cloud.positions, queries, 1, &bound, &wrong), InvalidInput);
    const std::vector<double> short_bound(queries.size() - 1, 1.0);
    EXPECT_THROW(squared_nearest_point_distances(h, h.cloud.positions, queries, 1, &short_bound), InvalidInput);
    EXPECT_THROW(squared_nearest_point_distances(h, std::vector<Vec3>(3), queries), InvalidInput);
}

// has_point_within, per query: whether the nearest point (brute force) lies within the radius, from the
// root and from a node of each query's (its nearest point's leaf, a node elsewhere, none).
TEST(Distance, point_within_a_radius_through_a_hierarchy)
{
    std::mt19937 rng(51);
    std::uniform_real_distribution<double> u(-1.4, 1.4);
    const Hierarchy h = sphere_and_scatter(rng);
    std::vector<Vec3> queries(600);
    for (Vec3& q : queries)
        q = Vec3{u(rng), u(rng), u(rng)} * 1.5;
    const std::vector<double> exact = brute_force_nearest(queries, h.cloud.positions);
    std::vector<double> radii(queries.size());
    std::vector<char> expected(queries.size());
    std::size_t yes = 0;
    for (std::size_t k = 0; k < queries.size(); ++k) {
        // Half a hair beyond the nearest point, half a hair short of it; the first 20 exactly at it.
        const double d = std::sqrt(exact[k]);
        radii[k] = k < 20 ? d : d * (k % 2 == 0 ? 1.001 : 0.999);
        expected[k] = k < 20 || k % 2 == 0 ? 1 : 0;
        if (k < 20) // a radius whose square rounds below the nearest squared distance says no
            expected[k] = radii[k] * radii[k] >= exact[k] ? 1 : 0;
        yes += expected[k];
    }
    ASSERT_GT(yes, 250u);
    ASSERT_LT(yes, 350u);
    EXPECT_EQ(has_point_within(h, queries, radii, nullptr, 1), expected);
    EXPECT_EQ(has_point_within(h, queries, radii, nullptr, 3), expected);
    std::vector<std::int32_t> first(queries.size(), -1);
    for (std::size_t k = 0; k < queries.size(); ++k)
        if (k % 3 != 2)
            first[k] = static_cast<std::int32_t>(k % 3 == 0 ? h.nodes.size() - 1 - k % 11 : k % h.nodes.size());
    EXPECT_EQ(has_point_within(h, queries, radii, &first, 2), expected);
    const std::vector<double> none(queries.size(), -1.0), nan(queries.size(), std::nan(""));
    EXPECT_EQ(has_point_within(h, queries, none), std::vector<char>(queries.size(), 0));
    EXPECT_EQ(has_point_within(h, queries, nan), std::vector<char>(queries.size(), 0));
    std::vector<std::int32_t> wrong = first;
    wrong[5] = static_cast<std::int32_t>(h.nodes.size());
    EXPECT_THROW(has_point_within(h, queries, radii, &wrong), InvalidInput);
    wrong.pop_back();
    EXPECT_THROW(has_point_within(h, queries, radii, &wrong), InvalidInput);
    EXPECT_THROW(has_point_within(h, queries, std::vector<double>(3, 1.0)), InvalidInput);
}

TEST(Distance, degenerate_input)
{
    const Mesh mesh = to_mesh(tetrahedron());
    const DistanceStats none = point_to_mesh_distance({}, mesh);
    EXPECT_EQ(none.max, 0.0);
    EXPECT_EQ(none.diagonal, 0.0);
    EXPECT_THROW(point_to_mesh_distance({{0, 0, 0}}, mesh), InvalidInput);  // zero diagonal
    EXPECT_THROW(point_to_mesh_distance({{0, 0, 0}, {1, 0, 0}}, Mesh{}), InvalidInput);
    EXPECT_THROW(point_to_mesh_distance({{0, 0, 0}, {NAN, 0, 0}}, mesh), InvalidInput);
    EXPECT_THROW(mesh_to_point_distance(mesh, {}), InvalidInput);
    EXPECT_EQ(mesh_to_point_distance(Mesh{}, {{0, 0, 0}}).max, 0.0);
    // Closest points need no extent: one point, or several at one position (the probes of a one-point
    // tile, QA round 32), each get their closest point; only a non-finite point or no faces is refused.
    const Soup t = tetrahedron();
    const Vec3 outside = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0 * 3.0;
    for (const std::vector<Vec3>& same : {std::vector<Vec3>{outside}, std::vector<Vec3>(5, outside)}) {
        const std::vector<ClosestPoint> c = closest_points(same, mesh);
        ASSERT_EQ(c.size(), same.size());
        for (const ClosestPoint& p : c) {
            EXPECT_GE(p.face, 0);
            EXPECT_LT(norm(p.point - outside), norm(outside)); // on the tetrahedron, nearer than its centre
        }
    }
    EXPECT_THROW(closest_points({{0, 0, 0}, {NAN, 0, 0}}, mesh), InvalidInput);
    EXPECT_THROW(closest_points({{0, 0, 0}}, Mesh{}), InvalidInput);
}

// A deleted face is no face of the mesh (QA round 59: faces_intersect took one and said false).
TEST(MeshStats, faces_intersect_refuses_a_deleted_face)
{
    Mesh mesh = testing::uv_sphere(8, 16, 1.0);
    mesh.request_face_status();
    mesh.request_edge_status();
    mesh.request_vertex_status();
    mesh.request_halfedge_status();
    EXPECT_FALSE(faces_intersect(mesh, Mesh::FaceHandle(3), Mesh::FaceHandle(40)));
    mesh.delete_face(Mesh::FaceHandle(3), false);
    EXPECT_THROW(faces_intersect(mesh, Mesh::FaceHandle(3), Mesh::FaceHandle(40)), InvalidInput);
}

// corners_intersect skips the exact predicates for faces whose boxes are apart (QA round 78: capping
// holes on trial tested every pair of a cap's faces). Against triangles_meet on pairs that are apart,
// that overlap, that cross, and that touch where their boxes touch (a corner on the other's face or
// corner at the box's edge: contact, so they meet), on a small grid so that ties are common.
TEST(MeshStats, corners_intersect_agrees_with_the_exact_test_where_boxes_are_apart_or_touch)
{
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> coordinate(0, 4);
    std::size_t meeting = 0, apart_boxes = 0, touching_boxes = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        Mesh mesh;
        std::array<Vec3, 3> a, b;
        std::array<Mesh::VertexHandle, 3> fa, fb;
        for (int k = 0; k < 3; ++k) {
            a[static_cast<std::size_t>(k)] = {double(coordinate(rng)), double(coordinate(rng)), double(coordinate(rng))};
            b[static_cast<std::size_t>(k)] = {double(coordinate(rng)) + 2.0, double(coordinate(rng)), double(coordinate(rng))};
        }
        for (int k = 0; k < 3; ++k) {
            const Vec3& p = a[static_cast<std::size_t>(k)];
            const Vec3& q = b[static_cast<std::size_t>(k)];
            fa[static_cast<std::size_t>(k)] = mesh.add_vertex(Mesh::Point(p.x, p.y, p.z));
            fb[static_cast<std::size_t>(k)] = mesh.add_vertex(Mesh::Point(q.x, q.y, q.z));
        }
        const auto hi = [](const std::array<Vec3, 3>& t) { return std::max({t[0].x, t[1].x, t[2].x}); };
        const auto lo = [](const std::array<Vec3, 3>& t) { return std::min({t[0].x, t[1].x, t[2].x}); };
        apart_boxes += hi(a) < lo(b) ? 1 : 0;
        touching_boxes += hi(a) == lo(b) ? 1 : 0;
        const bool expected = triangles_meet(a, b);
        meeting += expected ? 1 : 0;
        ASSERT_EQ(corners_intersect(mesh, fa, fb), expected) << "trial " << trial;
        ASSERT_EQ(corners_intersect(mesh, fb, fa), expected) << "trial " << trial;
    }
    // The cases the shortcut decides and those it must leave to the exact test all occurred.
    EXPECT_GT(apart_boxes, 100u);
    EXPECT_GT(touching_boxes, 100u);
    EXPECT_GT(meeting, 100u);
}

} // namespace
} // namespace mrt
