// Tests of color_vertices.h: colours of an analytic colouring come back on the vertices (a two-colour
// sphere exactly away from its equator, a linear ramp within rounding), every vertex gets one, the result
// does not depend on the thread count, uncoloured input leaves the mesh uncoloured, and LOD tiles and
// files carry the colours.
#include "formats/write_mesh.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/color_vertices.h"
#include "libmrtile/cut.h"
#include "libmrtile/lod_set.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"

#include "tests/test_dir.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

namespace mrt {
namespace {

using Rgba = std::array<std::uint8_t, 4>;

// A sphere whose upper half is red and lower half blue (alpha 200), or coloured by a ramp in x.
PointCloud colored_sphere(bool ramp)
{
    PointCloud c = shapes::sphere(20000);
    for (const Vec3& p : c.positions) {
        if (ramp) {
            const auto r = static_cast<std::uint8_t>(std::lround(127.5 * (p.x + 1.0)));
            c.colors.push_back(Rgba{r, 50, static_cast<std::uint8_t>(255 - r), 255});
        } else {
            c.colors.push_back(p.z >= 0 ? Rgba{255, 0, 0, 200} : Rgba{0, 0, 255, 200});
        }
    }
    return c;
}

TEST(ColorVertices, halves_come_back_exactly_away_from_the_seam)
{
    const Hierarchy h = build_hierarchy(colored_sphere(false));
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.005));
    ASSERT_TRUE(r.mesh.has_vertex_colors());
    std::size_t above = 0, below = 0;
    for (const auto v : r.mesh.vertices()) {
        const double z = r.mesh.point(v)[2] + h.cloud.origin.z;
        const auto c = r.mesh.color(v);
        EXPECT_EQ(c[3], 200); // alpha is carried too
        if (z > 0.25) { // beyond the faces that straddle the equator
            EXPECT_EQ((std::array<int, 3>{c[0], c[1], c[2]}), (std::array<int, 3>{255, 0, 0}));
            ++above;
        } else if (z < -0.25) {
            EXPECT_EQ((std::array<int, 3>{c[0], c[1], c[2]}), (std::array<int, 3>{0, 0, 255}));
            ++below;
        } else {
            EXPECT_EQ(c[0] + c[2], 255); // a mix of the two, never anything else
            EXPECT_EQ(c[1], 0);
        }
    }
    EXPECT_GT(above, 50u);
    EXPECT_GT(below, 50u);
}

TEST(ColorVertices, a_ramp_is_reproduced_and_threads_do_not_matter)
{
    const Hierarchy h = build_hierarchy(colored_sphere(true));
    const Cut cut = cut_by_tolerance(h, 0.002);
    MeshOptions one, three;
    one.colors.threads = 1;
    three.colors.threads = 3;
    const MeshResult a = mesh_cut(h, cut, one), b = mesh_cut(h, cut, three);
    ASSERT_EQ(a.mesh.n_vertices(), b.mesh.n_vertices());
    double worst = 0.0;
    for (const auto v : a.mesh.vertices()) {
        EXPECT_EQ(a.mesh.color(v), b.mesh.color(Mesh::VertexHandle(v.idx())));
        const double x = a.mesh.point(v)[0] + h.cloud.origin.x;
        const double expected = 127.5 * (x + 1.0);
        worst = std::max(worst, std::abs(a.mesh.color(v)[0] - expected));
        EXPECT_EQ(a.mesh.color(v)[0] + a.mesh.color(v)[2], 255);
    }
    // A vertex averages the points of its faces (a few spacings around it), the colour a linear
    // function of x: off by the ramp over about one face (2 units per 1% of the radius).
    EXPECT_LT(worst, 12.0);
}

TEST(ColorVertices, uncoloured_input_or_disabled_leaves_the_mesh_alone)
{
    const Hierarchy plain = build_hierarchy(shapes::sphere(5000));
    EXPECT_FALSE(mesh_cut(plain, cut_by_tolerance(plain, 0.01)).mesh.has_vertex_colors());
    const Hierarchy h = build_hierarchy(colored_sphere(false));
    MeshOptions off;
    off.colors.enabled = false;
    Mesh m = mesh_cut(h, cut_by_tolerance(h, 0.01), off).mesh;
    EXPECT_FALSE(m.has_vertex_colors());
    EXPECT_GT(color_vertices(m, h.cloud), 0u);
    EXPECT_TRUE(m.has_vertex_colors());
}

TEST(ColorVertices, lod_tiles_and_files_carry_the_colours)
{
    const Hierarchy h = build_hierarchy(colored_sphere(false));
    LodSetOptions o;
    o.max_tile_triangles = 2000;
    const LodSet set = make_lod_set(h, o);
    ASSERT_GT(set.tiles.size(), 1u);
    for (const LodTile& tile : set.tiles) {
        if (tile.mesh.n_vertices() > 0) {
            EXPECT_TRUE(tile.mesh.has_vertex_colors());
        }
    }
    const std::filesystem::path dir = testing::fresh_test_dir("color_vertices");
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, 0.01));
    write_mesh(r.mesh, h.cloud.origin, dir / "m.ply");
    std::ifstream in(dir / "m.ply", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    EXPECT_NE(bytes.find("property uchar red"), std::string::npos);
}

} // namespace
} // namespace mrt
