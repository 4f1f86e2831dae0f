// Benchmarks of reconstruction (paper §4.2-4.3, libmrtile/reconstruct.h): our tiles + manifold surface
// against CGAL's Advancing Front Surface Reconstruction, raw and simplified by meshoptimizer to our
// face count; 1M points end to end from a .ply file; and the paper's Table 2 layout (tiles, vertices,
// E_RMS per τ). Targets (≥ 5× faster than AFSR, ≤ 1.5× the distance of AFSR+meshopt at equal size,
// 1M points end to end in ≤ 5 s) are checked here, never in unit tests.
#include "tools/bench.h"
#include "tools/bench_afsr.h"
#include "tools/bench_common.h"
#include "tools/bench_measure.h"

#include "formats/read_points.h"
#include "formats/write_mesh.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/reconstruct.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>

namespace mrt::bench {
namespace {

constexpr double kMinSpeedupOverAfsr = 5.0;     // target: AFSR time / ours at the finest tolerance
constexpr double kMaxDistanceRatio = 1.5;       // target: our mean distance / AFSR+meshopt's, equal faces
constexpr double kMaxEndToEndSeconds = 5.0;     // target: 1M points .ply -> mesh .ply, single thread
constexpr std::size_t kTolerances = 3;
constexpr std::array<double, kTolerances> kMeshTolerances = {0.005, 0.002, 0.001}; // coarse to fine

struct MeshInput
{
    std::string label;
    std::function<PointCloud()> make; // deterministic
};

// One method on one input, measured in a forked child (plain numbers: they cross a pipe).
struct MethodMeasurement
{
    Timing total;  // points in memory -> mesh (ours: build + cut + mesh; peers: AFSR [+ meshopt])
    Timing part;   // ours: cut + mesh; AFSR: 0; AFSR+meshopt: the simplification alone
    std::uint64_t peak = 0;  // bytes, the child's peak resident size at the end of the method
    std::uint64_t tiles = 0; // ours only
    std::uint64_t faces = 0;
    std::uint64_t caps = 0;  // faces with an angle above 150 degrees (count_caps): creases under shading
    DistanceStats distance;  // input points -> mesh, fractions of the bbox diagonal
    DistanceStats reverse;   // mesh (vertices, face centroids) -> nearest input point: spikes and flaps
    TopologyStats topology;
};

struct PeerMeasurement
{
    MethodMeasurement afsr;
    std::array<MethodMeasurement, kTolerances> simplified; // to our face count at each tolerance
};

Timing operator+(const Timing& a, const Timing& b) { return {a.wall + b.wall, a.cpu + b.cpu}; }

MethodMeasurement measure_ours(const MeshInput& input, double tolerance)
{
    return run_in_child<MethodMeasurement>([&] {
        PointCloud cloud = input.make();
        reset_peak_rss();
        MethodMeasurement m;
        Hierarchy h;
        Cut cut;
        MeshResult result;
        const Timing build = time_call([&] { h = build_hierarchy(std::move(cloud)); });
        m.part = time_call([&] {
            cut = cut_by_tolerance(h, tolerance);
            result = mesh_cut(h, cut);
        });
        m.total = build + m.part;
        m.peak = peak_resident_bytes();
        m.tiles = cut.size();
        m.faces = result.mesh.n_faces();
        const QualityReport quality = measure_quality(h, result.cut, result.mesh);
        m.distance = quality.point_to_mesh;
        m.reverse = quality.mesh_to_points;
        m.topology = quality.topology;
        m.caps = quality.caps;
        return m;
    });
}

void measure_soup(const TriangleSoup& soup, const std::vector<Vec3>& points, MethodMeasurement& m)
{
    m.faces = soup.triangles.size();
    m.topology = topology_stats(soup.positions, soup.triangles);
    const Mesh mesh = unshared_mesh(soup);
    m.distance = point_to_mesh_distance(points, mesh);
    m.reverse = mesh_to_point_distance(mesh, points);
    m.caps = count_caps(mesh);
}

PeerMeasurement measure_peers(const MeshInput& input, const std::array<std::uint64_t, kTolerances>& target_faces)
{
    return run_in_child<PeerMeasurement>([&] {
        const PointCloud cloud = input.make();
        reset_peak_rss();
        PeerMeasurement p;
        TriangleSoup soup;
        p.afsr.total = time_call([&] { soup = afsr_reconstruct(cloud.positions); });
        p.afsr.peak = peak_resident_bytes();
        for (std::size_t i = 0; i < kTolerances; ++i)
        {
            MethodMeasurement& m = p.simplified[i];
            TriangleSoup small;
            m.part = time_call([&] { small = meshopt_simplify_to(soup, target_faces[i]); });
            m.total = p.afsr.total + m.part;
            m.peak = peak_resident_bytes();
            measure_soup(small, cloud.positions, m);
        }
        measure_soup(soup, cloud.positions, p.afsr);
        return p;
    });
}

std::string mib(std::uint64_t bytes) { return fixed(static_cast<double>(bytes) / (1024.0 * 1024.0), 0); }

std::vector<std::string> method_row(const std::string& input, const std::string& method, const std::string& setting,
                                    const MethodMeasurement& m, const std::string& part, const std::string& check)
{
    const TopologyStats& t = m.topology;
    return {input,
            method,
            setting,
            m.tiles > 0 ? with_commas(m.tiles) : "",
            fixed(m.total.cpu, 2),
            part,
            mib(m.peak),
            with_commas(m.faces),
            scientific(m.distance.mean),
            scientific(m.distance.max),
            scientific(m.reverse.max),
            std::to_string(t.nonmanifold_edges) + " / " + std::to_string(t.nonmanifold_vertices),
            std::to_string(t.boundary_loops),
            t.genus < 0 ? "n/a" : std::to_string(t.genus),
            m.faces > 0 ? fixed(100.0 * static_cast<double>(m.caps) / static_cast<double>(m.faces), 1) : "",
            check};
}

void add_input_rows(Table& table, const MeshInput& input)
{
    progress("mesh: " + input.label + ": ours at " + std::to_string(kTolerances) + " tolerances ...");
    std::array<MethodMeasurement, kTolerances> ours;
    std::array<std::uint64_t, kTolerances> faces{};
    for (std::size_t i = 0; i < kTolerances; ++i)
    {
        ours[i] = measure_ours(input, kMeshTolerances[i]);
        faces[i] = ours[i].faces;
    }
    progress("mesh: " + input.label + ": ours took " + fixed(ours.back().total.cpu, 2) +
             " s CPU at the finest tolerance; AFSR + meshopt ...");
    const PeerMeasurement peers = measure_peers(input, faces);
    progress("mesh: " + input.label + ": AFSR took " + fixed(peers.afsr.total.cpu, 2) + " s CPU");

    for (std::size_t i = 0; i < kTolerances; ++i)
    {
        std::string check;
        if (i + 1 == kTolerances)
        {
            const double speedup = peers.afsr.total.cpu / ours[i].total.cpu;
            check = "AFSR / ours " + fixed(speedup, 2) + "× " + verdict(speedup >= kMinSpeedupOverAfsr);
        }
        table.rows.push_back(method_row(input.label, "ours", "tol " + fixed(kMeshTolerances[i], 3), ours[i],
                                        fixed(ours[i].part.cpu, 2), check));
    }
    table.rows.push_back(method_row(input.label, "AFSR", "all points", peers.afsr, "", ""));
    for (std::size_t i = 0; i < kTolerances; ++i)
    {
        const MethodMeasurement& m = peers.simplified[i];
        const double ratio = ours[i].distance.mean / m.distance.mean;
        table.rows.push_back(method_row(input.label, "AFSR+meshopt", with_commas(faces[i]) + " faces", m,
                                        fixed(m.part.cpu, 2),
                                        "ours / this " + fixed(ratio, 2) + "× " + verdict(ratio <= kMaxDistanceRatio)));
    }
}

Table peers_table(const std::vector<MeshInput>& inputs)
{
    Table t;
    t.title = "Reconstruction: ours vs. CGAL Advancing Front (AFSR), raw and simplified by meshoptimizer to our size";
    t.columns = {{"input", Align::Left},
                 {"method", Align::Left},
                 {"tolerance / target", Align::Left},
                 {"tiles"},
                 {"s (CPU)"},
                 {"cut+mesh / simplify s"},
                 {"peak MiB"},
                 {"faces"},
                 {"mean dist"},
                 {"max dist"},
                 {"mesh→pts max"},
                 {"non-manifold E / V"},
                 {"loops"},
                 {"genus"},
                 {"caps %"},
                 {"check", Align::Left}};
    for (const MeshInput& input : inputs)
        add_input_rows(t, input);
    t.notes = {
        "Noisy torus 1M: `shapes::torus(1000000)` + Gaussian noise σ = 0.0005 (closed, genus 1); bun_zipper.ply: "
        "the Stanford bunny scan (open at its base, holes in the scan).",
        "s (CPU): from the points in memory to the mesh, single thread. Ours: `build_hierarchy` (default options) + "
        "`cut_by_tolerance` + `mesh_cut`, each tolerance in a fresh child (so the build is counted every time; "
        "the persistent hierarchy makes later cuts cost only the cut+mesh column). AFSR: "
        "`CGAL::advancing_front_surface_reconstruction` with default parameters on all input points (1M points "
        "take well under the 3-minute limit, so no subset is used). AFSR+meshopt: AFSR + `meshopt_simplify` "
        "(no error bound, target = our face count at that tolerance; it may stop above the target).",
        "Peak MiB: the child's peak resident memory at the end of the method (input cloud and program included; "
        "the peak is reset after making the input).",
        "Distances: every input point to the closest point of the mesh's triangles "
        "(`point_to_mesh_distance`), mean and max as fractions of the points' bounding-box diagonal. AFSR "
        "interpolates the points, so its distances are those of points it left out. Mesh→pts max: the other way, "
        "from the mesh's vertices and face centroids to the nearest input point (`mesh_to_point_distance`): "
        "spikes, flaps and fills over holes where there are no points.",
        "Topology: `topology_stats` of the triangle set (peers: the raw soup, so non-manifold edges count); genus "
        "n/a = a non-manifold or non-orientable component.",
        "Caps %: faces with an angle above 150° (`count_caps`), as a share of the faces: their normals are noise, "
        "which shading draws as creases (ours flips them away, `remove_slivers`).",
        "Targets: ours ≥ " + fixed(kMinSpeedupOverAfsr, 0) + "× faster than AFSR at the finest tolerance (CPU); our "
        "mean distance ≤ " + fixed(kMaxDistanceRatio, 1) + "× that of AFSR+meshopt at the same face count."};
    return t;
}

// Writes the cloud as a binary little-endian PLY with float x y z (what scanners typically deliver).
void write_points_ply(const PointCloud& cloud, const std::filesystem::path& path)
{
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex " << cloud.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    std::vector<char> bytes(cloud.size() * 12);
    for (std::size_t i = 0; i < cloud.size(); ++i)
    {
        const Vec3 p = cloud.origin + cloud.positions[i];
        const float xyz[3] = {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
        std::memcpy(bytes.data() + 12 * i, xyz, 12);
    }
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out)
        throw std::runtime_error("cannot write " + path.string());
}

struct EndToEnd
{
    Timing read, build, mesh, write; // mesh = cut + mesh_cut
    std::uint64_t points = 0, faces = 0, ply_bytes = 0;
};

EndToEnd measure_end_to_end(std::size_t points, double tolerance)
{
    return run_in_child<EndToEnd>([&] {
        ScratchDir scratch("mesh");
        const auto input = scratch.path() / "torus.ply";
        write_points_ply(noisy_torus(points), input);
        EndToEnd e;
        PointCloud cloud;
        Hierarchy h;
        MeshResult result;
        e.read = time_call([&] { cloud = read_points(input); });
        e.points = cloud.size();
        e.build = time_call([&] { h = build_hierarchy(std::move(cloud)); });
        e.mesh = time_call([&] { result = mesh_cut(h, cut_by_tolerance(h, tolerance)); });
        const auto output = scratch.path() / "mesh.ply";
        e.write = time_call([&] { write_mesh(result.mesh, h.cloud.origin, output); });
        e.faces = result.mesh.n_faces();
        e.ply_bytes = std::filesystem::file_size(output);
        return e;
    });
}

Table end_to_end_table(std::size_t points)
{
    Table t;
    t.title = "End to end: " + short_count(points) + " points, .ply file → mesh .ply file, single thread";
    t.columns = {{"tolerance"}, {"points"},    {"read s"},  {"build s"},  {"cut+mesh s"},
                 {"write s"},   {"faces"},     {"mesh MB"}, {"total s (CPU; ≤ 5)"}, {"total s (wall)"}};
    for (const double tolerance : {kMeshTolerances.front(), kMeshTolerances.back()})
    {
        progress("mesh: end to end, " + short_count(points) + " points at tolerance " + fixed(tolerance, 3) + " ...");
        const EndToEnd e = measure_end_to_end(points, tolerance);
        const Timing total = e.read + e.build + e.mesh + e.write;
        t.rows.push_back({fixed(tolerance, 3), with_commas(e.points), fixed(e.read.cpu, 2), fixed(e.build.cpu, 2),
                          fixed(e.mesh.cpu, 2), fixed(e.write.cpu, 2), with_commas(e.faces),
                          fixed(static_cast<double>(e.ply_bytes) / 1e6, 1),
                          fixed(total.cpu, 2) + " " + verdict(total.cpu <= kMaxEndToEndSeconds), fixed(total.wall, 2)});
    }
    t.notes = {"Input: the noisy torus written first as a binary little-endian PLY of float x y z (not timed); "
               "then `read_points` → `build_hierarchy` (default options) → `cut_by_tolerance` → `mesh_cut` → "
               "`write_mesh` (binary PLY with normals), each stage timed (CPU). Target: total ≤ " +
               fixed(kMaxEndToEndSeconds, 0) + " s at every tolerance."};
    return t;
}

// The paper's Table 2 (τ_PCA,lim, t_cluster on an SGI O² R5000, N_tiles, N_points, E_RMS).
struct PaperRow
{
    double tau;
    double paper_seconds;
    std::uint64_t paper_tiles;
    std::uint64_t paper_vertices;
    double paper_e_rms;
};

struct PaperSet
{
    std::string label;
    std::function<PointCloud()> make;
    std::vector<PaperRow> rows;
};

void add_paper_rows(Table& table, const PaperSet& set)
{
    progress("mesh: paper Table 2 layout, " + set.label + " ...");
    double smallest_tau = set.rows.front().tau;
    for (const PaperRow& row : set.rows)
        smallest_tau = std::min(smallest_tau, row.tau);
    BuildOptions options;
    options.tau = smallest_tau;
    options.paper_split_order = true;
    PointCloud cloud = set.make();
    Hierarchy h;
    const Timing build = time_call([&] { h = build_hierarchy(std::move(cloud), options); });
    for (const PaperRow& row : set.rows)
    {
        Cut cut;
        MeshResult result;
        const Timing time = time_call([&] {
            cut = cut_by_tau(h, row.tau);
            result = mesh_cut(h, cut);
        });
        const QualityReport q = measure_quality(h, result.cut, result.mesh);
        table.rows.push_back({set.label, fixed(row.tau, row.tau < 1 ? 3 : 0), fixed(build.cpu, 3), fixed(time.cpu, 3),
                              fixed(row.paper_seconds, 2), with_commas(cut.size()), with_commas(row.paper_tiles),
                              with_commas(result.mesh.n_vertices()), with_commas(row.paper_vertices),
                              fixed(100.0 * q.e_rms, 3), fixed(row.paper_e_rms, 3), scientific(q.point_to_mesh.mean),
                              q.topology.genus < 0 ? "n/a" : std::to_string(q.topology.genus),
                              std::to_string(q.topology.boundary_loops)});
    }
}

Table paper_layout_table(const BenchContext& context)
{
    std::vector<PaperSet> sets;
    const auto bunny = context.data_dir / "bun_zipper.ply";
    if (std::filesystem::exists(bunny))
        sets.push_back({"Rabbit (bun_zipper.ply)", [bunny] { return read_points(bunny); },
                        {{0.006, 7.83, 50, 1110, 1.68}, {0.002, 15.05, 354, 4764, 0.049}, {0.001, 18.94, 727, 8016, 0.026}}});
    sets.push_back({"3Holes (three_holes(4000))", [] { return shapes::three_holes(4000); },
                    {{10, 0.97, 59, 762, 1.7}, {5, 1.24, 91, 1002, 0.9}, {2, 1.77, 202, 1815, 0.39}, {1, 2.38, 402, 2620, 0.19}}});
    sets.push_back({"step function (step_function(8000))", [] { return shapes::step_function(8000); },
                    {{0.001, 1.63, 60, 715, 0.0}}});

    Table t;
    t.title = "The paper's Table 2 layout: tiles, vertices and E_RMS per τ, ours beside the paper's";
    t.columns = {{"data set", Align::Left},
                 {"τ"},
                 {"build s"},
                 {"cut+mesh s"},
                 {"paper s (SGI, 1998)"},
                 {"tiles"},
                 {"paper tiles"},
                 {"vertices"},
                 {"paper vertices"},
                 {"E_RMS %"},
                 {"paper E_RMS"},
                 {"mean dist"},
                 {"genus"},
                 {"loops"}};
    for (const PaperSet& set : sets)
        add_paper_rows(t, set);
    t.notes = {"One hierarchy per data set: `BuildOptions::tau` = the set's smallest τ, `paper_split_order = true` "
               "(build s: CPU, once per set); each row `cut_by_tau(h, τ)` + `mesh_cut` (CPU). Paper s is the "
               "paper's clustering time t_cluster.",
               "Vertices: of our mesh (tile centres + boundary points), beside the paper's N_points.",
               "E_RMS %: `measure_quality(...).e_rms` (paper eq. 4-6: mean distance of a point to its tile's plane / "
               "object diameter) × 100; the paper's column is printed as published (no unit given; its "
               "magnitudes suggest percent).",
               "Mean dist: `point_to_mesh_distance` mean, fraction of the bbox diagonal. Genus and loops: "
               "`topology_stats` of the mesh (the bunny has open scan borders; 3Holes is genus 3; the step function "
               "is an open height field, genus 0 with one loop)."};
    if (!std::filesystem::exists(bunny))
        t.notes.push_back("bun_zipper.ply not found under " + context.data_dir.string() + ": its rows are skipped.");
    return t;
}

} // namespace

std::vector<Table> mesh_tables(const BenchContext& context)
{
    std::vector<MeshInput> inputs;
    if (1000000 <= context.max_points)
        inputs.push_back({"noisy torus 1M", [] { return noisy_torus(1000000); }});
    const auto bunny = context.data_dir / "bun_zipper.ply";
    if (std::filesystem::exists(bunny))
        inputs.push_back({"bun_zipper.ply", [bunny] { return read_points(bunny); }});
    else
        progress("mesh: " + bunny.string() + " not found, its rows are skipped (--data DIR)");

    std::vector<Table> tables = {peers_table(inputs)};
    if (1000000 <= context.max_points)
        tables.push_back(end_to_end_table(1000000));
    tables.push_back(paper_layout_table(context));
    return tables;
}

} // namespace mrt::bench
