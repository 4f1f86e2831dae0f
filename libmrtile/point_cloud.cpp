// Input handling shared by every stage: bounding box, origin shift and validation. Not part of the
// paper's method; it exists so that every later stage can assume finite, origin-centred positions.
#include "libmrtile/point_cloud.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>

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

namespace {

std::uint64_t mix(std::uint64_t h, double value)
{
    value += 0.0; // -0 and +0 compare equal: give them one bit pattern
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    h ^= bits + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    // splitmix64 finalizer: the low bits index the table, so every input bit must reach them
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebull;
    return h ^ (h >> 31);
}

} // namespace

std::vector<std::uint32_t> first_occurrences(const std::vector<Vec3>& positions)
{
    const std::size_t n = positions.size();
    assert(n < std::numeric_limits<std::uint32_t>::max());
    std::size_t size = 16;
    while (size < 2 * n)
        size *= 2;
    // Open addressing, linear probing. A slot holds the index + 1 of the first point seen there (low
    // half; 0 = empty) and the hash's high half as a tag, so a probe past another position rarely has
    // to load that position (the table is random access; the positions would be a second miss).
    std::vector<std::uint64_t> slots(size, 0);
    std::vector<std::uint32_t> kept;
    kept.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3& p = positions[i];
        const std::uint64_t hash = mix(mix(mix(0, p.x), p.y), p.z);
        const std::uint64_t tag = hash & 0xffffffff00000000ull;
        for (std::size_t s = static_cast<std::size_t>(hash) & (size - 1);; s = (s + 1) & (size - 1)) {
            const std::uint64_t slot = slots[s];
            if (slot == 0) {
                slots[s] = tag | static_cast<std::uint64_t>(i + 1);
                kept.push_back(static_cast<std::uint32_t>(i));
                break;
            }
            if ((slot & 0xffffffff00000000ull) == tag && positions[(slot & 0xffffffffull) - 1] == p)
                break; // a duplicate of an earlier point
        }
    }
    return kept;
}

std::vector<std::uint32_t> remove_duplicates(PointCloud& cloud)
{
    std::vector<std::uint32_t> kept = first_occurrences(cloud.positions);
    if (kept.size() == cloud.positions.size())
        return kept;
    // kept is increasing, so compacting in place never overwrites a point still to be read.
    for (std::size_t k = 0; k < kept.size(); ++k) {
        cloud.positions[k] = cloud.positions[kept[k]];
        if (cloud.has_colors())
            cloud.colors[k] = cloud.colors[kept[k]];
    }
    cloud.positions.resize(kept.size());
    if (cloud.has_colors())
        cloud.colors.resize(kept.size());
    return kept;
}

} // namespace mrt
