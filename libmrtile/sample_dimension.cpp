// Beyond the paper: whether the input samples a surface at all. The method (and every surface
// reconstruction) assumes a surface sample; points that fill a volume are meshed slowly into pieces of
// no use, so the command line refuses them up front. See sample_dimension.h for the measure.

#include "libmrtile/sample_dimension.h"

#include "libmrtile/errors.h"
#include "libmrtile/neighbours.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace mrt {

SampleDimension sample_dimension(const std::vector<Vec3>& positions, const DimensionOptions& options)
{
    if (options.near < 2 || options.far <= options.near || options.samples == 0 || options.max_points == 0 ||
        !std::isfinite(options.volume_dimension))
        throw InvalidInput("DimensionOptions: near at least 2, far above near, samples and max_points at least 1, "
                           "a finite volume_dimension");
    for (const Vec3& p : positions)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw InvalidInput("sample_dimension: a position is not finite");
    SampleDimension out;
    const std::size_t stride = (positions.size() + options.max_points - 1) / options.max_points;
    std::vector<Vec3> thinned;
    thinned.reserve(positions.size() / std::max<std::size_t>(1, stride) + 1);
    for (std::size_t i = 0; i < positions.size(); i += stride)
        thinned.push_back(positions[i]);
    if (thinned.size() < 8 * options.far)
        return out;
    const NearestNeighbours neighbours(thinned);
    const std::size_t step = std::max<std::size_t>(1, thinned.size() / options.samples);
    const double log_ratio = std::log(static_cast<double>(options.far) / static_cast<double>(options.near));
    std::vector<std::uint32_t> index;
    std::vector<double> distance;
    double sum = 0.0;
    for (std::size_t i = 0; i < thinned.size() && out.sampled < options.samples; i += step) {
        neighbours.query(static_cast<std::uint32_t>(i), options.far, index, distance);
        if (distance.size() < options.far)
            continue;
        const double inner = distance[options.near - 1], outer = distance.back();
        // A clump of equal points has no scale to grow from; it says nothing of the dimension.
        if (!(inner > 0.0) || !(outer > inner))
            continue;
        sum += log_ratio / std::log(outer / inner);
        ++out.sampled;
    }
    if (out.sampled > 0) {
        out.mean_dimension = sum / static_cast<double>(out.sampled);
        out.fills_volume = out.mean_dimension >= options.volume_dimension;
    }
    return out;
}

} // namespace mrt
