// Beyond the paper: whether the input samples a surface at all. The method (and every surface
// reconstruction) assumes a surface sample; points that fill a volume are meshed slowly into pieces of
// no use, so the command line refuses them before meshing. See sample_dimension.h for the measures.

#include "libmrtile/sample_dimension.h"

#include "libmrtile/errors.h"
#include "libmrtile/median.h"
#include "libmrtile/neighbours.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mrt {

namespace {

// The mean local dimension of every k-th of `positions` (see the file comment of the header), which are
// in the tree's order: spatially even, where every k-th point of a file can be one row of a grid.
void measure_dimension(const std::vector<Vec3>& positions, const DimensionOptions& options, SampleDimension& out)
{
    const std::size_t stride = (positions.size() + options.max_points - 1) / options.max_points;
    std::vector<Vec3> thinned;
    thinned.reserve(positions.size() / std::max<std::size_t>(1, stride) + 1);
    for (std::size_t i = 0; i < positions.size(); i += stride)
        thinned.push_back(positions[i]);
    if (thinned.size() < 8 * options.far)
        return;
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
    if (out.sampled > 0)
        out.mean_dimension = sum / static_cast<double>(out.sampled);
}

// The median over the leaves of at least 8 points of sqrt(λ0 / λ1) of their points as read: the
// leaves' own frames where the points were not moved (eigen_decomposition of the same moments), the
// raw positions' where denoising moved them.
double median_leaf_roughness(const Hierarchy& h)
{
    std::vector<double> roughness;
    for (const Node& n : h.nodes) {
        if (!n.is_leaf() || n.count() < 8)
            continue;
        Eigen3x3 e = n.frame;
        if (!h.raw_positions.empty()) {
            Moments m;
            for (std::uint32_t i = n.begin; i < n.end; ++i)
                m.add(h.raw_positions[i]);
            e = eigen_decomposition(m);
        }
        roughness.push_back(e.values[1] > 0.0 ? std::sqrt(e.values[0] / e.values[1]) : 0.0);
    }
    return upper_median_in_place(roughness);
}

} // namespace

SampleDimension sample_dimension(const Hierarchy& h, const DimensionOptions& options)
{
    if (options.near < 2 || options.far <= options.near || options.samples == 0 || options.max_points == 0 ||
        !std::isfinite(options.volume_dimension) || !std::isfinite(options.volume_roughness))
        throw InvalidInput("DimensionOptions: near at least 2, far above near, samples and max_points at least 1, "
                           "finite thresholds");
    const std::vector<Vec3>& positions = h.raw_positions.empty() ? h.cloud.positions : h.raw_positions;
    SampleDimension out;
    measure_dimension(positions, options, out);
    out.leaf_roughness = median_leaf_roughness(h);
    out.fills_volume = out.sampled > 0 && out.mean_dimension >= options.volume_dimension &&
                       out.leaf_roughness >= options.volume_roughness;
    return out;
}

} // namespace mrt
