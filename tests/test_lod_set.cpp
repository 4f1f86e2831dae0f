// Tests of lod_set.h (levels and the 3D Tiles tile tree) and, end to end, of what `mrtile` writes for
// the acceptance command: a Draco tileset of the Stanford bunny that real clients accept.
#include "formats/lod_tileset.h"
#include "formats/read_points.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/georef.h"
#include "libmrtile/lod_set.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/shapes.h"
#include "npm/node_clients.h"
#include "tests/terrain_fixtures.h"
#include "tests/test_dir.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <sys/wait.h>

namespace mrt {
namespace {

const Hierarchy& torus()
{
    static const Hierarchy h = [] {
        PointCloud c = shapes::torus(40000);
        shapes::add_noise(c, 0.0005);
        return build_hierarchy(c);
    }();
    return h;
}

// Levels: tolerance halves, geometric error never rises with the level and ends at 0, every level is a
// valid manifold mesh, and the measured error of a coarser level is never below a finer one's.
TEST(LodSet, levels_are_consistent)
{
    LodSetOptions o;
    o.tileset = false;
    o.max_tile_triangles = 4096;
    std::vector<std::pair<std::size_t, std::size_t>> progress;
    o.progress = [&](std::size_t done, std::size_t total) { progress.push_back({done, total}); };
    const LodSet set = make_lod_set(torus(), o);
    ASSERT_GE(set.levels.size(), 3u);
    EXPECT_TRUE(set.tiles.empty());
    // One progress call per level, counting up to the number of levels.
    ASSERT_EQ(progress.size(), set.levels.size());
    for (std::size_t i = 0; i < progress.size(); ++i)
        EXPECT_EQ(progress[i], std::make_pair(i + 1, set.levels.size()));
    double previous_mean = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < set.levels.size(); ++l) {
        const LodLevel& level = set.levels[l];
        SCOPED_TRACE(l);
        if (l > 0) {
            EXPECT_LT(level.tolerance, set.levels[l - 1].tolerance);
            EXPECT_LE(level.geometric_error, set.levels[l - 1].geometric_error);
            EXPECT_GT(level.cut.size(), set.levels[l - 1].cut.size());
        }
        // No level that adds a few tiles for a whole mesh (this torus: 2,833, 3,400, then its 3,403 leaves).
        if (l > 1) {
            EXPECT_GE(static_cast<double>(level.cut.size()), 1.5 * static_cast<double>(set.levels[l - 1].cut.size()));
        }
        const TopologyStats t = topology_stats(level.mesh);
        EXPECT_EQ(t.nonmanifold_edges, 0u);
        EXPECT_EQ(t.nonmanifold_vertices, 0u);
        const double mean = point_to_mesh_distance(torus().cloud.positions, level.mesh).mean;
        EXPECT_LE(mean, previous_mean * 1.05); // a finer level is never (meaningfully) worse
        previous_mean = mean;
    }
    EXPECT_EQ(set.levels.back().geometric_error, 0.0);
    EXPECT_EQ(set.levels.back().cut.size(), torus().leaf_count());

    LodSetOptions explicit_levels;
    explicit_levels.tileset = false;
    explicit_levels.tolerances = {0.01, 0.004, 0.001};
    EXPECT_EQ(make_lod_set(torus(), explicit_levels).levels.size(), 3u);
    explicit_levels.tolerances = {0.001, 0.01};
    EXPECT_THROW(make_lod_set(torus(), explicit_levels), InvalidInput);
    LodSetOptions no_levels; // automatic levels, at most none (was two, silently: QA, session 19)
    no_levels.tileset = false;
    no_levels.max_levels = 0;
    EXPECT_THROW(make_lod_set(torus(), no_levels), InvalidInput);
}

// QA round qa3: an explicit level count past the leaves halved the tolerance to 0 and then pushed zero
// tolerances until memory ran out (levels = SIZE_MAX never returned). Levels finer than the finest cut
// are skipped anyway, so asking for any number past them gives the same levels.
TEST(LodSet, a_huge_level_count_ends_at_the_finest_cut)
{
    const Hierarchy h = build_hierarchy(shapes::sphere(3000));
    LodSetOptions many, all;
    many.tileset = all.tileset = false;
    many.levels = 60;
    all.levels = std::numeric_limits<std::size_t>::max();
    const std::vector<LodLevel> a = make_lod_levels(h, many);
    const std::vector<LodLevel> b = make_lod_levels(h, all);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_EQ(a[k].cut, b[k].cut);
        EXPECT_EQ(a[k].tolerance, b[k].tolerance);
    }
    EXPECT_EQ(b.back().cut.size(), cut_by_tolerance(h, 0.0).size());
    LodSetOptions infinite; // refused as the levels' own option, not by the cut it would reach
    infinite.tolerances = {std::numeric_limits<double>::infinity(), 0.01};
    try {
        make_lod_levels(h, infinite);
        ADD_FAILURE() << "no exception";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("lods: tolerances"), std::string::npos) << e.what();
    }
}

// Unevenly sampled: a torus whose x < 0 half has a tenth of the points. Level 0 (a best-N cut) used to
// carry the tolerance of its worst tile while far coarser tiles would meet it elsewhere; the first
// halving was then no finer (128 tiles at 0.0154, 130 at 0.0077) and `lods` kept one level. The levels
// must nest: every node of a level lies at or below a node of the one before (QA run, session 13).
TEST(LodSet, uneven_sampling_still_gives_nested_levels)
{
    const PointCloud all = shapes::torus(110000);
    PointCloud c;
    for (std::size_t i = 0; i < all.size(); ++i)
        if (all.positions[i].x > 0 || i % 10 == 0)
            c.positions.push_back(all.positions[i]);
    const Hierarchy h = build_hierarchy(c);
    LodSetOptions o;
    o.tileset = false;
    o.first_level_triangles = 4096; // as `mrtile lods`
    const LodSet set = make_lod_set(h, o);
    ASSERT_GE(set.levels.size(), 4u);
    for (std::size_t l = 1; l < set.levels.size(); ++l) {
        SCOPED_TRACE(l);
        const Cut& coarse = set.levels[l - 1].cut;
        EXPECT_GT(set.levels[l].cut.size(), coarse.size());
        // Non-increasing (near the leaves a tile that cannot be split keeps the largest distance), and
        // falling from level 0 to level 1.
        EXPECT_LE(set.levels[l].geometric_error, set.levels[l - 1].geometric_error);
        if (l == 1) {
            EXPECT_LT(set.levels[l].geometric_error, set.levels[l - 1].geometric_error);
        }
        for (const std::int32_t id : set.levels[l].cut) {
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            const bool below = std::any_of(coarse.begin(), coarse.end(), [&](std::int32_t up) {
                const Node& u = h.nodes[static_cast<std::size_t>(up)];
                return u.begin <= n.begin && n.end <= u.end;
            });
            EXPECT_TRUE(below) << "node " << id;
        }
    }
    // Level 0 is the tolerance cut at its own tolerance.
    const Cut again = cut_by_tolerance(h, set.levels[0].tolerance);
    EXPECT_EQ(std::set<std::int32_t>(again.begin(), again.end()),
              std::set<std::int32_t>(set.levels[0].cut.begin(), set.levels[0].cut.end()));
}

// No level is in more pieces or has more boundary loops than the finest: the rocker arm's level 0 (94
// tiles) was in 5 pieces with 469 open edges while every finer level was closed (QA, session 19); it
// is cut again at a finer tolerance, and the levels still nest.
// The levels `mrtile lods` makes: no tile tree, level 0 of at most three quarters of 4,096 triangles.
LodSet lods_as_the_cli_makes(const Hierarchy& h)
{
    LodSetOptions o;
    o.tileset = false;
    o.first_level_triangles = 4096;
    return make_lod_set(h, o);
}

