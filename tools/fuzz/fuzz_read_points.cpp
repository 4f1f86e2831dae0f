// Fuzz target for the point readers (formats/read_points.h): any bytes, under any of the extensions the
// readers dispatch on (gzip-compressed ones too: their readers cannot check counts against a file size), must give a cloud or one of our two exceptions, never a crash, a hang, an
// out-of-memory or another exception. The readers take paths (they stream from files), so the input is
// written to a file named by its first byte's pick of extension.
#include "formats/read_points.h"
#include "libmrtile/errors.h"

#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace {

const char* const kExtensions[] = {".ply", ".xyz", ".pts", ".txt", ".csv", ".obj", ".off", ".las", ".ptx",
                                   ".pcd", ".ply.gz", ".xyz.gz", ".conf", ".laz", ".pcd.gz", ".las.gz", ".ptx.gz"};

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    if (size == 0)
        return 0;
    const std::size_t count = sizeof kExtensions / sizeof kExtensions[0];
    const std::string path = "/dev/shm/mrtile_fuzz_" + std::to_string(getpid()) + kExtensions[data[0] % count];
    const std::string extension = kExtensions[data[0] % count];
    if (extension.size() > 3 && extension.compare(extension.size() - 3, 3, ".gz") == 0) {
        // Compressed for real, so that the reader cannot know the size (zlib would read raw bytes as they are).
        gzFile out = gzopen(path.c_str(), "wb1");
        if (size > 1)
            gzwrite(out, data + 1, static_cast<unsigned>(size - 1));
        gzclose(out);
    } else {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    }
    mrt::ReadOptions options;
    options.max_points = 1u << 20; // the harness's memory, not a reader limit under test
    try {
        const mrt::PointCloud cloud = mrt::read_points(path, options);
        for (const mrt::Vec3& p : cloud.positions)
            if (!(std::abs(p.x) <= 1e300 && std::abs(p.y) <= 1e300 && std::abs(p.z) <= 1e300))
                std::abort(); // a non-finite point got through
    } catch (const mrt::InvalidInput&) {
    } catch (const mrt::IoError&) {
    }
    std::remove(path.c_str());
    return 0;
}
