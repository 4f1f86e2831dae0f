// Benchmarks of "any cut" from a saved model (libmrtile/cut.h, model_file.h, reconstruct.h): a 4M-point
// hierarchy is built once, saved and loaded, then cut by tile budget and by a focus region and meshed.
// The point of the persistent hierarchy is that a cut costs nodes, not points; the targets (1,000-tile
// cut < 50 ms, ≥ 1M output triangles/s, model file < 200 B/point) are checked here.
#include "tools/bench.h"
#include "tools/bench_common.h"
#include "tools/bench_measure.h"

#include "formats/read_points.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/model_file.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/refine_mesh.h"

#include <array>
#include <functional>

namespace mrt::bench {
namespace {

constexpr double kMaxCutSeconds = 0.050;          // target: a 1,000-tile cut
constexpr double kMinTrianglesPerSecond = 1e6;    // target: output triangles per second of meshing
constexpr double kMaxModelBytesPerPoint = 200.0;  // target: .mrt file size
constexpr double kFocusBaseTolerance = 0.01;
constexpr double kFocusTolerance = 0.0005;
constexpr double kFocusRadius = 0.1;              // × the bounding-box diagonal
constexpr std::size_t kCuts = 3;

struct CutMeasurement
{
    std::uint64_t tiles = 0;
    std::uint64_t triangles = 0;
    Timing cut;  // fastest of several runs (a cut takes milliseconds)
    Timing mesh; // mesh_cut, once
    double surface_seconds = 0.0; // the part of mesh_cut spent in build_surface (§4.3), wall
    double tile_seconds = 0.0;    // the part spent in make_tiles (§4.2), wall
    double fit_seconds = 0.0;     // the part spent in fit_vertices, wall
};

// refine_mesh (incremental) against a fresh mesh_cut of the same finer cut.
struct RefineMeasurement
{
    std::uint64_t tiles_before = 0, tiles_after = 0, fresh_tiles = 0;
    std::uint64_t changed = 0, kept = 0, absent = 0, adopted = 0; // tiles re-triangulated (split or merged), left, absent, adopted
    std::uint64_t faces = 0, fresh_faces = 0, faces_added = 0;
    Timing refine, fresh;
    DistanceStats distance, fresh_distance; // of the points measured (see the table's notes)
};
constexpr std::size_t kRefines = 4;

struct CutsMeasurement
{
    std::uint64_t points = 0;
    std::uint64_t nodes = 0;
    std::uint64_t file_bytes = 0;
    Timing build;
    Timing save;
    Timing load;
    std::uint64_t peak = 0; // bytes, the whole child
    std::array<CutMeasurement, kCuts> cuts;
    std::array<RefineMeasurement, kRefines> refines;
};

// The focus sphere sits on the torus's outer equator (+x side of the box), so it covers surface.
FocusRegion focus_region(const Hierarchy& h)
{
    const BoundingBox box = h.bbox();
    FocusRegion region;
    region.shape = FocusRegion::Shape::Sphere;
    region.centre = {box.max.x, box.centre().y, box.centre().z};
    region.radius = kFocusRadius * box.diagonal();
    region.tolerance = kFocusTolerance;
    return region;
}

CutMeasurement measure_cut(const Hierarchy& h, const std::function<Cut()>& make_cut)
{
    CutMeasurement m;
    Cut cut;
    m.cut = time_fastest([&] { cut = make_cut(); }, 3, 20, 0.2);
    MeshResult result;
    m.mesh = time_call([&] { result = mesh_cut(h, cut); });
    m.tiles = cut.size();
    m.triangles = result.mesh.n_faces();
    m.surface_seconds = result.surface.seconds;
    m.fit_seconds = result.fit.seconds;
    m.tile_seconds = result.seconds - result.surface.seconds - result.fit.seconds;
    return m;
}

// The base mesh changed to `finer` in place and, for comparison, `finer` meshed afresh; distances of
// `probe` (points of the cloud) to both. `any_cut`: update_mesh (coarsens and refines) instead of
// refine_mesh (a finer cut).
RefineMeasurement measure_refine(const Hierarchy& h, const MeshResult& base, const Cut& finer,
                                 const std::vector<Vec3>& probe, bool any_cut = false)
{
    RefineMeasurement m;
    m.tiles_before = base.cut.size();
    MeshResult refined = base; // copied outside the timing: a caller refines its mesh in place
    LocalRefineStats stats;
    m.refine = time_call([&] { stats = any_cut ? update_mesh(h, refined, finer) : refine_mesh(h, refined, finer); });
    m.changed = stats.refined + stats.coarsened;
    m.kept = stats.kept;
    m.absent = stats.absent;
    m.adopted = stats.adopted;
    m.faces_added = stats.faces_added;
    m.tiles_after = refined.cut.size();
    m.faces = refined.mesh.n_faces();
    MeshResult fresh;
    m.fresh = time_call([&] { fresh = mesh_cut(h, finer); });
    m.fresh_tiles = fresh.cut.size();
    m.fresh_faces = fresh.mesh.n_faces();
    m.distance = point_to_mesh_distance(probe, refined.mesh);
    m.fresh_distance = point_to_mesh_distance(probe, fresh.mesh);
    return m;
}

CutsMeasurement measure_cuts(std::size_t points, const std::filesystem::path& bunny)
{
    return run_in_child<CutsMeasurement>([points, bunny] {
        CutsMeasurement m;
        ScratchDir scratch("cuts");
        const auto path = scratch.path() / "torus.mrt";
        {
            PointCloud cloud = noisy_torus(points);
            m.points = cloud.size();
            Hierarchy built;
            m.build = time_call([&] { built = build_hierarchy(std::move(cloud)); });
            m.save = time_call([&] { save_model(built, path); });
        }
        m.file_bytes = std::filesystem::file_size(path);
        Hierarchy h;
        m.load = time_call([&] { h = load_model(path); });
        m.nodes = h.nodes.size();
        progress("cuts: model loaded in " + fixed(m.load.wall, 2) + " s; cutting and meshing ...");
        m.cuts[0] = measure_cut(h, [&] { return cut_by_budget(h, 1000); });
        m.cuts[1] = measure_cut(h, [&] { return cut_by_budget(h, 10000); });
        const FocusRegion region = focus_region(h);
        m.cuts[2] = measure_cut(h, [&] { return cut_by_regions(h, kFocusBaseTolerance, {region}); });
        m.peak = peak_resident_bytes();
        progress("cuts: incremental refinement (refine_mesh) against fresh meshes ...");
        {
            const MeshResult base = mesh_cut(h, cut_by_tolerance(h, kFocusBaseTolerance));
            std::vector<Vec3> inside; // the points in the focus sphere
            for (const Vec3& p : h.cloud.positions)
                if (distance(p, region.centre) < region.radius)
                    inside.push_back(p);
            m.refines[0] = measure_refine(h, base, refine_cut(h, base.cut, kFocusBaseTolerance, {region}), inside);
        }
        std::vector<Vec3> sample; // every 40th point: the whole surface, for the budget and camera rows
        for (std::size_t i = 0; i < h.cloud.positions.size(); i += 40)
            sample.push_back(h.cloud.positions[i]);
        m.refines[1] = measure_refine(h, mesh_cut(h, cut_by_budget(h, 1000)), cut_by_budget(h, 10000), sample);
        {
            // A camera moved to the other side of the torus (update_mesh: coarser behind, finer in front).
            const BoundingBox box = h.bbox();
            auto camera_at = [&](double side) {
                Camera c;
                c.position = box.centre() + Vec3{side * box.diagonal(), 0.0, 0.2 * box.diagonal()};
                c.direction = box.centre() - c.position;
                c.max_pixel_error = 4.0;
                return c;
            };
            const MeshResult base = mesh_cut(h, cut_for_camera(h, camera_at(0.7)));
            m.refines[2] = measure_refine(h, base, cut_for_camera(h, camera_at(-0.7)), sample, true);
        }
        {
            // A real scan: the bunny refined everywhere from tolerance 0.005 to 0.001.
            const Hierarchy rabbit = build_hierarchy(read_points(bunny));
            const MeshResult base = mesh_cut(rabbit, cut_by_tolerance(rabbit, 0.005));
            m.refines[3] = measure_refine(rabbit, base, cut_by_tolerance(rabbit, 0.001), rabbit.cloud.positions);
        }
        return m;
    });
}

Table cuts_table(const CutsMeasurement& m, const std::string& input)
{
    const char* names[kCuts] = {"budget 1,000 tiles", "budget 10,000 tiles", "focus sphere (base 0.01, 0.0005 inside)"};
    Table t;
    t.title = "Any cut from a loaded model: " + input;
    t.columns = {{"cut", Align::Left}, {"tiles"},          {"triangles"},       {"cut ms (1,000 tiles: < 50)"},
                 {"mesh s"},           {"tiles / surface / fit s"}, {"mesh s (wall)"}, {"cut+mesh s"},  {"triangles/s (≥ 1M)"}};
    for (std::size_t i = 0; i < kCuts; ++i)
    {
        const CutMeasurement& c = m.cuts[i];
        const double rate = static_cast<double>(c.triangles) / (c.cut.cpu + c.mesh.cpu);
        std::string cut_ms = fixed(c.cut.cpu * 1e3, 2);
        if (i == 0)
            cut_ms += " " + verdict(c.cut.cpu < kMaxCutSeconds);
        t.rows.push_back({names[i], with_commas(c.tiles), with_commas(c.triangles), cut_ms, fixed(c.mesh.cpu, 2),
                          fixed(c.tile_seconds, 2) + " / " + fixed(c.surface_seconds, 2) + " / " + fixed(c.fit_seconds, 2),
                          fixed(c.mesh.wall, 2),
                          fixed(c.cut.cpu + c.mesh.cpu, 2),
                          with_commas(static_cast<std::uint64_t>(rate)) + " " + verdict(rate >= kMinTrianglesPerSecond)});
    }
    const double bytes_per_point = static_cast<double>(m.file_bytes) / static_cast<double>(m.points);
    t.notes = {
        input + ": " + with_commas(m.points) + " points, " + with_commas(m.nodes) + " nodes; built (default options) in " +
            fixed(m.build.cpu, 2) + " s CPU, `save_model` " + fixed(m.save.wall, 2) + " s, `load_model` " +
            fixed(m.load.wall, 2) + " s wall / " + fixed(m.load.cpu, 2) + " s CPU; model file " +
            with_commas(m.file_bytes) + " bytes = " + fixed(bytes_per_point, 1) + " B/point " +
            verdict(bytes_per_point < kMaxModelBytesPerPoint) + " (target < " + fixed(kMaxModelBytesPerPoint, 0) +
            "); child's peak memory " + fixed(static_cast<double>(m.peak) / (1024.0 * 1024.0), 0) + " MiB.",
        "Cuts on the loaded model: `cut_by_budget(h, n)`; focus: `cut_by_regions(h, 0.01, {sphere})`, the sphere of "
        "radius 10% of the bbox diagonal centred on the torus's outer equator, tolerance 0.0005 inside. Cut ms: "
        "CPU, fastest of at least 3 runs; mesh s: `mesh_cut` once (CPU); tiles / surface / fit: its split as `MeshResult` reports it (wall; tiles = §4.2 pseudo tiles, surface = §4.3 `build_surface`, fit = `fit_vertices`; the per-tile Delaunay triangulations and the fit's closest-face queries use every core, so CPU can exceed wall).",
        "Triangles/s: output triangles / (cut + mesh) CPU seconds. The 50 ms target is read as the cut alone "
        "(the cut+mesh column shows what the whole request costs)."};
    return t;
}

Table refine_table(const CutsMeasurement& m, const std::string& input)
{
    const char* names[kRefines] = {"focus sphere: 0.01 → 0.0005 inside", "budget 1,000 → 10,000 tiles",
                                   "camera moved to the other side (update_mesh)", "bun_zipper.ply: tolerance 0.005 → 0.001"};
    Table t;
    t.title = "Incremental refinement (`refine_mesh`) vs. a fresh `mesh_cut` of the same cut: " + input + " and the bunny";
    t.columns = {{"refinement", Align::Left}, {"tiles before → after (fresh)"}, {"changed / kept / absent / adopted"},
                 {"faces (fresh)"}, {"refine s"}, {"fresh mesh_cut s"}, {"speed-up"},
                 {"output triangles/s (≥ 1M)"}, {"mean dist (fresh)"}, {"max dist (fresh)"}};
    for (std::size_t i = 0; i < kRefines; ++i)
    {
        const RefineMeasurement& r = m.refines[i];
        const double rate = static_cast<double>(r.faces) / r.refine.cpu;
        t.rows.push_back({names[i],
                          with_commas(r.tiles_before) + " → " + with_commas(r.tiles_after) + " (" + with_commas(r.fresh_tiles) + ")",
                          with_commas(r.changed) + " / " + with_commas(r.kept) + " / " + with_commas(r.absent) + " / " + with_commas(r.adopted),
                          with_commas(r.faces) + " (" + with_commas(r.fresh_faces) + ")", fixed(r.refine.cpu, 3),
                          fixed(r.fresh.cpu, 2), fixed(r.fresh.cpu / r.refine.cpu, 1) + "×",
                          with_commas(static_cast<std::uint64_t>(rate)) + " " + verdict(rate >= kMinTrianglesPerSecond),
                          scientific(r.distance.mean) + " (" + scientific(r.fresh_distance.mean) + ")",
                          scientific(r.distance.max) + " (" + scientific(r.fresh_distance.max) + ")"});
    }
    t.notes = {
        "Base meshes: `mesh_cut` of `cut_by_tolerance(h, 0.01)` (focus row) and of `cut_by_budget(h, 1000)`; "
        "finer cuts: `refine_cut(h, base.cut, 0.01, {the focus sphere above})` and `cut_by_budget(h, 10000)`; for the "
        "bunny (its own hierarchy, default options), `cut_by_tolerance` 0.005 and 0.001; camera row: `cut_for_camera` from "
        "0.7 bbox diagonals on +x, 0.2 up, looking at the centre (pixel error 4), then the same on −x, and `update_mesh` "
        "instead of `refine_mesh` (it coarsens behind and refines in front). Refine s: "
        "`refine_mesh(h, base, finer)` in place (CPU, once; the copy of the base mesh is not timed); fresh: `mesh_cut(h, finer)` "
        "(CPU, once). Changed / kept / absent / adopted: tiles re-triangulated (refined, or merged groups) / left as they were (their region was not one disc, "
        "would fold or would cross its surroundings; the cut after keeps them, so it can have fewer tiles than the fresh "
        "one) / split with nothing of theirs in the mesh / new tiles whose points lay in a neighbour's fan, given vertices by "
        "re-triangulating that neighbour's region with theirs (`LocalRefineStats::adopted`).",
        "Output triangles/s: the whole refined mesh's faces / refine CPU seconds; it needs a meshed base cut, so it is "
        "the incremental path, not a cut meshed from the model alone (the table above). Distances: focus row, the "
        "points inside the sphere; budget and camera rows, every 40th point; bunny, every point; to the mesh, as fractions of the bbox "
        "diagonal of the points measured (`point_to_mesh_distance`)."};
    return t;
}

} // namespace

std::vector<Table> cuts_tables(const BenchContext& context)
{
    std::size_t points = 4000000;
    if (points > context.max_points)
        points = static_cast<std::size_t>(context.max_points);
    const std::string input = "noisy torus " + short_count(points);
    progress("cuts: " + input + ": build, save, load ...");
    const CutsMeasurement m = measure_cuts(points, context.data_dir / "bun_zipper.ply");
    return {cuts_table(m, input), refine_table(m, input)};
}

} // namespace mrt::bench
