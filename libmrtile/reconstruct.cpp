// Glue of the method's stages (paper Fig. 1: clustering → tiles → reconstruction) and the error
// measures of paper §5 (eq. 4-6), so the CLI, the demo and the benchmarks all run the same pipeline.
#include "libmrtile/reconstruct.h"

#include "libmrtile/errors.h"

#include <chrono>
#include <cmath>

namespace mrt {

MeshResult mesh_cut(const Hierarchy& h, const Cut& cut, const MeshOptions& options)
{
    if (!is_partition(h, cut))
        throw InvalidInput("mesh: the cut is not a partition of the model's points");
    const auto start = std::chrono::steady_clock::now();
    MeshResult result;
    const std::vector<Tile> tiles = make_tiles(h, cut, options.tiles);
    result.tiles = tiles.size();
    result.mesh = build_surface(h, tiles, options.surface, &result.surface);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

double e_rms(const Hierarchy& h, const Cut& cut)
{
    double sum = 0.0;
    for (std::int32_t id : cut) {
        const Node& n = h.nodes[static_cast<std::size_t>(id)];
        const Vec3 normal = n.frame.vectors[0];
        for (std::uint32_t i = n.begin; i < n.end; ++i)
            sum += std::abs(dot(h.cloud.positions[i] - n.centre(), normal));
    }
    const double diameter = h.bbox().largest_side();
    const auto count = static_cast<double>(h.cloud.size());
    return diameter > 0 && count > 0 ? sum / (count * diameter) : 0.0;
}

QualityReport measure_quality(const Hierarchy& h, const Cut& cut, const Mesh& mesh)
{
    QualityReport q;
    q.topology = topology_stats(mesh);
    q.e_rms = e_rms(h, cut);
    if (mesh.n_faces() > 0 && h.bbox().diagonal() > 0)
        q.point_to_mesh = point_to_mesh_distance(h.cloud.positions, mesh);
    return q;
}

} // namespace mrt
