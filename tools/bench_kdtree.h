#pragma once
// The reference every build is compared with: a nanoflann kd-tree over the same points (the cheapest
// spatial hierarchy one could build, so "build / kd-tree" says what the clustering costs on top).

#include "libmrtile/vec3.h"
#include "tools/bench_measure.h"

#include <cstddef>
#include <vector>

namespace mrt::bench {

// Times nanoflann::KDTreeSingleIndexAdaptor construction (L2, 3D) over `points`: the fastest of a
// few builds (at least 3, and at least 0.3 s in total, at most 20).
Timing time_kdtree_build(const std::vector<Vec3>& points, std::size_t leaf_size = 10);

} // namespace mrt::bench