TEST(LodSet, coarse_levels_are_no_more_broken_than_the_finest)
{
    const Hierarchy h = build_hierarchy(read_points(MRTILE_SHARED_DATA "/rocker-arm.obj"));
    const LodSet set = lods_as_the_cli_makes(h);
    ASSERT_GE(set.levels.size(), 3u);
    const TopologyStats finest = topology_stats(set.levels.back().mesh);
    for (std::size_t l = 0; l < set.levels.size(); ++l) {
        SCOPED_TRACE(l);
        const TopologyStats t = topology_stats(set.levels[l].mesh);
        EXPECT_LE(t.components, finest.components);
        EXPECT_LE(t.boundary_loops, finest.boundary_loops);
        if (l > 0) {
            EXPECT_GT(set.levels[l].cut.size(), set.levels[l - 1].cut.size());
            EXPECT_LT(set.levels[l].tolerance, set.levels[l - 1].tolerance);
        }
        // The growth rule of automatic levels holds after the mending too (QA round 77: a mended
        // level kept 3,099 tiles before the finest's 3,132; here level 1 had 189 to level 0's 136).
        if (l > 0 && l + 1 < set.levels.size()) {
            const auto tiles = static_cast<double>(set.levels[l].cut.size());
            EXPECT_GE(static_cast<double>(set.levels[l + 1].cut.size()), 1.5 * tiles);
            EXPECT_GE(tiles, 1.5 * static_cast<double>(set.levels[0].cut.size()));
        }
    }
    // The level made again is the tolerance cut at its own tolerance, as every automatic level is.
    const Cut again = cut_by_tolerance(h, set.levels[0].tolerance);
    EXPECT_EQ(std::set<std::int32_t>(again.begin(), again.end()),
              std::set<std::int32_t>(set.levels[0].cut.begin(), set.levels[0].cut.end()));
}

// The bunny's automatic levels 0 and 1 had holes in the ears (loops of 59-71 edges where every finer
// level is closed: tiles straddling the thin ear, QA round 72), while their loop counts were no more
// than the finest level's. Now no level has a loop away from the finest level's borders (measured here
// by brute force: most of a loop's vertices farther than three of the level's median edges from every
// border vertex of the finest mesh), the levels still nest, level 0 still fits its budget and is no
// further from the points than before.
TEST(LodSet, coarse_levels_have_no_holes_where_the_finest_has_none)
{
    const Hierarchy h = build_hierarchy(read_points(MRTILE_SHARED_DATA "/bun_zipper.ply"));
    const LodSet set = lods_as_the_cli_makes(h);
    ASSERT_GE(set.levels.size(), 4u);
    const Mesh& finest = set.levels.back().mesh;
    std::vector<Vec3> border;
    for (const auto v : finest.vertices())
        if (finest.is_boundary(v))
            border.push_back(to_vec3(finest.point(v)));
    ASSERT_FALSE(border.empty()); // the bunny scan is open at its base
    for (std::size_t l = 0; l + 1 < set.levels.size(); ++l) {
        SCOPED_TRACE(l);
        const Mesh& m = set.levels[l].mesh;
        std::vector<double> lengths;
        for (const auto e : m.edges())
            lengths.push_back(m.calc_edge_length(e));
        std::sort(lengths.begin(), lengths.end());
        const double reach = 3.0 * lengths[lengths.size() / 2];
        std::vector<char> seen(m.n_halfedges(), 0);
        for (const auto start : m.halfedges()) {
            if (!m.is_boundary(start) || seen[static_cast<std::size_t>(start.idx())])
                continue;
            std::size_t size = 0, far = 0;
            for (auto he = start; !seen[static_cast<std::size_t>(he.idx())]; he = m.next_halfedge_handle(he)) {
                seen[static_cast<std::size_t>(he.idx())] = 1;
                const Vec3 p = to_vec3(m.point(m.to_vertex_handle(he)));
                double nearest = std::numeric_limits<double>::infinity();
                for (const Vec3& b : border)
                    nearest = std::min(nearest, distance(b, p));
                ++size;
                far += nearest > reach;
            }
            EXPECT_LE(2 * far, size) << "a loop of " << size << " edges, " << far << " of its vertices away from the finest borders";
        }
        // Nested: every node of this level's cut lies at or above nodes of the next.
        std::set<std::int32_t> coarse(set.levels[l].cut.begin(), set.levels[l].cut.end());
        std::set<std::int32_t> covered;
        for (const std::int32_t id : set.levels[l + 1].cut)
            for (std::int32_t n = id; n >= 0; n = h.nodes[static_cast<std::size_t>(n)].parent)
                if (coarse.count(n)) {
                    covered.insert(n);
                    break;
                }
        EXPECT_EQ(covered, coarse);
        EXPECT_LT(set.levels[l].cut.size(), set.levels[l + 1].cut.size());
    }
    EXPECT_LE(set.levels[0].mesh.n_faces(), 4096u * 3 / 4);
    // Level 0 mended is still level 0: coarser than level 1, and its error no lower than level 1's.
    EXPECT_GE(set.levels[0].geometric_error, set.levels[1].geometric_error);
}

// The Draco grid of a tileset spans its vertices, not its root's box: a stray point 50 radii away (in
// the root box, left out of every mesh) no longer makes the grid 25 times coarser.
TEST(LodSet, draco_grid_spans_the_meshes_not_a_stray_point)
{
    PointCloud c = shapes::sphere(5000);
    c.positions.push_back({50, 0, 0});
    const Hierarchy h = build_hierarchy(c);
    LodSetOptions o;
    o.max_tile_triangles = 2048;
    const LodSet set = make_lod_set(h, o);
    ASSERT_FALSE(set.tiles.empty());
    EXPECT_LT(set.tiles[0].box.largest_side(), 3.0); // its content's (before QA round 57: over 50)
    const QuantizationGrid grid = tileset_grid(set);
    EXPECT_LT(grid.range, 3.0); // the sphere and its skirts (before: over 50)
    EXPECT_GT(grid.range, 1.9);
    for (const LodTile& t : set.tiles)
        for (const auto v : t.mesh.vertices()) {
            const Vec3 p = to_vec3(t.mesh.point(v));
            for (double d : {p.x - grid.min.x, p.y - grid.min.y, p.z - grid.min.z}) {
                EXPECT_GE(d, 0.0);
                EXPECT_LE(d, grid.range);
            }
        }
}

// Stray points the surface leaves out (their own cluster, no fan) set no tile's box, error or skirt
// (QA round 57: a unit sphere of 20k points with five strays within 50 had skirts 16 deep through the
// sphere, a geometric error of 8.4 on every coarse tile and a root box 60 wide). Every tile's box and
// content stay within the sphere and its skirts, and the errors are those of the sphere alone.
TEST(LodSet, strays_left_out_set_no_box_error_or_skirt)
{
    PointCloud c = shapes::sphere(20000);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> far(-50.0, 50.0);
    for (int k = 0; k < 5; ++k)
        c.positions.push_back({far(rng), far(rng), far(rng)});
    const Hierarchy h = build_hierarchy(c);
    const Hierarchy clean = build_hierarchy(shapes::sphere(20000));
    LodSetOptions o;
    o.max_tile_triangles = 1000;
    const LodSet set = make_lod_set(h, o), reference = make_lod_set(clean, o);
    ASSERT_GT(set.tiles.size(), 1u);
    EXPECT_LT(set.tiles[0].geometric_error, 2.0 * reference.tiles[0].geometric_error + 1e-9);
    for (const LodLevel& level : set.levels)
        EXPECT_LT(level.max_plane_distance, 0.2);
    // Skirts hang at most twice the level's largest plane distance (under 0.2) from the surface.
    const double reach = 1.45;
    for (const LodTile& t : set.tiles) {
        EXPECT_LT(t.geometric_error, 0.5);
        if (t.mesh.n_vertices() == 0)
            continue;
        for (const double side : {t.box.min.x, t.box.min.y, t.box.min.z, t.box.max.x, t.box.max.y, t.box.max.z})
            EXPECT_LT(std::abs(side), 1.1 * reach);
        for (const auto v : t.mesh.vertices())
            EXPECT_LT(norm(to_vec3(t.mesh.point(v))), 1.1 * reach);
    }
}

