#pragma once
// tools/bench: the benchmark program. Each group of tables is a BenchSuite registered in bench.cpp;
// adding one = a function returning tables (in its own tools/bench_<name>.cpp) + one registry line.

#include "tools/bench_table.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace mrt::bench {

struct BenchContext
{
    std::filesystem::path data_dir;       // the shared real scans (bun_zipper.ply, ...)
    std::uint64_t max_points = 4000000;   // generated inputs larger than this are skipped
};

struct BenchSuite
{
    const char* name;        // for --only
    const char* description; // for --list
    std::vector<Table> (*run)(const BenchContext&);
};

// Progress lines go to stderr so that stdout holds only the markdown.
void progress(const std::string& message);

// Table 1: hierarchy build speed and memory against a kd-tree, on generated and real scans.
std::vector<Table> hierarchy_tables(const BenchContext& context);
// Table 2 of the paper: tile counts for the bunny at the paper's three τ.
std::vector<Table> paper_tables(const BenchContext& context);
// Reconstruction against CGAL AFSR and meshoptimizer; end to end; the paper's Table 2 layout (bench_mesh.cpp).
std::vector<Table> mesh_tables(const BenchContext& context);
// Cuts and meshing from a loaded model (bench_cuts.cpp).
std::vector<Table> cuts_tables(const BenchContext& context);
// 3D Tiles export and Draco size (bench_export.cpp).
std::vector<Table> export_tables(const BenchContext& context);
// Noisy samples: the noise floor alone vs. denoised (bench_noise.cpp).
std::vector<Table> noise_tables(const BenchContext& context);

} // namespace mrt::bench
