#pragma once
//! \file box_grid.h
//! \brief Items (a mesh's faces) filed by the cubic grid cells their bounding boxes overlap, so that the
//! items near a box are found in time proportional to what lies there: the faces a hole's cap could
//! cross (surface_holes.cpp), the faces an edit could cross (untangle.cpp).
//! \details Cells are hashed on 21 bits per axis: far cells may share a key, which gives more
//! candidates, never fewer (callers test every candidate exactly). An item whose box overlaps more than
//! kMaxCellsPerItem cells is kept apart and is a candidate of every query: a face reaching a stray point
//! 10^6 cell sizes away would otherwise be filed in 10^18 cells (QA round 34: a 300-point sphere with 28
//! such strays filled 24 GB).

#include "libmrtile/point_cloud.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace mrt {

//! The bounding box of a triangle, as filed in a BoxGrid.
inline BoundingBox triangle_box(const std::array<Vec3, 3>& t)
{
    return {min(min(t[0], t[1]), t[2]), max(max(t[0], t[1]), t[2])};
}

class BoxGrid
{
public:
    static constexpr double kMaxCellsPerItem = 4096.0;

    explicit BoxGrid(double cell) : cell_(cell) {}

    //! The number of cells `box` overlaps (a double: it can exceed any integer type).
    double cell_count(const BoundingBox& box) const
    {
        const auto [lo, hi] = cells(box);
        return static_cast<double>(hi[0] - lo[0] + 1) * static_cast<double>(hi[1] - lo[1] + 1) *
               static_cast<double>(hi[2] - lo[2] + 1);
    }

    //! Files item `id` under every cell `box` overlaps. Filing an item again (it moved) is allowed:
    //! its old entries stay, and callers test each candidate's current box.
    void insert(std::uint32_t id, const BoundingBox& box)
    {
        if (cell_count(box) > kMaxCellsPerItem) {
            if (id >= is_oversized_.size())
                is_oversized_.resize(std::size_t{id} + 1, 0);
            if (!is_oversized_[id]) {
                is_oversized_[id] = 1;
                oversized_.push_back(id);
            }
            return;
        }
        for_each_cell(box, [&](std::uint64_t key) {
            std::vector<std::uint32_t>& list = cells_[key];
            if (list.empty() || list.back() != id)
                list.push_back(id);
        });
    }

    //! Calls visit(id) for the items kept apart, then for those filed under the cells `box` overlaps,
    //! until visit returns true; returns whether one did. An item can come more than once (once per
    //! cell it shares with `box`).
    template <typename Visit>
    bool any_candidate(const BoundingBox& box, Visit visit) const
    {
        for (const std::uint32_t id : oversized_)
            if (visit(id))
                return true;
        bool found = false;
        for_each_cell(box, [&](std::uint64_t key) {
            if (found)
                return;
            const auto it = cells_.find(key);
            if (it == cells_.end())
                return;
            for (const std::uint32_t id : it->second)
                if (visit(id)) {
                    found = true;
                    return;
                }
        });
        return found;
    }

    //! Calls visit(id) for every candidate of `box` (as any_candidate).
    template <typename Visit>
    void for_each_candidate(const BoundingBox& box, Visit visit) const
    {
        any_candidate(box, [&](std::uint32_t id) {
            visit(id);
            return false;
        });
    }

private:
    std::pair<std::array<std::int64_t, 3>, std::array<std::int64_t, 3>> cells(const BoundingBox& b) const
    {
        const auto c = [&](double x) { return static_cast<std::int64_t>(std::floor(x / cell_)); };
        return {{c(b.min.x), c(b.min.y), c(b.min.z)}, {c(b.max.x), c(b.max.y), c(b.max.z)}};
    }

    template <typename Visit>
    void for_each_cell(const BoundingBox& b, Visit visit) const
    {
        const auto [lo, hi] = cells(b);
        const auto u = [](std::int64_t v) { return static_cast<std::uint64_t>(v) & 0x1fffffu; };
        for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
                    visit(u(x) << 42 | u(y) << 21 | u(z));
    }

    double cell_;
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
    std::vector<std::uint32_t> oversized_; //!< items over kMaxCellsPerItem cells, in the order filed
    std::vector<char> is_oversized_;       //!< per item id: in oversized_
};

} // namespace mrt