// No two levels mesh the same cut (QA round 57: the bunny with three stray points, as `mrtile lods`
// cuts it, had levels 0 and 1 at the same 258 tiles, and its tileset two byte-identical root tiles).
TEST(LodSet, no_level_repeats_the_one_before)
{
    PointCloud c = read_points(MRTILE_SHARED_DATA "/bun_zipper.ply");
    for (const Vec3& stray : {Vec3{0.4, 0.1, 0.0}, Vec3{-0.3, 0.5, 0.2}, Vec3{0.0, -0.4, -0.3}})
        c.positions.push_back(stray - c.origin);
    const Hierarchy h = build_hierarchy(c);
    LodSetOptions o;
    o.tileset = false;
    o.first_level_triangles = 4096; // as `mrtile lods`
    const std::vector<LodLevel> levels = make_lod_levels(h, o);
    ASSERT_GE(levels.size(), 3u);
    for (std::size_t k = 0; k + 1 < levels.size(); ++k) {
        Cut a = levels[k].cut, b = levels[k + 1].cut;
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        EXPECT_NE(a, b) << k;
        EXPECT_LT(levels[k].mesh.n_faces(), levels[k + 1].mesh.n_faces()) << k;
    }
}

// One Draco grid spans a whole tileset: 14 bits gave a survey 20 km wide 1.4 m steps, and its finest
// tiles (3 cm from the points on average) were 0.3-0.6 m off (QA round 38). The bits are the fewest
// that keep a vertex's quantization (up to √3/2 of a step) under half the finest level's accuracy (the
// mean RMS plane distance of its tiles); a terrain 1 unit wide keeps 14.
TEST(LodSet, a_wide_survey_gets_the_draco_bits_its_finest_level_needs)
{
    const auto bits_for = [](double width, double relief, double sigma) {
        PointCloud c = shapes::smooth_height_field(20000);
        std::mt19937 rng(7);
        std::normal_distribution<double> noise(0.0, sigma);
        for (Vec3& p : c.positions)
            p = Vec3{p.x * width, p.y * width, p.z * relief + noise(rng)};
        const Hierarchy h = build_hierarchy(c);
        LodSetOptions o;
        o.max_tile_triangles = 4096;
        const LodSet set = make_lod_set(h, o);
        const QuantizationGrid grid = tileset_grid(set);
        double sum = 0.0, points = 0.0;
        for (const std::int32_t id : set.levels.back().cut) {
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            sum += n.rms_plane_distance * static_cast<double>(n.count());
            points += static_cast<double>(n.count());
        }
        const double accuracy = sum / points;
        const int bits = tileset_position_bits(h, set, grid);
        const auto moves = [&](int b) { return 0.5 * std::sqrt(3.0) * grid.range / (std::ldexp(1.0, b) - 1.0); };
        EXPECT_LE(moves(bits), 0.5 * accuracy);
        if (bits > 14) {
            EXPECT_GT(moves(bits - 1), 0.5 * accuracy); // the fewest that do
        }
        EXPECT_THROW(tileset_position_bits(h, set, grid, 1.0, 0), InvalidInput);
        EXPECT_THROW(tileset_position_bits(h, set, grid, 0.0), InvalidInput);
        // Model units in feet on a grid in metres: the accuracy is 3.3 times smaller there, 1-2 bits more.
        return std::pair{bits, tileset_position_bits(h, set, grid, 0.3048)};
    };
    EXPECT_EQ(bits_for(1.0, 0.2, 1e-3).first, 14);
    const auto [wide, in_feet] = bits_for(20000.0, 50.0, 0.02); // 20 km, 50 m of relief, 2 cm of noise
    EXPECT_GT(wide, 14);
    EXPECT_GE(in_feet, wide + 1);
    EXPECT_LE(in_feet, wide + 2);
}

// A noisy sample's LOD set ends at its noise floor, not at the leaves (levels below it would mesh
// noise: blobs that break the surface into pieces), and its first level is no finer than that.
// QA round 50: a small noisy model got a level 0 nearly as fine as its finest level (a 40k-point wedge:
// 907 and 946 tiles), so its tileset held about the same mesh twice: level 0 was cut at the tolerance
// of the finest cut, which is coarser where the finest ends at the noise floor. Where the finest mesh
// fits level 0's budget it is now the one level; otherwise every automatic level, level 0 included, has
// at most 1/1.5 of the next one's tiles.
TEST(LodSet, a_model_whose_finest_mesh_fits_level_0_is_one_level)
{
    PointCloud c = shapes::sphere(10000);
    shapes::add_noise(c, 0.002);
    const Hierarchy h = build_hierarchy(c);
    LodSetOptions o;
    o.tileset = false;
    const std::vector<LodLevel> one = make_lod_levels(h, o);
    ASSERT_EQ(one.size(), 1u);
    EXPECT_EQ(one.front().cut, cut_by_tolerance(h, 0.0));
    EXPECT_LE(one.front().mesh.n_faces(), o.max_tile_triangles * 3 / 4);
    o.first_level_triangles = 1024; // level 0 at most 768 faces: the finest (about 7,000) does not fit
    const std::vector<LodLevel> several = make_lod_levels(h, o);
    ASSERT_GE(several.size(), 2u);
    EXPECT_LE(several.front().mesh.n_faces(), 768u);
    EXPECT_EQ(several.back().cut, cut_by_tolerance(h, 0.0));
    for (std::size_t k = 0; k + 1 < several.size(); ++k)
        EXPECT_GE(static_cast<double>(several[k + 1].cut.size()), 1.5 * static_cast<double>(several[k].cut.size())) << k;
}

TEST(LodSet, noisy_sample_ends_at_the_noise_floor)
{
    PointCloud c = shapes::sphere(30000);
    shapes::add_noise(c, 0.02);
    const Hierarchy h = build_hierarchy(c);
    ASSERT_GT(max_noise_floor(h), 0.0);
    LodSetOptions o;
    o.tileset = false;
    const LodSet set = make_lod_set(h, o);
    ASSERT_FALSE(set.levels.empty());
    EXPECT_EQ(set.levels.back().cut, cut_by_tolerance(h, 0.0));
    for (const LodLevel& level : set.levels) {
        const TopologyStats t = topology_stats(level.mesh);
        EXPECT_EQ(t.boundary_loops, 0u);
        EXPECT_EQ(t.components, 1u);
    }
}

// Whatever the thread count, the levels are the same meshes.
TEST(LodSet, thread_count_does_not_change_the_result)
{
    LodSetOptions o;
    o.tileset = false;
    o.max_tile_triangles = 4096;
    o.threads = 1;
    const LodSet one = make_lod_set(torus(), o);
    o.threads = 3;
    const LodSet three = make_lod_set(torus(), o);
    ASSERT_EQ(one.levels.size(), three.levels.size());
    for (std::size_t l = 0; l < one.levels.size(); ++l) {
        const Mesh& a = one.levels[l].mesh;
        const Mesh& b = three.levels[l].mesh;
        ASSERT_EQ(a.n_vertices(), b.n_vertices());
        ASSERT_EQ(a.n_faces(), b.n_faces());
        for (const auto v : a.vertices())
            ASSERT_EQ(a.point(v), b.point(Mesh::VertexHandle(v.idx())));
        for (const auto f : a.faces()) {
            auto fa = a.cfv_begin(f);
            auto fb = b.cfv_begin(Mesh::FaceHandle(f.idx()));
            for (int k = 0; k < 3; ++k, ++fa, ++fb)
                ASSERT_EQ(fa->idx(), fb->idx());
        }
    }
}

