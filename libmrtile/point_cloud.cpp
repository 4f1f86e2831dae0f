// Input handling shared by every stage: bounding box, origin shift, validation, duplicate merging and
// the length tolerances are relative to. Not part of the paper's method; it exists so that every later
// stage can assume finite, origin-centred, distinct positions, and a scale that a few stray points do not
// decide.
#include "libmrtile/point_cloud.h"

#include "libmrtile/errors.h"
#include "libmrtile/huge_pages.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdio>
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
    return bounding_box(positions.data(), positions.size());
}

BoundingBox bounding_box(const Vec3* positions, std::size_t count)
{
    BoundingBox box;
    if (count == 0)
        return box;
    box.min = box.max = positions[0];
    for (std::size_t i = 1; i < count; ++i) {
        box.min = min(box.min, positions[i]);
        box.max = max(box.max, positions[i]);
    }
    return box;
}

void recenter(PointCloud& cloud)
{
    if (cloud.empty())
        return;
    // The median, not the box centre: a few stray points far away (a sensor glitch at 1e20) would put
    // a box centre so far from the rest that, shifted by it, the real points lose their digits. A
    // strided sample of at most 65,536 points keeps this cheap and deterministic.
    const std::size_t stride = sample_stride(cloud.size(), 65536);
    std::vector<double> axis;
    auto median = [&](double Vec3::*coordinate) {
        axis.clear();
        for (std::size_t i = 0; i < cloud.size(); i += stride)
            axis.push_back(cloud.positions[i].*coordinate);
        const auto middle = axis.begin() + static_cast<std::ptrdiff_t>(axis.size() / 2);
        std::nth_element(axis.begin(), middle, axis.end());
        return *middle;
    };
    // An axis on which the points straddle 0 is left as it is: no shift, no rounding, every digit kept.
    // Elsewhere (georeferenced input, 10^6 and up) a whole-number shift near the points keeps the
    // digits that matter; origin + position gives the input back to within its last bit.
    const BoundingBox box = bounding_box(cloud.positions);
    auto shift_along = [&](double Vec3::*coordinate) {
        return box.min.*coordinate <= 0.0 && box.max.*coordinate >= 0.0 ? 0.0 : std::round(median(coordinate));
    };
    const Vec3 shift{shift_along(&Vec3::x), shift_along(&Vec3::y), shift_along(&Vec3::z)};
    if (shift == Vec3{})
        return;
    for (Vec3& p : cloud.positions)
        p -= shift;
    if (cloud.viewpoint)
        *cloud.viewpoint -= shift;
    cloud.origin += shift;
}

void append(PointCloud& into, PointCloud from)
{
    if (into.empty()) {
        into = std::move(from);
        return;
    }
    const Vec3 shift = from.origin - into.origin;
    if (!into.viewpoint || !from.viewpoint || *into.viewpoint != *from.viewpoint + shift)
        into.viewpoint.reset();
    if (into.crs != from.crs)
        into.crs.clear(); // coordinates in different systems have none in common
    into.coarse_coordinates.insert(into.coarse_coordinates.end(), from.coarse_coordinates.begin(),
                                   from.coarse_coordinates.end());
    const std::size_t old_size = into.positions.size();
    into.positions.reserve(old_size + from.positions.size());
    for (const Vec3& p : from.positions)
        into.positions.push_back(p + shift);
    if (into.has_colors() || from.has_colors()) {
        const std::array<std::uint8_t, 4> white = {255, 255, 255, 255};
        into.colors.resize(old_size, white);
        if (from.has_colors())
            into.colors.insert(into.colors.end(), from.colors.begin(), from.colors.end());
        else
            into.colors.resize(into.positions.size(), white);
    }
}

void check_colors(const PointCloud& cloud, const std::string& what)
{
    if (!cloud.colors.empty() && cloud.colors.size() != cloud.positions.size())
        throw InvalidInput(what + ": " + std::to_string(cloud.colors.size()) + " colours for " +
                           std::to_string(cloud.positions.size()) + " points");
}

