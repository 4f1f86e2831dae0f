// Benchmark of noisy samples (denoise.h, the noise floor of hierarchy.h): generated shapes and shared
// scans with Gaussian noise of 1-3 point spacings, built with the noise kept (the floor alone) and
// denoised (the default for such samples), meshed at two tolerances. Quality is measured against the
// noise-free points (what the noise hides), so that "nearer the surface" is a number, not a look.
#include "tools/bench.h"
#include "tools/bench_common.h"
#include "tools/bench_measure.h"

#include "formats/read_points.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/parallel.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/shapes.h"

#include <cmath>
#include <filesystem>
#include <optional>

namespace mrt::bench {
namespace {

constexpr double kTolerances[] = {0.01, 0.002};

struct NoisyInput
{
    std::string name;
    PointCloud clean;
    double spacing = 0.0; // mean point spacing: sqrt(area / points)
    double noise_spacings = 0.0;
};

// A scan's spacing from the area of its clean mesh at tolerance 0.002 (the scans have no formula).
double mesh_spacing(const PointCloud& clean)
{
    const Hierarchy h = build_hierarchy(clean);
    const MeshResult m = mesh_cut(h, cut_by_tolerance(h, 0.002));
    double area = 0.0;
    for (const auto f : m.mesh.faces())
        area += m.mesh.calc_face_area(f);
    return std::sqrt(area / static_cast<double>(clean.size()));
}

std::vector<NoisyInput> inputs(const BenchContext& context, std::vector<std::string>& missing)
{
    std::vector<NoisyInput> out;
    out.push_back({"sphere 100k", shapes::sphere(100000), std::sqrt(4.0 * M_PI / 100000.0), 2.0});
    out.push_back({"torus 100k", shapes::torus(100000), std::sqrt(4.0 * M_PI * M_PI * 0.35 / 100000.0), 3.0});
    const double box_area = 2.0 * (1.0 * 2.0 + 2.0 * 0.5 + 0.5 * 1.0);
    PointCloud box = shapes::box_surface({1.0, 2.0, 0.5}, 100000 / box_area);
    const double box_spacing = std::sqrt(box_area / static_cast<double>(box.size()));
    out.push_back({"box 1×2×0.5", std::move(box), box_spacing, 2.0});
    const double plate_area = 2.0 * (1.0 + 2.0 * 0.03);
    PointCloud plate = shapes::box_surface({1.0, 1.0, 0.03}, 100000 / plate_area);
    const double plate_spacing = std::sqrt(plate_area / static_cast<double>(plate.size()));
    out.push_back({"plate 1×1×0.03", std::move(plate), plate_spacing, 1.0});
    const std::pair<const char*, double> scans[] = {{"bun_zipper.ply", 1.0}, {"igea.ply", 2.0}, {"fandisk.obj", 1.0}, {"rocker-arm.obj", 1.0}};
    for (const auto& [file, spacings] : scans) {
        const auto path = context.data_dir / file;
        if (!std::filesystem::exists(path)) {
            missing.push_back(file);
            continue;
        }
        PointCloud clean = read_points(path);
        const double spacing = mesh_spacing(clean);
        out.push_back({file, std::move(clean), spacing, spacings});
    }
    return out;
}

struct Meshed
{
    TopologyStats topology;
    double mean_to_clean = 0.0; // noise-free points → mesh, fraction of their diagonal
    std::size_t faces = 0;
};

Meshed mesh_at(const Hierarchy& h, const PointCloud& clean, double tolerance)
{
    const MeshResult r = mesh_cut(h, cut_by_tolerance(h, tolerance));
    Meshed m;
    m.topology = topology_stats(r.mesh);
    m.faces = r.mesh.n_faces();
    // The mesh is relative to the hierarchy's origin, the clean points to their own.
    std::vector<Vec3> truth = clean.positions;
    for (Vec3& p : truth)
        p = p + clean.origin - h.cloud.origin;
    m.mean_to_clean = point_to_mesh_distance(truth, r.mesh).mean;
    return m;
}

std::string pieces(const Meshed& m)
{
    return std::to_string(m.topology.boundary_loops) + " / " + std::to_string(m.topology.components);
}

} // namespace

std::vector<Table> noise_tables(const BenchContext& context)
{
    set_default_threads(1);
    Table t;
    t.title = "Noisy samples: the noise floor alone vs. denoised (`--only noise`)";
    t.columns = {{"input", Align::Left}, {"noise (spacings)"}, {"tolerance"}, {"floor only: loops / pieces"},
                 {"mean to clean"}, {"build s"}, {"denoised: loops / pieces"}, {"mean to clean"}, {"build s"}};
    std::vector<std::string> missing;
    for (NoisyInput& in : inputs(context, missing)) {
        progress("noise: " + in.name);
        PointCloud noisy = in.clean;
        shapes::add_noise(noisy, in.noise_spacings * in.spacing);
        BuildOptions raw;
        raw.denoise = BuildOptions::Denoise::Off;
        std::optional<Hierarchy> kept, denoised;
        const Timing kept_time = time_call([&] { kept = build_hierarchy(noisy, raw); });
        const Timing denoised_time = time_call([&] { denoised = build_hierarchy(noisy); });
        for (const double tolerance : kTolerances) {
            const Meshed a = mesh_at(*kept, in.clean, tolerance), b = mesh_at(*denoised, in.clean, tolerance);
            t.rows.push_back({in.name, fixed(in.noise_spacings, 0), fixed(tolerance, 3), pieces(a), scientific(a.mean_to_clean),
                              fixed(kept_time.cpu, 2), (denoised->info.denoised ? "" : "(not denoised) ") + pieces(b),
                              scientific(b.mean_to_clean), fixed(denoised_time.cpu, 2)});
        }
    }
    t.notes = {
        "Gaussian noise (`shapes::add_noise`, seed 7) of the given number of mean point spacings (sqrt(area / points); "
        "a scan's area from its clean mesh at tolerance 0.002). Single thread, CPU seconds.",
        "Floor only: `build_hierarchy` with `BuildOptions::denoise = Off` (cuts stop at the noise floor, hierarchy.h); "
        "denoised: the default build, which finds the sample noisy and moves the points onto a quadric fitted to "
        "their 48 nearest neighbours before building again (denoise.h). `cut_by_tolerance` → `mesh_cut` on each.",
        "Loops / pieces: boundary loops and connected components of the mesh (the clean meshes: 0 / 1, the bunny "
        "2 / 1 for its base, fandisk 0 / 1, the rocker arm 1 / 1: a slit on a face sampled only along its outline). Mean to clean: the noise-free points' mean distance "
        "to the mesh, as a fraction of their bounding-box diagonal.",
        "The plate is 6.6 spacings thick: its two sides are 6.6 σ apart."};
    for (const std::string& file : missing)
        t.notes.push_back(file + " not found under " + context.data_dir.string() + ": its rows are skipped.");
    return {t};
}

} // namespace mrt::bench