// A tile's geometric error is its own: the largest node_error of its level's cut nodes in its region
// (brute force here), never above its level's, raised to its children's; the finest level's tiles get 0. On a
// surface whose roughness varies (a sphere with one rippled cap) tiles of the smooth part are below
// their level's worst, so a client refines them later; with the level's error on every tile (as
// before) they refined as early as the roughest.
// By brute force: each vertex of a level mesh with the cut node it stands for (its cluster id) and how
// far beyond two of that node's point spacings it lies from the nearest sample point (vertex_deviation
// in lod_set.cpp; negative within reach).
std::vector<std::pair<std::int32_t, double>> stand_off(const Hierarchy& h, const Mesh& mesh)
{
    std::vector<std::pair<std::int32_t, double>> out;
    OpenMesh::VPropHandleT<int> cluster;
    if (!mesh.get_property_handle(cluster, kVertexCluster))
        return out;
    for (const auto v : mesh.vertices()) {
        const auto& q = mesh.point(v);
        double nearest = std::numeric_limits<double>::infinity();
        for (const Vec3& p : h.cloud.positions)
            nearest = std::min(nearest, squared_norm(p - Vec3{q[0], q[1], q[2]}));
        const int node = mesh.property(cluster, v);
        out.push_back({node, std::sqrt(nearest) - 2.0 * node_spacing(h.nodes[static_cast<std::size_t>(node)])});
    }
    return out;
}

// Each tile's expected error by brute force: its own (the largest node_error and stand-off of its
// level's cut nodes in its region that the level's mesh shows, at most its level's; 0 at the finest level) and that raised to its
// children's (children come after their parents, so from the last tile back).
struct ExpectedTileErrors
{
    std::vector<double> own, raised;
};

ExpectedTileErrors expected_tile_errors(const Hierarchy& h, const LodSet& set)
{
    // Per level (the finest aside) and cut node: the farthest of its vertices off the sample.
    std::vector<std::vector<double>> deviation(set.levels.size(), std::vector<double>(h.nodes.size(), 0.0));
    for (std::size_t l = 0; l + 1 < set.levels.size(); ++l) {
        const auto off = stand_off(h, set.levels[l].mesh);
        EXPECT_FALSE(off.empty());
        for (const auto& [node, d] : off)
            deviation[l][static_cast<std::size_t>(node)] = std::max(deviation[l][static_cast<std::size_t>(node)], d);
    }
    ExpectedTileErrors e{std::vector<double>(set.tiles.size(), 0.0), std::vector<double>(set.tiles.size(), 0.0)};
    for (std::size_t k = set.tiles.size(); k-- > 0;) {
        const LodTile& t = set.tiles[k];
        const LodLevel& level = set.levels[t.level];
        const Node& region = h.nodes[static_cast<std::size_t>(t.region)];
        const std::vector<char> shown = nodes_in_mesh(h, level.mesh); // tiles the surface left out count not
        double own = 0.0;
        for (std::int32_t id : level.cut) {
            const Node& n = h.nodes[static_cast<std::size_t>(id)];
            if (shown[static_cast<std::size_t>(id)] && n.begin >= region.begin && n.end <= region.end)
                own = std::max({own, node_error(n), deviation[t.level][static_cast<std::size_t>(id)]});
        }
        e.own[k] = t.level + 1 == set.levels.size() ? 0.0 : std::min(own, level.geometric_error);
        e.raised[k] = e.own[k];
        for (const std::size_t c : t.children)
            e.raised[k] = std::max(e.raised[k], e.raised[c]);
    }
    return e;
}

TEST(LodSet, tiles_carry_their_own_geometric_error)
{
    PointCloud bumpy = shapes::sphere(30000);
    for (Vec3& p : bumpy.positions)
        if (p.z > 0.6)
            p = p * (1.0 + 0.02 * std::sin(40.0 * p.x) * std::sin(40.0 * p.y));
    const Hierarchy h = build_hierarchy(bumpy);
    LodSetOptions o;
    o.max_tile_triangles = 1500;
    const LodSet set = make_lod_set(h, o);
    ASSERT_GT(set.tiles.size(), 6u);
    const ExpectedTileErrors expected = expected_tile_errors(h, set);
    std::size_t smoother = 0;
    for (std::size_t k = 0; k < set.tiles.size(); ++k) {
        const LodTile& t = set.tiles[k];
        EXPECT_EQ(t.geometric_error, expected.raised[k]) << "tile " << k << " level " << t.level;
        if (t.level + 1 < set.levels.size() && t.geometric_error < set.levels[t.level].geometric_error)
            ++smoother;
    }
    EXPECT_GT(smoother, 0u);
}

// A tile's geometric error is at least how far its level's vertices stand off the sample (QA round 57:
// a corridor 200 x 2 x 3 m sampled on its floor, ceiling and walls; its 1,000-triangle tileset's level 0
// has a dozen faces whose fitted vertices lie metres from the walls, while its node errors, points
// against their tile planes, gave about 1 m). Checked by brute force on every tile of a coarse level
// (parents raised to their children's since QA round 62, so no parent's error caps it); the
// corridor's root must exceed its node errors, with or without the tile tree.
// Every tile of a level but the finest claims at least the farthest stand-off (`off`, per level) of the
// vertices that stand for cut nodes in its region (its content, skirts aside). Returns the tiles checked.
std::size_t expect_errors_cover_stand_off(const Hierarchy& h, const LodSet& set,
                                          const std::vector<std::vector<std::pair<std::int32_t, double>>>& off)
{
    std::size_t checked = 0;
    for (std::size_t k = 0; k < set.tiles.size(); ++k) {
        const LodTile& t = set.tiles[k];
        if (t.level + 1 == set.levels.size())
            continue;
        const Node& region = h.nodes[static_cast<std::size_t>(t.region)];
        double farthest = 0.0;
        for (const auto& [node, d] : off[t.level]) {
            const Node& n = h.nodes[static_cast<std::size_t>(node)];
            if (region.begin <= n.begin && n.end <= region.end)
                farthest = std::max(farthest, d);
        }
        EXPECT_GE(t.geometric_error, farthest) << "tile " << k << " level " << t.level;
        ++checked;
    }
    return checked;
}

