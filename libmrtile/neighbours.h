#pragma once
//! \file neighbours.h
//! \brief The k nearest neighbours of the points of a cloud, for the point-wise stages that run
//! before the hierarchy exists (outlier removal, denoising): a kd-tree over the points that answers
//! for points of its own cloud only, starting from each point's leaf.

#include "libmrtile/vec3.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

namespace mrt {

class NearestNeighbours
{
public:
    //! Builds the search structure over `positions` (finite), which must outlive this object.
    explicit NearestNeighbours(const std::vector<Vec3>& positions);
    //! The positions are kept by reference: a temporary would be gone before the first query.
    explicit NearestNeighbours(std::vector<Vec3>&& positions) = delete;
    ~NearestNeighbours();
    NearestNeighbours(const NearestNeighbours&) = delete;
    NearestNeighbours& operator=(const NearestNeighbours&) = delete;

    //! \brief The (at most) `k` nearest other points of point `i`, nearest first: their indices and
    //! distances. A duplicate of the point counts as another point; the point itself never does.
    //! Safe to call from several threads at once; the result depends on the positions only.
    //! Exact: no point left out is nearer than the k-th; which of the points tied at the k-th
    //! distance are returned is up to the search (deterministic). `within`, when given, is a distance that holds k other
    //! points around point i: the k-th distance of another point j plus the distance from j to i
    //! (j's neighbours and j itself, less i, are k points within it). Querying the points one after
    //! the other in order(), each with the bound of the one before (for_each_point), searches far
    //! fewer points; the result is the same up to those ties (a radius that holds fewer is searched
    //! again without).
    void query(std::uint32_t i, std::size_t k, std::vector<std::uint32_t>& index, std::vector<double>& distance,
               double within = std::numeric_limits<double>::infinity()) const;

    //! The points' indices in the tree's order (nearby points mostly consecutive).
    const std::vector<std::uint32_t>& order() const;

    //! \brief Calls visit(i, index, distance) with the `k` nearest neighbours of every point i, as
    //! query gives them, on up to `threads` threads (0 = the default, parallel.h): the points in
    //! order(), each queried with the radius of the one before. `visit` is called from several
    //! threads at once, never twice for a point; what each call gets does not depend on the threads.
    using Visit = std::function<void(std::uint32_t i, const std::vector<std::uint32_t>& index, const std::vector<double>& distance)>;
    void for_each_point(std::size_t k, std::size_t threads, const Visit& visit) const;

private:
    const std::vector<Vec3>* positions_;
    struct Tree;
    std::unique_ptr<Tree> tree_;
};

} // namespace mrt
