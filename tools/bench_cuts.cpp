// Benchmarks of "any cut" from a saved model (libmrtile/cut.h, model_file.h, reconstruct.h): a 4M-point
// hierarchy is built once, saved and loaded, then cut by tile budget and by a focus region and meshed.
// The point of the persistent hierarchy is that a cut costs nodes, not points; the targets (1,000-tile
// cut < 50 ms, ≥ 1M output triangles/s, model file < 200 B/point) are checked here.
#include "tools/bench.h"
#include "tools/bench_common.h"
#include "tools/bench_measure.h"

#include "libmrtile/cluster_tree.h"
#include "libmrtile/model_file.h"
#include "libmrtile/reconstruct.h"

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

CutsMeasurement measure_cuts(std::size_t points)
{
    return run_in_child<CutsMeasurement>([points] {
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

} // namespace

std::vector<Table> cuts_tables(const BenchContext& context)
{
    std::size_t points = 4000000;
    if (points > context.max_points)
        points = static_cast<std::size_t>(context.max_points);
    const std::string input = "noisy torus " + short_count(points);
    progress("cuts: " + input + ": build, save, load ...");
    return {cuts_table(measure_cuts(points), input)};
}

} // namespace mrt::bench