TEST(LodSet, tile_errors_cover_how_far_their_vertices_stand_off_the_sample)
{
    std::mt19937 rng(57);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    PointCloud corridor;
    for (int i = 0; i < 60000; ++i) {
        const double side = u(rng), x = 200.0 * u(rng), a = u(rng);
        corridor.positions.push_back(side < 0.25   ? Vec3{x, 2.0 * a, 0.0}
                                     : side < 0.5  ? Vec3{x, 2.0 * a, 3.0}
                                     : side < 0.75 ? Vec3{x, 0.0, 3.0 * a}
                                                   : Vec3{x, 2.0, 3.0 * a});
    }
    const Hierarchy h = build_hierarchy(corridor);
    LodSetOptions o;
    o.max_tile_triangles = 1000;
    const std::vector<LodLevel> levels = make_lod_levels(h, o);
    const LodSet set = make_lod_tiles(h, levels, o);
    ASSERT_GT(set.levels.size(), 2u);
    // Without the tile tree (as `mrtile lods` asks) the levels carry the same floored errors.
    LodSetOptions bare = o;
    bare.tileset = false;
    const LodSet levels_only = make_lod_tiles(h, levels, bare);
    ASSERT_EQ(levels_only.levels.size(), set.levels.size());
    for (std::size_t l = 0; l < set.levels.size(); ++l)
        EXPECT_EQ(levels_only.levels[l].geometric_error, set.levels[l].geometric_error) << l;
    // Per level: each vertex's distance off the sample, with the cut node it stands for.
    std::vector<std::vector<std::pair<std::int32_t, double>>> off(set.levels.size());
    for (std::size_t l = 0; l + 1 < set.levels.size(); ++l)
        off[l] = stand_off(h, set.levels[l].mesh);
    double node_errors = 0.0, root_off = 0.0;
    for (const std::int32_t id : set.levels[0].cut)
        node_errors = std::max(node_errors, node_error(h.nodes[static_cast<std::size_t>(id)]));
    for (const auto& [node, d] : off[0])
        root_off = std::max(root_off, d);
    EXPECT_GT(root_off, 1.5 * node_errors); // the case: node errors alone understate the root
    EXPECT_GE(set.tiles[0].geometric_error, root_off);
    EXPECT_GE(set.levels[0].geometric_error, root_off);
    EXPECT_GT(expect_errors_cover_stand_off(h, set, off), 3u);
    for (std::size_t l = 1; l < set.levels.size(); ++l)
        EXPECT_LE(set.levels[l].geometric_error, set.levels[l - 1].geometric_error);
}

// A finer level's vertices can stand farther off the sample than a coarser one's in the same region
// (QA round 62: a sphere whose cap above z = 0.5 is sampled 20 times sparser: tiles of levels 1-3 had
// vertices up to 0.089 off, capped at the root's own 0.036). The parent is raised to its children's,
// not the children lowered to their parent's: no tile claims less than its vertices' stand-off.
TEST(LodSet, a_parent_is_raised_to_its_childrens_error_not_the_children_lowered)
{
    std::mt19937 rng(62);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    PointCloud sphere;
    while (sphere.positions.size() < 30000) {
        const double z = 2.0 * u(rng) - 1.0, t = 2.0 * M_PI * u(rng), r = std::sqrt(1.0 - z * z);
        if (z > 0.5 && u(rng) > 0.05)
            continue;
        sphere.positions.push_back({r * std::cos(t), r * std::sin(t), z});
    }
    const Hierarchy h = build_hierarchy(sphere);
    std::size_t raised = 0; // tiles above their own error: the case
    for (const std::size_t budget : {256u, 1000u}) {
        LodSetOptions o;
        o.max_tile_triangles = budget;
        const LodSet set = make_lod_set(h, o);
        ASSERT_GT(set.levels.size(), 2u);
        const ExpectedTileErrors expected = expected_tile_errors(h, set);
        for (std::size_t k = 0; k < set.tiles.size(); ++k) {
            EXPECT_EQ(set.tiles[k].geometric_error, expected.raised[k]) << "budget " << budget << " tile " << k;
            raised += expected.raised[k] > expected.own[k];
        }
        std::vector<std::vector<std::pair<std::int32_t, double>>> off(set.levels.size());
        for (std::size_t l = 0; l + 1 < set.levels.size(); ++l)
            off[l] = stand_off(h, set.levels[l].mesh);
        EXPECT_GT(expect_errors_cover_stand_off(h, set, off), 3u);
    }
    EXPECT_GT(raised, 0u);
}

// Strays far off that the finest level does not show set no level's error (QA round 63, L4: birds 5-50 m
// over a terrain gave levels 0-2 errors of 50, 47 and 15 m where their meshes lie within a metre of the
// ground, so a client refined from kilometres away; the points' plane distances and the coverage gaps
// of bird clusters split off the ground carried them up the tree). A level's error is how far it can
// differ from the finest level: the ground's own error, what the finest shows of the birds, and what
// the level or a finer one shows of them (here a coarse level's 24 m tent up to a bird). A building
// that the finest level shows keeps at least every error its points give (the brute-force errors).
TEST(LodSet, strays_the_finest_level_leaves_out_set_no_error_a_building_does)
{
    const auto ground = test::rolling_ground;
    std::mt19937 rng(60);
    const test::TerrainWithBirds scene = test::terrain_with_birds(rng);
    const PointCloud& terrain = scene.clean;
    const PointCloud& birds = scene.birds;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    // A 10 x 10 x 15 m block standing on the ground at (60, 60), its walls and roof sampled as densely.
    PointCloud building = terrain;
    const double base = ground(60.0, 60.0) - 3.0;
    for (int i = 0; i < 7000; ++i) {
        const double a = 10.0 * unit(rng), b = 15.0 * unit(rng), side = unit(rng);
        building.positions.push_back(side < 0.15   ? Vec3{60.0 + a, 60.0, base + b}
                                     : side < 0.3  ? Vec3{60.0 + a, 70.0, base + b}
                                     : side < 0.45 ? Vec3{60.0, 60.0 + a, base + b}
                                     : side < 0.6  ? Vec3{70.0, 60.0 + a, base + b}
                                                   : Vec3{60.0 + a, 60.0 + 10.0 * unit(rng), base + 15.0});
    }
    LodSetOptions o;
    o.max_tile_triangles = 1000;
    const LodSet clean = make_lod_set(build_hierarchy(terrain), o);
    const Hierarchy hb = build_hierarchy(birds), hh = build_hierarchy(building);
    const LodSet with_birds = make_lod_set(hb, o), with_building = make_lod_set(hh, o);
    const std::size_t last = with_birds.levels.size() - 1;
    ASSERT_GT(last, 1u);
    const auto farthest_off_ground = [&](const Mesh& m) {
        double off = 0.0;
        for (const auto v : m.vertices()) {
            const auto& p = m.point(v);
            off = std::max(off, std::abs(p[2] - ground(p[0], p[1])));
        }
        return off;
    };
    std::vector<double> shows(last + 1);
    for (std::size_t l = 0; l <= last; ++l)
        shows[l] = farthest_off_ground(with_birds.levels[l].mesh);
    EXPECT_LT(shows[last], 10.0);
    const double ground_error = clean.levels[0].geometric_error;
    EXPECT_LT(ground_error, 5.0); // the coarsest plane over a 10 m relief
    for (std::size_t l = 0; l < last; ++l) {
        const double e = with_birds.levels[l].geometric_error;
        const double finer_show = *std::max_element(shows.begin() + static_cast<std::ptrdiff_t>(l), shows.end() - 1);
        EXPECT_LT(e, ground_error + shows[last] + finer_show) << "level " << l;
        EXPECT_GE(e, shows[l] - shows[last] - ground_error) << "level " << l;
    }
    EXPECT_LT(with_birds.tiles[0].geometric_error, 30.0);
    // What the coarse levels show still counts: every tile covers its vertices' stand-off.
    std::vector<std::vector<std::pair<std::int32_t, double>>> off(last + 1);
    for (std::size_t l = 0; l < last; ++l)
        off[l] = stand_off(hb, with_birds.levels[l].mesh);
    EXPECT_GT(expect_errors_cover_stand_off(hb, with_birds, off), 3u);
    // The building is shown: no error is below what its points give (the brute-force errors; a small
    // piece of wall that a coarse level meshes and the finest leaves out can raise one).
    const ExpectedTileErrors expected = expected_tile_errors(hh, with_building);
    ASSERT_EQ(expected.raised.size(), with_building.tiles.size());
    for (std::size_t k = 0; k < with_building.tiles.size(); ++k)
        EXPECT_GE(with_building.tiles[k].geometric_error, expected.raised[k]) << "tile " << k;
    EXPECT_GT(with_building.tiles[0].geometric_error, 2.0 * ground_error); // the block stands out
}

