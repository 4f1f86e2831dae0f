// Point input (formats/): placeholder XYZ reader until the streaming readers land.
#include "formats/read_points.h"

#include "libmrtile/errors.h"

#include <fstream>
#include <sstream>

namespace mrt {

PointCloud read_points(const std::filesystem::path& path, const ReadOptions&)
{
    std::ifstream in(path);
    if (!in)
        throw IoError(path.string() + ": cannot open");
    PointCloud c;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        Vec3 p;
        if (ls >> p.x >> p.y >> p.z)
            c.positions.push_back(p);
    }
    validate(c, path.string());
    recenter(c);
    return c;
}

} // namespace mrt
