// tools/bench: the benchmark program. Speed and memory targets are checked here (never in unit tests);
// it prints markdown tables for the README. Each suite is one function returning tables; the registry
// below maps `--only` names to them, so adding a table is one function and one line.
#include "tools/bench.h"
#include "tools/bench_measure.h"
#include "tools/huge_page_malloc.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <sstream>

namespace mrt::bench {

void progress(const std::string& message) { std::cerr << "[bench] " << message << std::endl; }

namespace {

const std::vector<BenchSuite>& suites()
{
    static const std::vector<BenchSuite> all = {
        {"hierarchy", "hierarchy build: speed, peak memory, model size vs. a nanoflann kd-tree", hierarchy_tables},
        {"paper", "the paper's Table 2: bunny tile counts at τ = 0.006, 0.002, 0.001", paper_tables},
        {"mesh", "reconstruction vs. CGAL AFSR (+ meshoptimizer), 1M points end to end, the paper's Table 2 layout", mesh_tables},
        {"cuts", "budget and focus cuts + meshing from a loaded 4M-point model; model file size", cuts_tables},
        {"export", "3D Tiles export of a 1M-point model (glTF, Draco); Draco size vs. draco_encoder", export_tables},
        {"noise", "noisy shapes and scans: the noise floor alone vs. denoised, loops, pieces, distance to the clean points", noise_tables},
    };
    return all;
}

std::vector<std::string> split_list(const std::string& list)
{
    std::vector<std::string> names;
    std::stringstream in(list);
    std::string name;
    while (std::getline(in, name, ','))
        if (!name.empty())
            names.push_back(name);
    return names;
}

} // namespace
} // namespace mrt::bench

int main(int argc, char** argv)
{
    using namespace mrt::bench;
    // As the CLI runs (huge_page_malloc.h); GLIBC_TUNABLES=glibc.malloc.hugetlb=0 measures without.
    mrt::tools::use_huge_page_malloc(argv);
    BenchContext context;
    context.data_dir = MRTILE_SHARED_DATA;
    std::string only;
    bool list = false;

    CLI::App app{"libmrtile benchmarks: prints markdown tables to stdout, progress to stderr"};
    app.add_option("--only", only, "comma-separated suites to run (default: all; see --list)");
    app.add_option("--data", context.data_dir, "directory of the shared real scans (bun_zipper.ply)")
        ->capture_default_str();
    app.add_option("--max-points", context.max_points, "skip generated inputs larger than this")
        ->capture_default_str();
    app.add_flag("--list", list, "list the suites and exit");
    CLI11_PARSE(app, argc, argv);

    if (list)
    {
        for (const BenchSuite& s : suites())
            std::cout << s.name << "\t" << s.description << "\n";
        return 0;
    }
    std::vector<const BenchSuite*> selected;
    for (const BenchSuite& s : suites())
        selected.push_back(&s);
    if (!only.empty())
    {
        selected.clear();
        for (const std::string& name : split_list(only))
        {
            const auto it = std::find_if(suites().begin(), suites().end(),
                                         [&](const BenchSuite& s) { return name == s.name; });
            if (it == suites().end())
            {
                std::cerr << "bench: unknown suite '" << name << "' in --only (see --list)\n";
                return 2;
            }
            selected.push_back(&*it);
        }
    }

#ifndef __OPTIMIZE__
    progress("warning: this is an unoptimised build; use tools/bench.sh (Release) for real numbers");
#endif
    const std::string load_before = load_average();
    const auto start = std::chrono::steady_clock::now();
    try
    {
        for (const BenchSuite* s : selected)
            for (const Table& table : s->run(context))
                print_markdown(table, std::cout);
    }
    catch (const std::exception& e)
    {
        std::cerr << "bench: " << e.what() << "\n";
        return 1;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "_Machine: " << load_before << " before, " << load_average() << " after; heap: " << mrt::tools::heap_setting()
              << " (as the CLI runs); benchmark took " << fixed(seconds, 0) << " s._\n";
    return 0;
}