// The tile tree: budgets honoured, errors non-increasing, boxes nested, children's regions partition
// their parent's region, and the leaves are at the finest level.
TEST(LodSet, tile_tree_is_a_valid_replace_hierarchy)
{
    LodSetOptions o;
    o.max_tile_triangles = 3000;
    const LodSet set = make_lod_set(torus(), o);
    const Hierarchy& h = torus();
    ASSERT_GT(set.tiles.size(), 4u);
    std::size_t leaves = 0;
    for (const LodTile& t : set.tiles) {
        EXPECT_LE(t.mesh.n_faces(), o.max_tile_triangles);
        const Node& region = h.nodes[static_cast<std::size_t>(t.region)];
        if (t.children.empty()) {
            ++leaves;
            EXPECT_TRUE(t.level == set.levels.size() - 1 || t.geometric_error == 0.0) << t.level;
            continue;
        }
        EXPECT_GT(t.geometric_error, 0.0);
        std::uint32_t next = region.begin;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;
        for (std::size_t c : t.children) {
            const LodTile& child = set.tiles[c];
            EXPECT_EQ(child.level, t.level + 1);
            EXPECT_LE(child.geometric_error, t.geometric_error);
            for (int k = 0; k < 3; ++k) {
                EXPECT_GE(child.box.min[k], t.box.min[k]);
                EXPECT_LE(child.box.max[k], t.box.max[k]);
            }
            const Node& r = h.nodes[static_cast<std::size_t>(child.region)];
            ranges.push_back({r.begin, r.end});
        }
        std::sort(ranges.begin(), ranges.end());
        for (const auto& r : ranges) {
            EXPECT_EQ(r.first, next);
            next = r.second;
        }
        EXPECT_EQ(next, region.end);
    }
    EXPECT_GT(leaves, 1u);
    // Tiles of the finest level own every face of the finest level mesh once (skirts and the faces
    // they overlap their neighbours by aside), and overlap some.
    std::size_t faces = 0, overlap = 0;
    for (const LodTile& t : set.tiles)
        if (t.level == set.levels.size() - 1) {
            faces += t.mesh.n_faces() - t.skirt_faces - t.overlap_faces;
            overlap += t.overlap_faces;
        }
    EXPECT_EQ(faces, set.levels.back().mesh.n_faces());
    EXPECT_GT(overlap, 0u);
}

// A tile whose geometric error is 0 (every cut node in its region exactly planar) ends its branch: a
// client's screen-space error for it is 0 at any distance, so children under it would never load (QA
// round 57: fandisk's flat faces at a budget of 128 had two such chains). A box's faces are exactly
// planar, so its coarse levels have such tiles; the rest of the tree is as before, children covering
// their parent's points.
TEST(LodSet, a_tile_without_error_has_no_children)
{
    const Hierarchy h = build_hierarchy(shapes::box_surface({1.0, 2.0, 0.5}, 30000 / 7.0));
    LodSetOptions o;
    o.max_tile_triangles = 128;
    const LodSet set = make_lod_set(h, o);
    ASSERT_GT(set.levels.size(), 2u);
    std::size_t exact_above_finest = 0, refined = 0;
    for (const LodTile& t : set.tiles) {
        if (t.level + 1 < set.levels.size() && t.geometric_error == 0.0) {
            ++exact_above_finest;
            EXPECT_TRUE(t.children.empty()) << "tile of level " << t.level << " region " << t.region;
        }
        if (!t.children.empty())
            ++refined;
    }
    EXPECT_GT(exact_above_finest, 0u);
    EXPECT_GT(refined, 0u);
}

// --max-tile-triangles counts the skirts (QA round 28b): regions were chosen by their faces alone,
// within three quarters of the budget, and a small region's skirt (two faces per border edge) can
// outgrow the quarter left: at 256 the bunny had 102 of 424 tiles over it, up to 343 faces, at 64 63%
// of them. Now a tile exceeds the budget only where its region cannot be split at its level (a leaf,
// or a node whose children lie below the level's cut) or it is the root (the coarsest level whole).
TEST(LodSet, tiles_with_their_skirts_fit_the_triangle_budget)
{
    const Hierarchy& h = torus();
    for (const std::size_t budget : {64u, 256u, 1000u}) {
        SCOPED_TRACE(budget);
        LodSetOptions o;
        o.max_tile_triangles = budget;
        const LodSet set = make_lod_set(h, o);
        std::vector<std::vector<char>> at_or_above(set.levels.size(), std::vector<char>(h.nodes.size(), 0));
        for (std::size_t l = 0; l < set.levels.size(); ++l)
            for (std::int32_t id : set.levels[l].cut)
                for (std::int32_t n = id; n >= 0 && !at_or_above[l][static_cast<std::size_t>(n)];
                     n = h.nodes[static_cast<std::size_t>(n)].parent)
                    at_or_above[l][static_cast<std::size_t>(n)] = 1;
        std::size_t over = 0, skirted = 0;
        for (std::size_t t = 1; t < set.tiles.size(); ++t) {
            const LodTile& tile = set.tiles[t];
            skirted += tile.skirt_faces > 0;
            // The skirts are the content's last faces (the glTF writer puts them in a primitive of
            // their own): each has a corner hung below the surface faces' vertices, and two or one on it.
            ASSERT_LT(tile.skirt_faces, std::max<std::size_t>(tile.mesh.n_faces(), 1)) << "tile " << t;
            const std::size_t surface_faces = tile.mesh.n_faces() - tile.skirt_faces;
            std::set<std::array<double, 3>> on_surface;
            for (std::size_t f = 0; f < surface_faces; ++f)
                for (const auto v : tile.mesh.fv_range(Mesh::FaceHandle(static_cast<int>(f)))) {
                    const auto p = tile.mesh.point(v);
                    on_surface.insert({p[0], p[1], p[2]});
                }
            for (std::size_t f = surface_faces; f < tile.mesh.n_faces(); ++f) {
                int on = 0;
                for (const auto v : tile.mesh.fv_range(Mesh::FaceHandle(static_cast<int>(f)))) {
                    const auto p = tile.mesh.point(v);
                    on += on_surface.count({p[0], p[1], p[2]}) > 0;
                }
                EXPECT_TRUE(on == 1 || on == 2) << "tile " << t << ": face " << f << " of the skirts has " << on
                                                << " corners on the surface";
            }
            if (tile.mesh.n_faces() <= budget)
                continue;
            const Node& region = h.nodes[static_cast<std::size_t>(tile.region)];
            const bool splittable = !region.is_leaf() && at_or_above[tile.level][static_cast<std::size_t>(region.left)] &&
                                    at_or_above[tile.level][static_cast<std::size_t>(region.right)];
            over += splittable;
            EXPECT_FALSE(splittable) << "tile " << t << ": " << tile.mesh.n_faces() << " faces, "
                                     << tile.skirt_faces << " of them skirt";
        }
        EXPECT_GT(skirted, set.tiles.size() / 2);
        EXPECT_EQ(over, 0u);
    }
}