void validate(const PointCloud& cloud, const std::string& what)
{
    if (cloud.empty())
        throw InvalidInput(what + ": no points");
    check_colors(cloud, what);
    if (!is_finite(cloud.origin))
        throw InvalidInput(what + ": origin is not finite");
    if (cloud.viewpoint && !is_finite(*cloud.viewpoint))
        throw InvalidInput(what + ": the viewpoint is not finite");
    for (std::size_t i = 0; i < cloud.positions.size(); ++i)
        if (!is_finite(cloud.positions[i]))
            throw InvalidInput(what + ": point " + std::to_string(i) + " has a NaN or infinite coordinate");
    // Finite is not enough: squared distances and the moments of the cut's clusters would overflow, and
    // glTF's 32-bit floats end at 3.4e38. No scene spans 1e30 units; a file that does is corrupt or has
    // stray points far from the rest.
    const BoundingBox box = bounding_box(cloud.positions);
    const double side = box.largest_side();
    if (!(side <= kMaxExtent)) {
        const Vec3 size = box.size();
        const int a = size.x == side ? 0 : size.y == side ? 1 : 2;
        char range[128];
        std::snprintf(range, sizeof range, "%c from %.6g to %.6g", "xyz"[a], (cloud.origin + box.min)[a],
                      (cloud.origin + box.max)[a]);
        throw InvalidInput(what + ": the points span " + range + ", more than the 1e30 units a mesh can have (a corrupt "
                           "file, or stray points far from the rest: remove them)");
    }
    // A sphere 1e-200 across was refused as "collinear or coincident", one 1e-100 across as "every piece
    // is a small detached island", and one 1e-160 across gave NaN distances: the scale was the cause.
    if (side > 0.0 && side < kMinExtent) {
        char size[64];
        std::snprintf(size, sizeof size, "%.6g", side);
        throw InvalidInput(what + ": the points span at most " + size + " units (the largest side of their box), less "
                           "than the 1e-30 a mesh can have (32-bit floats and squared distances lose their digits): "
                           "scale them up");
    }
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

double tolerance_scale(const std::vector<Vec3>& positions)
{
    constexpr double kPercentile = 0.01;
    constexpr std::size_t kSampleSize = 65536;
    const BoundingBox full = bounding_box(positions);
    const std::size_t n = positions.size();
    if (n < 200) // the percentiles of a small cloud are its extremes
        return full.largest_side();
    // Sample every k-th point by hash of its position, so that the sample does not depend on the order
    // (the build sees the input's order, a loaded model the tree's).
    const std::uint64_t k = std::max<std::uint64_t>(1, n / kSampleSize);
    std::array<std::vector<double>, 3> sample;
    for (std::vector<double>& axis : sample)
        axis.reserve(2 * (n / k) + 16); // about n / k are taken: no regrowth copies
    for (const Vec3& p : positions)
        if (k == 1 || mix(mix(mix(0, p.x), p.y), p.z) % k == 0)
            for (int axis = 0; axis < 3; ++axis)
                sample[static_cast<std::size_t>(axis)].push_back(p[axis]);
    const std::size_t m = sample[0].size();
    if (m < 200)
        return full.largest_side();
    BoundingBox core;
    const std::size_t lo = static_cast<std::size_t>(kPercentile * static_cast<double>(m - 1));
    const std::size_t hi = m - 1 - lo;
    for (int axis = 0; axis < 3; ++axis) {
        std::vector<double>& v = sample[static_cast<std::size_t>(axis)];
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(lo), v.end());
        core.min[axis] = v[lo];
        std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(hi), v.end());
        core.max[axis] = v[hi];
    }
    const double reach = core.largest_side();
    if (!(reach > 0))
        return full.largest_side();
    const Vec3 margin{reach, reach, reach};
    const Vec3 lo_limit = core.min - margin, hi_limit = core.max + margin;
    auto inside = [&](const Vec3& p) {
        return p.x >= lo_limit.x && p.y >= lo_limit.y && p.z >= lo_limit.z && p.x <= hi_limit.x && p.y <= hi_limit.y &&
               p.z <= hi_limit.z;
    };
    if (inside(full.min) && inside(full.max))
        return full.largest_side(); // no far point: the common case
    BoundingBox kept;
    bool any = false;
    for (const Vec3& p : positions)
        if (inside(p)) {
            kept.min = any ? min(kept.min, p) : p;
            kept.max = any ? max(kept.max, p) : p;
            any = true;
        }
    return kept.largest_side();
}

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
    // Both written once, at random and in order: fresh memory, so huge pages (huge_pages.h).
    std::vector<std::uint64_t> slots;
    reserve_on_huge_pages(slots, size);
    slots.resize(size, 0);
    std::vector<std::uint32_t> kept;
    reserve_on_huge_pages(kept, n);
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
    check_colors(cloud, "remove_duplicates");
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
