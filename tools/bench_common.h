#pragma once
// Helpers shared by the mesh, cuts and export tables of tools/bench: the generated scan they all use,
// a scratch directory for the files they write, file sizes, and small-number formatting.

#include "libmrtile/point_cloud.h"
#include "libmrtile/shapes.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

namespace mrt::bench {

inline constexpr double kScanNoiseSigma = 0.0005; // σ of the generated scans (torus: R = 1, r = 0.35)

// The generated closed scan of every table: `shapes::torus(n)` plus Gaussian noise (deterministic).
inline PointCloud noisy_torus(std::size_t n)
{
    PointCloud cloud = shapes::torus(n);
    shapes::add_noise(cloud, kScanNoiseSigma);
    return cloud;
}

// A fresh directory under the system's temp dir, removed with everything in it on destruction.
class ScratchDir
{
public:
    explicit ScratchDir(const std::string& name)
        : path_(std::filesystem::temp_directory_path() /
                ("mrtile-bench-" + name + "-" + std::to_string(static_cast<long>(::getpid()))))
    {
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~ScratchDir()
    {
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;

    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

// Total size of the regular files below `dir`, and how many there are.
struct DirectorySize
{
    std::uint64_t bytes = 0;
    std::uint64_t files = 0;
};

inline DirectorySize directory_size(const std::filesystem::path& dir)
{
    DirectorySize size;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
        if (entry.is_regular_file())
        {
            size.bytes += entry.file_size();
            ++size.files;
        }
    return size;
}

// 0.000291 -> "2.91e-04": distances as fractions of a diagonal span several decades.
inline std::string scientific(double value)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.2e", value);
    return text;
}

} // namespace mrt::bench