// A hill in UTM coordinates (a sphere of radius 400 m, 3 degrees west of its zone's central meridian
// at 47 N) placed on the globe: every vertex, mapped into the content's ENU frame and back out by the
// root transform (the frame's inverse, built separately as a matrix), lands where the CRS puts it; the
// boxes still nest; normals turn with the grid (convergence about 2.2 degrees here).
TEST(LodSet, georeference_puts_every_vertex_where_the_crs_says)
{
    PointCloud c = shapes::sphere(8000, 400.0);
    shapes::translate(c, {272000.0, 5206000.0, 300.0});
    recenter(c);
    const Hierarchy h = build_hierarchy(c);
    LodSetOptions o;
    o.max_tile_triangles = 600;
    const LodSet original = make_lod_set(h, o);
    ASSERT_GT(original.tiles.size(), 3u);
    LodSet set = original;
    const std::optional<ProjectedCrs> crs = crs_from_epsg(32633);
    ASSERT_TRUE(crs.has_value());
    const GeoPlacement placed = georeference(set, h.cloud.origin, h.nodes.front().box, *crs);
    EXPECT_NEAR(placed.anchor.latitude_deg, 47.0, 0.1);
    EXPECT_NEAR(placed.anchor.longitude_deg, 12.0, 0.1);
    const auto& m = placed.root_transform; // column-major
    std::size_t checked = 0;
    double largest_turn = 0, smallest_turn = 180;
    for (std::size_t t = 0; t < set.tiles.size(); ++t) {
        const Mesh& before = original.tiles[t].mesh;
        const Mesh& after = set.tiles[t].mesh;
        ASSERT_EQ(before.n_vertices(), after.n_vertices());
        EXPECT_EQ(set.tiles[t].geometric_error, original.tiles[t].geometric_error); // metres already
        for (const auto v : after.vertices()) {
            const Vec3 q = h.cloud.origin + to_vec3(before.point(v));
            const Vec3 want = geodetic_to_ecef(crs->projection.ellipsoid, projected_to_geodetic(crs->projection, q.x, q.y, q.z));
            const Vec3 e = to_vec3(after.point(v));
            const Vec3 got{m[0] * e.x + m[4] * e.y + m[8] * e.z + m[12], m[1] * e.x + m[5] * e.y + m[9] * e.z + m[13],
                           m[2] * e.x + m[6] * e.y + m[10] * e.z + m[14]};
            ASSERT_LT(norm(got - want), 1e-3) << "tile " << t;
            for (int k = 0; k < 3; ++k) {
                EXPECT_GE(e[k], set.tiles[t].box.min[k]);
                EXPECT_LE(e[k], set.tiles[t].box.max[k]);
            }
            // The turn of a normal seen from above: grid north rotated to true north.
            const Vec3 n0 = to_vec3(before.normal(v)), n1 = to_vec3(after.normal(v));
            if (std::hypot(n0.x, n0.y) > 0.5) { // steep: the Earth's curvature tilts the up part too
                const double turn = std::remainder(std::atan2(n1.y, n1.x) - std::atan2(n0.y, n0.x), 2 * kPi) * 180.0 / kPi;
                largest_turn = std::max(largest_turn, turn);
                smallest_turn = std::min(smallest_turn, turn);
            }
            EXPECT_NEAR(norm(n1), 1.0, 1e-9);
            ++checked;
        }
        for (std::size_t child : set.tiles[t].children)
            for (int k = 0; k < 3; ++k) {
                EXPECT_GE(set.tiles[child].box.min[k], set.tiles[t].box.min[k]);
                EXPECT_LE(set.tiles[child].box.max[k], set.tiles[t].box.max[k]);
            }
    }
    EXPECT_GT(checked, 500u);
    // West of the central meridian in the northern hemisphere grid north points east of true north:
    // every direction turns by the same angle, atan(tan(dlon) sin(lat)): about 2.2 degrees here.
    EXPECT_NEAR(smallest_turn, largest_turn, 0.05);
    EXPECT_NEAR(std::abs(largest_turn), 2.2, 0.15);
}

// The structural tileset check, the Khronos validator (no errors or warnings) and draco3d (every
// content decodes) on a Draco tileset of at least `min_contents` contents.
void expect_clients_pass(const std::filesystem::path& tiles, int min_contents)
{
    const nlohmann::json results = testing::run_node_script("tileset_check.mjs", {tiles.string()});
    ASSERT_EQ(results.size(), 1u);
    const nlohmann::json& r = results[0];
    EXPECT_TRUE(r["problems"].empty()) << r["problems"].dump(1);
    EXPECT_GE(r["contents"].get<int>(), min_contents);
    for (const nlohmann::json& v : r["validation"]) {
        EXPECT_EQ(v["errors"], 0) << v.dump(1);
        EXPECT_EQ(v["warnings"], 0) << v.dump(1);
    }
    EXPECT_EQ(r["draco"].size(), r["contents"].get<std::size_t>());
}

// The acceptance command, through the CLI, checked by the Khronos validator, draco3d and the
// structural tileset check.
TEST(LodSet, bunny_draco_tileset_passes_real_clients)
{
    const auto dir = testing::fresh_test_dir("lod_set");
    const std::string command = std::string(MRTILE_CLI) + " reconstruct " + MRTILE_SHARED_DATA +
                                "/bun_zipper.ply -o " + (dir / "tiles").string() + " --format 3dtiles --draco -q >" +
                                (dir / "out.txt").string() + " 2>&1";
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
    expect_clients_pass(dir / "tiles", 2);
}

// A tileset placed on the globe by its CRS passes the same clients: the transformed contents validate,
// Draco decodes them, and the recomputed boxes still nest (a torus of 100 m in UTM zone 33N).
TEST(LodSet, georeferenced_draco_tileset_passes_real_clients)
{
    const auto dir = testing::fresh_test_dir("lod_set");
    PointCloud c = shapes::torus(20000, 100.0, 35.0);
    {
        std::ofstream out(dir / "utm.xyz");
        out.precision(10);
        for (const Vec3& p : c.positions)
            out << 470000.0 + p.x << ' ' << 5200000.0 + p.y << ' ' << 300.0 + p.z << '\n';
    }
    const std::string command = std::string(MRTILE_CLI) + " reconstruct " + (dir / "utm.xyz").string() + " -o " +
                                (dir / "tiles").string() + " --format 3dtiles --draco --crs EPSG:32633 " +
                                "--max-tile-triangles 2000 -q >" + (dir / "out.txt").string() + " 2>&1";
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
    expect_clients_pass(dir / "tiles", 3);
}

// What a viewer shows of a tileset when it refines tiles where `fine` holds (their box) and not
// elsewhere: REPLACE refinement lets a tile of any level sit beside a neighbour of any other.
void shown_tiles(const LodSet& set, std::size_t t, const std::function<bool(const BoundingBox&)>& fine,
                 std::vector<std::size_t>& out)
{
    const LodTile& tile = set.tiles[t];
    if (tile.children.empty() || !fine(tile.box)) {
        out.push_back(t);
        return;
    }
    for (const std::size_t c : tile.children)
        shown_tiles(set, c, fine, out);
}

struct Triangle
{
    Vec3 a, b, c;
};

// The first triangle a ray meets (from `from` along `dir`), and whether it faces the ray: -1 none,
// 1 front, 0 back. Edges count as inside, so a ray along a shared edge meets both faces.
int first_hit(const std::vector<Triangle>& triangles, const std::vector<std::size_t>& candidates, const Vec3& from,
              const Vec3& dir)
{
    double best = std::numeric_limits<double>::infinity();
    int facing = -1;
    for (const std::size_t k : candidates) {
        const Triangle& t = triangles[k];
        const Vec3 e1 = t.b - t.a, e2 = t.c - t.a;
        const Vec3 p = cross(dir, e2);
        const double det = dot(e1, p);
        if (std::abs(det) < 1e-12)
            continue;
        const Vec3 s = from - t.a;
        const double u = dot(s, p) / det;
        const Vec3 q = cross(s, e1);
        const double v = dot(dir, q) / det;
        const double along = dot(e2, q) / det;
        constexpr double slack = 1e-9;
        if (u < -slack || v < -slack || u + v > 1 + slack || along <= 0 || along >= best)
            continue;
        best = along;
        facing = dot(cross(e1, e2), dir) < 0 ? 1 : 0;
    }
    return facing;
}

