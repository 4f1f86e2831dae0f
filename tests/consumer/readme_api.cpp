// The README's main API example (the block of calls under "Library"), built against the *installed*
// package and run by the install_consumer test on a generated scan, so that it stays true. The text
// between the README markers is the README's, verbatim; the readme_api_in_sync test checks that it is.
// README includes begin
#include "formats/read_points.h"       // read_points
#include "libmrtile/outliers.h"        // remove_outliers (opt-in)
#include "libmrtile/denoise.h"         // denoise_points (build_hierarchy calls it on noisy samples)
#include "libmrtile/cluster_tree.h"    // build_hierarchy  (§4.1)
#include "libmrtile/sample_dimension.h" // sample_dimension (a surface at all, or points filling a volume?)
#include "libmrtile/model_file.h"      // save_model / load_model
#include "libmrtile/cut.h"             // cut_by_*
#include "libmrtile/coverage_gap.h"    // coverage_gap (holes a tile would cover)
#include "libmrtile/reconstruct.h"     // mesh_cut (§4.2-4.3), measure_quality
#include "libmrtile/single_view.h"     // single_view_stats (is a cloud with a viewpoint one view from it?)
#include "libmrtile/refine_mesh.h"     // refine_mesh / coarsen_mesh / update_mesh (a mesh patched in place for another cut)
#include "formats/write_mesh.h"        // write_mesh
#include "formats/write_gltf.h"        // write_gltf
#include "libmrtile/lod_set.h"         // make_lod_set, make_lod_levels, make_lod_tiles
#include "formats/lod_tileset.h"       // write_lod_tileset
// README includes end
#include "libmrtile/shapes.h"

#include <cstdio>
#include <filesystem>

