// Input handling shared by every stage: bounding box, origin shift and validation. Not part of the
// paper's method; it exists so that every later stage can assume finite, origin-centred positions.
#include "libmrtile/point_cloud.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <cmath>

namespace mrt {

double BoundingBox::largest_side() const
{
    const Vec3 s = size();
    return std::max({s.x, s.y, s.z});
}

double BoundingBox::diagonal() const { return norm(size()); }

BoundingBox bounding_box(const std::vector<Vec3>& positions)
{
    BoundingBox box;
    if (positions.empty())
        return box;
    box.min = box.max = positions.front();
    for (const Vec3& p : positions) {
        box.min = min(box.min, p);
        box.max = max(box.max, p);
    }
    return box;
}

void recenter(PointCloud& cloud)
{
    if (cloud.empty())
        return;
    const Vec3 c = bounding_box(cloud.positions).centre();
    // A whole-number shift is exact in double for any realistic coordinate, so origin + position
    // reproduces the input to the last bit the input had.
    const Vec3 shift{std::round(c.x), std::round(c.y), std::round(c.z)};
    if (shift == Vec3{})
        return;
    for (Vec3& p : cloud.positions)
        p -= shift;
    cloud.origin += shift;
}

void validate(const PointCloud& cloud, const std::string& what)
{
    if (cloud.empty())
        throw InvalidInput(what + ": no points");
    if (!cloud.colors.empty() && cloud.colors.size() != cloud.positions.size())
        throw InvalidInput(what + ": " + std::to_string(cloud.colors.size()) + " colours for " +
                           std::to_string(cloud.positions.size()) + " points");
    if (!is_finite(cloud.origin))
        throw InvalidInput(what + ": origin is not finite");
    for (std::size_t i = 0; i < cloud.positions.size(); ++i)
        if (!is_finite(cloud.positions[i]))
            throw InvalidInput(what + ": point " + std::to_string(i) + " has a NaN or infinite coordinate");
}

} // namespace mrt
