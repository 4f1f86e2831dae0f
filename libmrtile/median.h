#pragma once
//! \file median.h
//! \brief The median of a list of numbers, as the stages take it (internal: not installed).
//! \details Point spacings, roughness and distances are judged against a median so that a few odd
//! values (a tile over a hole, a stray point) do not move the judgement; nth_element finds it in
//! linear time.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace mrt {

//! The element at index size / 2 of `values` in sorted order (the upper of the two middle ones of an
//! even count); reorders `values`. 0 for an empty list.
inline double upper_median_in_place(std::vector<double>& values)
{
    if (values.empty())
        return 0.0;
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

//! The same on a copy.
inline double upper_median(std::vector<double> values)
{
    return upper_median_in_place(values);
}

} // namespace mrt
