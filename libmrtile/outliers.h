#pragma once
//! \file outliers.h
//! \brief Removing isolated points before the hierarchy is built (beyond the paper, opt-in).
//! \details Raw scans carry points that belong to no surface: mixed pixels at silhouettes, dust, stray
//! returns. The hierarchy has no notion of them: a cluster holding one is far from planar, so it is split
//! again and again, and the stray points end up as vertices of spikes and bridges in the mesh (the bunny
//! with 1% of its points added uniformly in its box: 354 of 4,272 vertices more than 1% of the diagonal
//! off the surface). How isolated a point is: the mean distance d(p) to its k nearest neighbours. A point
//! is an outlier when d(p) exceeds `local_ratio` × the median d of those neighbours (it stands apart
//! from the surface next to it; density changes across the cloud do not matter), or `global_ratio` ×
//! the median d over the whole cloud (far from any surface, e.g. among other stray points, whose own
//! neighbours are as sparse as they are). The global test assumes a roughly even density, as object
//! scans have; for scene scans whose density falls with the range, set global_ratio to 0.

#include "libmrtile/point_cloud.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mrt {

struct OutlierOptions
{
    //! k: neighbours whose mean distance measures how isolated a point is.
    std::size_t neighbours = 8;
    //! Outlier when d(p) > local_ratio × the median d of its k neighbours (0 = no local test).
    double local_ratio = 3.0;
    //! Outlier when d(p) > global_ratio × the median d of all points (0 = no global test).
    double global_ratio = 6.0;
    //! Threads for the neighbour queries (0 = one per hardware thread). The result does not depend on it.
    std::size_t threads = 0;
};

//! \brief Indices of the outliers among `positions`, ascending. Deterministic.
//! \details A cloud of at most `neighbours` points has none. Exact duplicates are nobody's outliers: a
//! test whose median distance is 0 is skipped.
//! \throw InvalidInput if neighbours is 0, a ratio is negative or NaN, or a position is not finite.
std::vector<std::uint32_t> find_outliers(const std::vector<Vec3>& positions, const OutlierOptions& options = {});

//! \brief Removes the outliers (positions and their colours) in place; returns how many went.
//! \throw InvalidInput as find_outliers, or unless the colours are empty or one per position (check_colors).
std::size_t remove_outliers(PointCloud& cloud, const OutlierOptions& options = {});

} // namespace mrt