int main()
{
    { // scan.ply: a sphere's points, as a scan would give them (positions only)
        const mrt::PointCloud sphere = mrt::shapes::sphere(6000);
        std::FILE* f = std::fopen("scan.ply", "w");
        if (f == nullptr)
            return 1;
        std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
                     sphere.positions.size());
        for (const mrt::Vec3& p : sphere.positions)
            std::fprintf(f, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
        std::fclose(f);
    }
    // README body begin
mrt::PointCloud cloud = mrt::read_points("scan.ply");                  // recentred: double origin
std::size_t stray = mrt::remove_outliers(cloud);                        // opt-in: isolated points of a raw scan
std::vector<mrt::Vec3> smooth = cloud.positions;
double rms_move = mrt::denoise_points(smooth);                          // by hand: each onto a quadric of it and 47 neighbours
mrt::BuildOptions build;                                                // tolerance 1e-4, pca_limit 500, min_cluster 16
build.denoise = mrt::BuildOptions::Denoise::Auto;                       // default: noisy samples are denoised, then built
mrt::Hierarchy h = mrt::build_hierarchy(std::move(cloud), build);      // persistent tree, exact node statistics
bool no_surface = mrt::sample_dimension(h).fills_volume;                // points that fill a volume: what `build` refuses
bool moved = h.info.denoised;                                           // the stored points are the denoised ones
double move = mrt::typical_move(h, 0, h.cloud.size());                  // how far denoising moved them (0 if not): each region's floor is 0.7× its own
mrt::save_model(h, "scan.mrt");                                         // atomic, checksummed, deterministic

mrt::Cut coarse = mrt::cut_by_tolerance(h, 0.002);                      // RMS plane distance ≤ 0.2% of the size
mrt::Cut budget = mrt::cut_by_budget(h, 1000);                          // the best 1,000-tile cut
mrt::Cut paper  = mrt::cut_by_tau(h, 0.001);                            // the paper's τ
double hole = h.nodes[0].coverage_gap;                                  // how far the root's tile reaches over holes
double gap = mrt::coverage_gap(h.cloud.positions, {1, 0, 0}, {0, 1, 0}); // any points, judged in the xy plane (0: none)

mrt::MeshResult r = mrt::mesh_cut(h, coarse);                           // tiles (T1) + gaps (T2) → manifold Mesh, fitted
mrt::QualityReport q = mrt::measure_quality(h, r.cut, r.mesh);          // genus, loops, E_RMS (r.cut: the cut meshed)
bool one_view = r.surface.view && r.surface.view->single_view;          // with a viewpoint: one view, so no handles were made
std::size_t notches = r.notches;                                        // border notches filled where the points cover them (fill_notches.h)
std::size_t capped = r.covered_holes.closed;                            // small holes the points cover, capped from them (close_covered_holes.h)
std::size_t tubes = r.bridges.tubes;                                    // tubes of gap faces across empty space cut, both ends capped (remove_bridges.h)
mrt::SingleViewStats seen = mrt::single_view_stats(h.cloud.positions, {0, 0, 2}); // any viewpoint: the share of points hidden from it
mrt::TriangleCountResult small = mrt::mesh_to_triangle_count(h, 20000); // finest best-N cut with ≤ 20,000 faces
mrt::MendedMeshResult t = mrt::mesh_at_tolerance(h, 0.02);             // a tolerance cut, finer where it breaks into pieces
mrt::write_mesh(r.mesh, h.cloud.origin, "scan_mesh.ply");            // atomic; keeps a file's permissions, refuses a read-only one
mrt::GltfOptions gltf; gltf.draco = true;
mrt::write_gltf(r.mesh, h.cloud.origin, "scan.glb", gltf);

mrt::LodSet lods = mrt::make_lod_set(h);                                // levels + 3D Tiles tile tree
mrt::write_lod_tileset(lods, h.cloud.origin, "tiles", {});
mrt::TilesetOptions packed; packed.gltf.draco = true;                   // Draco: one grid, the bits the finest level needs
packed.gltf.draco_options.grid = mrt::tileset_grid(lods);
packed.gltf.draco_options.position_bits = mrt::tileset_position_bits(h, lods, *packed.gltf.draco_options.grid);
mrt::write_lod_tileset(lods, h.cloud.origin, "tiles_draco", packed);

mrt::StoredLevels stored{"my options", mrt::make_lod_levels(h)};          // the costly part, once
mrt::SaveOptions with_levels; with_levels.levels = &stored;
mrt::save_model(h, "scan.mrt", with_levels);                             // ~45 bytes per face of all levels
mrt::Model m = mrt::load_model_with_levels("scan.mrt");                  // later: hierarchy + levels
mrt::LodSet again = mrt::make_lod_tiles(m.hierarchy, std::move(m.levels.levels)); // tiles only: seconds

// Input in a projected CRS (h.cloud.crs, from a LAS file, or any "EPSG:N" / WKT): on the globe.
mrt::LodSet placed = mrt::make_lod_set(h);
const mrt::GeoPlacement at = mrt::georeference(placed, h.cloud.origin, h.nodes.front().box, mrt::parse_crs("EPSG:32633"));
mrt::TilesetOptions on_globe;
on_globe.root_transform = at.root_transform;                            // ENU at at.anchor → ECEF
mrt::write_lod_tileset(placed, {0, 0, 0}, "tiles_on_globe", on_globe);   // positions are ENU metres now
    // README body end
    (void)stray, (void)no_surface, (void)rms_move, (void)moved, (void)move, (void)budget, (void)paper, (void)hole, (void)gap, (void)q;
    (void)one_view, (void)notches, (void)capped, (void)tubes, (void)seen, (void)small, (void)t, (void)again;
    for (const char* made : {"scan.mrt", "scan_mesh.ply", "scan.glb", "tiles/tileset.json", "tiles_draco/tileset.json",
                             "tiles_on_globe/tileset.json"})
        if (!std::filesystem::exists(made)) {
            std::fprintf(stderr, "readme_api: %s was not written\n", made);
            return 1;
        }
    std::printf("readme_api: the README's API example ran: %zu faces at tolerance 0.002; tileset tiles: %zu\n",
                static_cast<std::size_t>(r.mesh.n_faces()), lods.tiles.size());
    return 0;
}
