#pragma once
//! \file polygon2d.h
//! \brief Outlines seen in a plane (a region's or a hole's corners projected by a PlaneFrame): signed
//! area, inside test, distance to a segment. Internal: shared by the local re-triangulation
//! (refine_mesh.cpp) and the caps from the points (close_covered_holes.cpp).

#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

namespace mrt {

using Point2 = std::array<double, 2>;

//! Positive for a counter-clockwise outline.
inline double signed_area(const std::vector<Point2>& polygon)
{
    double area = 0.0;
    for (std::size_t i = 0; i < polygon.size(); ++i) {
        const Point2& a = polygon[i];
        const Point2& b = polygon[(i + 1) % polygon.size()];
        area += a[0] * b[1] - a[1] * b[0];
    }
    return 0.5 * area;
}

//! Even-odd rule; a point on the outline may count either way (callers keep off it).
inline bool inside_polygon(const std::vector<Point2>& polygon, const Point2& p)
{
    bool inside = false;
    for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
        const Point2& a = polygon[i];
        const Point2& b = polygon[j];
        if ((a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0])
            inside = !inside;
    }
    return inside;
}

//! Squared distance from p to the segment a-b.
inline double segment_distance2(const Point2& p, const Point2& a, const Point2& b)
{
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    const double len2 = dx * dx + dy * dy;
    double t = len2 > 0.0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const double ex = a[0] + t * dx - p[0], ey = a[1] + t * dy - p[1];
    return ex * ex + ey * ey;
}

} // namespace mrt
