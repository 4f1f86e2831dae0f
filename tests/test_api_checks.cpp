// The public API refuses what it cannot use with InvalidInput, before any change, instead of reading out
// of bounds, running for days or writing a file it will not read back (QA round 51: a report-only round
// on the library's public functions, built with AddressSanitizer). One test per finding.
#include "libmrtile/close_covered_holes.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/color_vertices.h"
#include "libmrtile/coverage_gap.h"
#include "libmrtile/cut.h"
#include "libmrtile/denoise.h"
#include "libmrtile/errors.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/lod_set.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/model_file.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/refine_mesh.h"
#include "libmrtile/shapes.h"
#include "libmrtile/surface.h"
#include "libmrtile/tiles.h"
#include "test_dir.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace mrt {
namespace {

namespace fs = std::filesystem;

const Hierarchy& sphere_model()
{
    static const Hierarchy h = build_hierarchy(shapes::sphere(4000));
    return h;
}

// What `call` throws, or "" when it throws nothing.
template <typename F>
std::string refusal(F&& call)
{
    try {
        call();
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

std::string slurp(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A vertex naming a node beyond the hierarchy was read out of bounds when a step adopted an orphan tile;
// a NaN vertex went through and came back. Both are refused with the mesh left as it was.
TEST(ApiChecks, refine_mesh_checks_the_vertices_of_the_mesh_it_is_given)
{
    const Hierarchy& h = sphere_model();
    const Cut finer = cut_by_tolerance(h, 0.003);
    for (const int bad : {0, 1}) {
        SCOPED_TRACE(bad);
        MeshResult result = mesh_cut(h, cut_by_tolerance(h, 0.01));
        const Mesh::VertexHandle v(0);
        if (bad == 0) {
            auto cluster = OpenMesh::getProperty<OpenMesh::VertexHandle, int>(result.mesh, kVertexCluster);
            cluster[v] = 100000;
        } else {
            result.mesh.point(v) = Mesh::Point(std::nan(""), 0, 0);
        }
        const std::size_t faces = result.mesh.n_faces();
        const Cut before = result.cut;
        const std::string why = refusal([&] { refine_mesh(h, result, finer); });
        EXPECT_NE(why.find(bad == 0 ? "vertex 0 of result.mesh names tile 100000" : "vertex 0 of result.mesh has a NaN"),
                  std::string::npos)
            << why;
        EXPECT_EQ(result.mesh.n_faces(), faces);
        EXPECT_EQ(result.cut, before);
    }
}

// A bad LocalRefineOptions::remesh was found only by a step meshed afresh, after the in-place step had
// changed `result`; now the first call refuses it, naming the field.
TEST(ApiChecks, update_mesh_checks_its_remesh_options_first)
{
    const Hierarchy& h = sphere_model();
    MeshResult result = mesh_cut(h, cut_by_tolerance(h, 0.01));
    LocalRefineOptions o;
    o.remesh.surface.alpha = std::nan("");
    const Cut before = result.cut;
    const std::string why = refusal([&] { update_mesh(h, result, cut_by_tolerance(h, 0.005), o); });
    EXPECT_NE(why.find("LocalRefineOptions::remesh"), std::string::npos) << why;
    EXPECT_EQ(result.cut, before);
}

// Relaxation sweeps run inside every fit round: a million took 703 s on a 940-face torus. Capped as the
// rounds are, and checked before mesh_cut does any work.
TEST(ApiChecks, relaxation_sweeps_are_capped)
{
    const Hierarchy& h = sphere_model();
    MeshOptions o;
    o.fit.relax.iterations = kMaxRelaxIterations + 1;
    const std::string why = refusal([&] { mesh_cut(h, cut_by_tolerance(h, 0.01), o); });
    EXPECT_NE(why.find("iterations must be in [0, 100]"), std::string::npos) << why;
    o.fit.relax.iterations = kMaxRelaxIterations;
    o.fit.rounds = 1;
    EXPECT_EQ(refusal([&] { mesh_cut(h, cut_by_tolerance(h, 0.02), o); }), "");
}

// Caller-built inputs of the lower-level stages: indices out of range are refused, not read.
TEST(ApiChecks, lower_level_stages_check_their_indices)
{
    const Hierarchy& h = sphere_model();
    const Cut cut = cut_by_tolerance(h, 0.01);
    std::vector<Tile> tiles = make_tiles(h, cut);
    ASSERT_FALSE(tiles.empty());
    tiles.front().neighbours.push_back(99999);
    EXPECT_NE(refusal([&] { build_surface(h, tiles); }).find("names neighbour 99999"), std::string::npos);
    EXPECT_NE(refusal([&] { surrounded_tiles(tiles); }).find("names neighbour 99999"), std::string::npos);
    tiles.front().neighbours.pop_back();
    tiles.front().node = static_cast<std::int32_t>(h.nodes.size()) + 5;
    EXPECT_NE(refusal([&] { choose_height_field(h, tiles, {}); }).find("is not in the hierarchy"), std::string::npos);

    MeshResult r = mesh_cut(h, cut);
    EXPECT_NE(refusal([&] { faces_intersect(r.mesh, Mesh::FaceHandle(), Mesh::FaceHandle(0)); }).find("no face of the mesh"),
              std::string::npos);
    EXPECT_NE(refusal([&] { area_off_the_sample(r.mesh, h, std::vector<Mesh::FaceHandle>{Mesh::FaceHandle(999999)}, 0.1); })
                  .find("no face of the mesh"),
              std::string::npos);
    // A reach of 1e-300 overflowed the cell numbers (undefined behaviour); now every spot is off the
    // sample, as it is for any reach below the spacing.
    const std::vector<Mesh::FaceHandle> first{Mesh::FaceHandle(0)};
    EXPECT_GT(area_off_the_sample(r.mesh, h, first, 1e-300), 0.0);

    PointCloud few = h.cloud;
    few.colors.assign(10, {255, 0, 0, 255});
    EXPECT_NE(refusal([&] { color_vertices(r.mesh, few); }).find("10 colours for 4000 points"), std::string::npos);

    EXPECT_EQ(typical_move(h, 0, std::numeric_limits<std::size_t>::max()), 0.0); // wrapped round before
}

// make_lod_tiles trusts its levels to be h's, but a cut naming no node was read out of bounds.
TEST(ApiChecks, lod_tiles_check_the_levels_cuts)
{
    const Hierarchy& h = sphere_model();
    LodSetOptions o;
    o.levels = 2;
    std::vector<LodLevel> levels = make_lod_levels(h, o);
    ASSERT_FALSE(levels.empty());
    levels.back().cut = {99999};
    const std::string why = refusal([&] { make_lod_tiles(h, levels, o); });
    EXPECT_NE(why.find("lods: level " + std::to_string(levels.size() - 1)), std::string::npos) << why;
}

// Levels fine to coarse made a tile tree whose children were coarser than their parents (QA round 59).
TEST(ApiChecks, lod_tiles_take_levels_coarse_to_fine)
{
    const Hierarchy& h = sphere_model();
    LodSetOptions o;
    o.tolerances = {0.05, 0.01, 0.002};
    std::vector<LodLevel> levels = make_lod_levels(h, o);
    ASSERT_GE(levels.size(), 2u);
    EXPECT_NO_THROW(make_lod_tiles(h, levels, o));
    std::vector<LodLevel> reversed(levels.rbegin(), levels.rend());
    const std::string why = refusal([&] { make_lod_tiles(h, reversed, o); });
    EXPECT_NE(why.find("lods: level 1"), std::string::npos) << why;
    EXPECT_NE(why.find("coarse to fine"), std::string::npos) << why;
    std::vector<LodLevel> twice{levels[0], levels[0]};
    EXPECT_THROW(make_lod_tiles(h, twice, o), InvalidInput);
}

// save_model refuses what load_model would refuse, so a hierarchy damaged in memory never replaces a
// good file: a broken tree, repeated input indices, levels of another hierarchy.
TEST(ApiChecks, save_model_writes_only_what_loads)
{
    const fs::path dir = testing::fresh_test_dir("api_checks");
    const fs::path path = dir / "m.mrt";
    const Hierarchy& good = sphere_model();
    save_model(good, path);
    const std::string saved = slurp(path);

    Hierarchy tree = good;
    tree.nodes[1].end = tree.nodes[1].begin;
    Hierarchy indices = good;
    indices.input_index[0] = indices.input_index[1];
    for (const Hierarchy* bad : {&tree, &indices}) {
        const std::string why = refusal([&] { save_model(*bad, path); });
        EXPECT_NE(why.find("(it would not load)"), std::string::npos) << why;
        EXPECT_EQ(slurp(path), saved);
    }

    const Hierarchy other = build_hierarchy(shapes::torus(3000));
    StoredLevels foreign;
    foreign.levels = make_lod_levels(other, {});
    SaveOptions with_foreign;
    with_foreign.levels = &foreign;
    const std::string why = refusal([&] { save_model(good, path, with_foreign); });
    EXPECT_NE(why.find("(they would not load)"), std::string::npos) << why;
    EXPECT_EQ(slurp(path), saved);
}

// Options and inputs that were taken without a word.
TEST(ApiChecks, silent_degradations_are_refused)
{
    const Hierarchy& h = sphere_model();
    Camera camera;
    camera.position = {3, 0, 0};
    camera.direction = {-1, 0, 0};
    Camera wide = camera;
    wide.viewport_height = std::numeric_limits<double>::infinity(); // every node refined to the leaves
    EXPECT_NE(refusal([&] { cut_for_camera(h, wide); }).find("finite viewport height"), std::string::npos);
    Camera lax = camera;
    lax.max_pixel_error = std::numeric_limits<double>::infinity(); // the root alone
    EXPECT_NE(refusal([&] { cut_for_camera(h, lax); }).find("finite viewport height"), std::string::npos);

    // A unit sphere 1e12 from its origin built 54 finest tiles instead of 169, at 1e15 one.
    PointCloud far = shapes::sphere(2000);
    for (Vec3& p : far.positions)
        p = p + Vec3{1e12, 0, 0};
    EXPECT_NE(refusal([&] { build_hierarchy(far); }).find("call recenter(cloud)"), std::string::npos);
    recenter(far);
    EXPECT_EQ(refusal([&] { build_hierarchy(far); }), "");
    PointCloud near = shapes::sphere(2000);
    for (Vec3& p : near.positions)
        p = p + Vec3{1e7, 0, 0}; // a survey's easting: fine
    EXPECT_EQ(refusal([&] { build_hierarchy(near); }), "");

    std::vector<Vec3> points = shapes::sphere(500).positions;
    DenoiseOptions denoise;
    denoise.isolated_ratio = std::nan("");
    EXPECT_NE(refusal([&] { denoise_points(points, denoise); }).find("isolated_ratio"), std::string::npos);

    Hierarchy copy = h;
    CoverageOptions coverage;
    coverage.sample_fraction = std::nan("");
    EXPECT_NE(refusal([&] { set_coverage_gaps(copy, 1, coverage); }).find("sample_fraction in [0, 1]"), std::string::npos);
}

} // namespace
} // namespace mrt