// QA round 68 (the tilesets in CesiumJS and three.js): a smooth terrain showed the background through
// slivers along tile borders where a coarse tile sat beside tiles three levels finer. A skirt hung as
// deep as twice its own level's plane distances, a few centimetres at the finest level, while the
// coarse neighbour's surface lay up to its own error (metres) below; and the strip along a border that
// one level's faces give to one side and the other level's to the other was held by neither tile.
// Here a clean terrain's tileset is shown fine on one side of a line and as coarse as the tree allows
// on the other, and rays come down straight and at 30 and 45 degrees over the whole terrain: each must
// first meet a face that looks at it (the surface, or a skirt's outer side), never the back of one (it
// went through a crack) or nothing. Before: 1,322 of 96,468 rays, now 1; both remedies are
// needed (measured per side on a 0.5 m grid of straight rays: the deeper skirts alone left 0.9-1.7%
// through, with overlaps around the cut nodes' vertices only 0-0.14%, the full overlaps with the old
// skirts 19 of 31,684 on one side, and 4 oblique rays).
TEST(LodSet, skirts_close_the_cracks_between_tiles_of_any_two_levels)
{
    std::mt19937 rng(68);
    std::uniform_real_distribution<double> u(0.0, 100.0);
    PointCloud c;
    for (int i = 0; i < 30000; ++i) {
        const double x = u(rng), y = u(rng);
        c.positions.push_back({x, y, 2.0 * test::rolling_ground(x, y)});
    }
    const Hierarchy h = build_hierarchy(c);
    LodSetOptions o;
    o.max_tile_triangles = 256;
    const LodSet set = make_lod_set(h, o);
    ASSERT_GE(set.levels.size(), 4u);
    const std::vector<std::function<bool(const BoundingBox&)>> sides = {
        [](const BoundingBox& b) { return b.min.x < 50; }, [](const BoundingBox& b) { return b.max.x > 50; },
        [](const BoundingBox& b) { return b.min.y < 50; }, [](const BoundingBox& b) { return b.max.y > 50; }};
    std::size_t rays = 0, through = 0, mixed = 0;
    for (std::size_t side = 0; side < sides.size(); ++side) {
        std::vector<std::size_t> shown;
        shown_tiles(set, 0, sides[side], shown);
        std::set<std::size_t> levels;
        for (const std::size_t t : shown)
            levels.insert(set.tiles[t].level);
        mixed += *levels.rbegin() >= *levels.begin() + 3; // a tile beside one three levels finer, at least
        // The shown triangles, binned on a 2 m grid of the plane by their boxes.
        std::vector<Triangle> triangles;
        for (const std::size_t t : shown) {
            const Mesh& m = set.tiles[t].mesh;
            for (const auto f : m.faces()) {
                std::array<Vec3, 3> p;
                int k = 0;
                for (const auto v : m.fv_range(f))
                    p[static_cast<std::size_t>(k++)] = to_vec3(m.point(v));
                triangles.push_back({p[0], p[1], p[2]});
            }
        }
        constexpr double cell = 2.0;
        constexpr int cells = 60; // -10 .. 110 m
        auto bin_of = [](double x) { return std::clamp(static_cast<int>(std::floor((x + 10.0) / cell)), 0, cells - 1); };
        std::vector<std::vector<std::size_t>> bins(static_cast<std::size_t>(cells * cells));
        for (std::size_t k = 0; k < triangles.size(); ++k) {
            const Triangle& t = triangles[k];
            for (int i = bin_of(std::min({t.a.x, t.b.x, t.c.x})); i <= bin_of(std::max({t.a.x, t.b.x, t.c.x})); ++i)
                for (int j = bin_of(std::min({t.a.y, t.b.y, t.c.y})); j <= bin_of(std::max({t.a.y, t.b.y, t.c.y})); ++j)
                    bins[static_cast<std::size_t>(i * cells + j)].push_back(k);
        }
        // Straight down on a 1 m grid: every ray meets the surface (before the overlaps, 1-2% went
        // through the strip that neither level's tile held).
        for (double x = 6.0; x < 95.0; x += 1.0)
            for (double y = 6.0; y < 95.0; y += 1.0) {
                ++rays;
                through += first_hit(triangles, bins[static_cast<std::size_t>(bin_of(x) * cells + bin_of(y))], Vec3{x, y, 50.0},
                                     Vec3{0, 0, -1}) != 1;
            }
        for (const double pitch_degrees : {30.0, 45.0})
            for (int azimuth = 0; azimuth < 8; ++azimuth) {
                const double pitch = pitch_degrees * M_PI / 180.0, turn = azimuth * M_PI / 4.0 + 0.1;
                const Vec3 dir{std::cos(pitch) * std::cos(turn), std::cos(pitch) * std::sin(turn), -std::sin(pitch)};
                for (double x = 6.0; x < 95.0; x += 2.5)
                    for (double y = 6.0; y < 95.0; y += 2.5) {
                        // From over the highest ground (2 x 5.5 m) down to 10 m under the target: the
                        // bins the ray's shadow crosses, in half-cell steps.
                        const Vec3 target{x, y, 2.0 * test::rolling_ground(x, y)};
                        const Vec3 from = target - dir * ((12.0 - target.z) / std::sin(pitch));
                        const double reach = (22.0 - target.z) / std::sin(pitch);
                        // A ray that crosses the terrain's outer border can pass under a coarse level's
                        // edge there, where no skirt hangs (nor should: nothing is beside it), or beyond
                        // it where that level's outline lies inside the sample's.
                        const Vec3 to = from + dir * reach;
                        if (std::min({from.x, from.y, to.x, to.y}) < 0 || std::max({from.x, from.y, to.x, to.y}) > 100)
                            continue;
                        std::vector<std::size_t> candidates;
                        int last = -1;
                        for (double along = 0; along <= reach; along += cell / 2) {
                            const Vec3 at = from + dir * along;
                            const int bin = bin_of(at.x) * cells + bin_of(at.y);
                            if (bin == last)
                                continue;
                            last = bin;
                            for (int di = -1; di <= 1; ++di) // neighbours too: the half-cell steps skip corners
                                for (int dj = -1; dj <= 1; ++dj) {
                                    const int i = std::clamp(bin_of(at.x) + di, 0, cells - 1), j = std::clamp(bin_of(at.y) + dj, 0, cells - 1);
                                    const auto& in = bins[static_cast<std::size_t>(i * cells + j)];
                                    candidates.insert(candidates.end(), in.begin(), in.end());
                                }
                        }
                        std::sort(candidates.begin(), candidates.end());
                        candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
                        ++rays;
                        through += first_hit(triangles, candidates, from, dir) != 1;
                    }
            }
    }
    EXPECT_EQ(mixed, sides.size());
    EXPECT_GT(rays, 10000u);
    // One straight ray still goes through, by a hole under a face's width where tiles of levels 3, 5
    // and 7 meet (a second ring of overlap closes it, at 1.6-4.6 times the triangles of no overlap).
    EXPECT_LE(through, 2u) << "of " << rays << " rays";
}

// Level 0 is a tileset's root tile, so its triangles may not exceed a tile's (QA round 59: 2,000 against
// 1,000 gave a root of 1,363 faces, 100,000 a single 23,000-face tile); a plain chain has no tiles.
TEST(LodSet, a_first_level_larger_than_a_tile_is_refused_for_a_tileset)
{
    LodSetOptions o;
    o.max_tile_triangles = 1000;
    o.first_level_triangles = 2000;
    EXPECT_THROW(make_lod_levels(torus(), o), InvalidInput);
    o.first_level_triangles = 1000;
    EXPECT_LE(make_lod_levels(torus(), o).front().mesh.n_faces(), 1000u);
    o.tileset = false;
    o.first_level_triangles = 2000;
    EXPECT_LE(make_lod_levels(torus(), o).front().mesh.n_faces(), 1500u); // three quarters of 2,000
}

} // namespace
} // namespace mrt
