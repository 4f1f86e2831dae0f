#pragma once
//! \file union_find.h
//! \brief Disjoint sets over the ids 0..n-1, for the pieces of meshes and tile graphs.
//! \details Path halving. The smallest id of a set is its root, so roots do not depend on the order of
//! the unions: code that iterates over roots stays deterministic. Sets can grow one id at a time (add).

#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace mrt {

class UnionFind
{
public:
    explicit UnionFind(std::size_t n = 0) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0u); }

    std::size_t size() const { return parent_.size(); }

    //! A new set holding the next id (size() before the call).
    void add() { parent_.push_back(static_cast<std::uint32_t>(parent_.size())); }

    std::uint32_t find(std::uint32_t i)
    {
        while (parent_[i] != i) {
            parent_[i] = parent_[parent_[i]];
            i = parent_[i];
        }
        return i;
    }

    void unite(std::uint32_t a, std::uint32_t b)
    {
        a = find(a);
        b = find(b);
        if (a < b)
            parent_[b] = a;
        else if (b < a)
            parent_[a] = b;
    }

private:
    std::vector<std::uint32_t> parent_;
};

} // namespace mrt
