// Reference timing for the hierarchy build: a nanoflann kd-tree over the same points. The only file of
// the benchmark that includes nanoflann.
#include "tools/bench_kdtree.h"

#include <nanoflann.hpp>

#include <cstdint>
#include <stdexcept>

namespace mrt::bench {
namespace {

// nanoflann's dataset interface over our positions, read in place (no copy).
struct PositionsAdaptor
{
    const std::vector<Vec3>& points;

    std::size_t kdtree_get_point_count() const { return points.size(); }
    double kdtree_get_pt(std::size_t i, std::size_t axis) const { return points[i][static_cast<int>(axis)]; }
    // false: let nanoflann compute the bounding box, as it would for any user.
    template <class Box>
    bool kdtree_get_bbox(Box&) const
    {
        return false;
    }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PositionsAdaptor>,
                                                   PositionsAdaptor, 3, std::uint32_t>;

} // namespace

Timing time_kdtree_build(const std::vector<Vec3>& points, std::size_t leaf_size)
{
    const PositionsAdaptor adaptor{points};
    std::size_t indexed = 0;
    const Timing t = time_fastest(
        [&] {
            const KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size));
            indexed = tree.vAcc.size();
        },
        3, 20, 0.3);
    if (indexed != points.size())
        throw std::runtime_error("kd-tree indexed " + std::to_string(indexed) + " of " +
                                 std::to_string(points.size()) + " points");
    return t;
}

} // namespace mrt::bench
