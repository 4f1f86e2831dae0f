#pragma once
//! \file neighbours.h
//! \brief The k nearest neighbours of the points of a cloud, for the point-wise stages that run
//! before the hierarchy exists (outlier removal, denoising). Wraps CGAL's kd-tree.

#include "libmrtile/vec3.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace mrt {

class NearestNeighbours
{
public:
    //! Builds the search structure over `positions` (finite), which must outlive this object.
    explicit NearestNeighbours(const std::vector<Vec3>& positions);
    ~NearestNeighbours();
    NearestNeighbours(const NearestNeighbours&) = delete;
    NearestNeighbours& operator=(const NearestNeighbours&) = delete;

    //! \brief The (at most) `k` nearest other points of point `i`, nearest first: their indices and
    //! distances. A duplicate of the point counts as another point; the point itself never does.
    //! Safe to call from several threads at once; the result depends on the positions only.
    void query(std::uint32_t i, std::size_t k, std::vector<std::uint32_t>& index, std::vector<double>& distance) const;

private:
    struct Tree;
    std::unique_ptr<Tree> tree_;
};

} // namespace mrt
