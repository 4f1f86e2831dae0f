#pragma once
//! \file vec3.h
//! \brief The one small vector type of the library (double precision, no outside dependency).
//! \details Positions are stored relative to a double origin (see point_cloud.h), so doubles keep
//! georeferenced clouds as accurate as clouds near the origin.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace mrt {

inline constexpr double kPi = 3.14159265358979323846;

//! Degrees (as options are given) to radians.
inline constexpr double radians(double degrees) { return degrees * kPi / 180.0; }

struct Vec3
{
    double x = 0.0, y = 0.0, z = 0.0;

    constexpr Vec3() = default;
    constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

    constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }

    constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
    constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(double s) const { return {x / s, y / s, z / s}; }
    Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
    constexpr bool operator==(const Vec3& o) const { return x == o.x && y == o.y && z == o.z; }
    constexpr bool operator!=(const Vec3& o) const { return !(*this == o); }
};

inline constexpr Vec3 operator*(double s, const Vec3& v) { return v * s; }
inline constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline constexpr Vec3 cross(const Vec3& a, const Vec3& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline constexpr double squared_norm(const Vec3& a) { return dot(a, a); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline constexpr double squared_distance(const Vec3& a, const Vec3& b) { return squared_norm(a - b); }
inline double distance(const Vec3& a, const Vec3& b) { return std::sqrt(squared_distance(a, b)); }
inline Vec3 normalized(const Vec3& a)
{
    const double n = norm(a);
    return n > 0.0 ? a / n : Vec3{};
}
//! `a` itself when its squared norm lies between 1e-300 and 1e300; otherwise `a` divided by its largest
//! coordinate: the same direction, whose norm neither overflows (1e300) nor underflows to 0 (1e-300).
//! Zero stays zero. For directions and axes a caller may give at any length.
inline Vec3 with_usable_norm(const Vec3& a)
{
    const double n2 = dot(a, a);
    if (n2 > 1e-300 && n2 < 1e300)
        return a;
    const double largest = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z)});
    return largest > 0.0 ? Vec3{a.x / largest, a.y / largest, a.z / largest} : a;
}
inline bool is_finite(const Vec3& a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
inline Vec3 min(const Vec3& a, const Vec3& b)
{
    return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
inline Vec3 max(const Vec3& a, const Vec3& b)
{
    return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}
//! A unit axis in the plane normal to the unit vector `normal`: helper × normal, normalized, for the
//! x axis as helper (the y axis where `normal` lies near x). With v = normal × u, (u, v, normal) is a
//! right-handed frame of that plane.
inline Vec3 perpendicular_axis(const Vec3& normal)
{
    const Vec3 helper = std::abs(normal.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    return normalized(cross(helper, normal));
}

//! The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection, 5.1.5: the
//! Voronoi region of p among the triangle's vertices, edges and face).
inline Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return a;
    const Vec3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double denom = 1.0 / (va + vb + vc);
    return a + ab * (vb * denom) + ac * (vc * denom);
}

inline double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
    return distance(p, closest_point_on_triangle(p, a, b, c));
}

//! The angle between x and y, in [0, pi] (atan2 of |x × y| and x · y: exact near 0 and pi, where acos
//! of a rounded cosine is not).
inline double angle_between(const Vec3& x, const Vec3& y)
{
    return std::atan2(norm(cross(x, y)), dot(x, y));
}

//! The largest angle of triangle (p, q, r), in radians (near pi for a cap).
inline double largest_angle(const Vec3& p, const Vec3& q, const Vec3& r)
{
    const auto corner = [](const Vec3& u, const Vec3& v, const Vec3& w) { return angle_between(u - w, v - w); };
    return std::max({corner(q, r, p), corner(r, p, q), corner(p, q, r)});
}

//! Whether `keep(spot)` holds at every spot of triangle (a, b, c): a barycentric grid with
//! ceil(longest edge / step) steps along each edge (1 to max_steps), in a fixed order; stops at the
//! first spot it fails. How covers and fills judge a triangle against the points around it.
template <typename Keep>
bool all_triangle_spots(const Vec3& a, const Vec3& b, const Vec3& c, double step, int max_steps, Keep keep)
{
    const double longest = std::max({distance(a, b), distance(b, c), distance(c, a)});
    const int steps = std::clamp(static_cast<int>(std::ceil(longest / step)), 1, max_steps);
    for (int i = 0; i <= steps; ++i)
        for (int j = 0; i + j <= steps; ++j) {
            const double u = static_cast<double>(i) / steps, v = static_cast<double>(j) / steps;
            if (!keep(a + (b - a) * u + (c - a) * v))
                return false;
        }
    return true;
}

//! Calls visit(spot) at the centre of each of the steps² equal sub-triangles of triangle (a, b, c),
//! steps = ceil(longest edge / step) (1 to max_steps), in a fixed order, and returns steps². Each spot
//! stands for the same share of the area: how the share of a triangle away from the points is told.
template <typename Visit>
std::size_t visit_subtriangle_centres(const Vec3& a, const Vec3& b, const Vec3& c, double step, int max_steps, Visit visit)
{
    const double longest = std::max({distance(a, b), distance(b, c), distance(c, a)});
    const int steps = std::clamp(static_cast<int>(std::ceil(longest / step)), 1, max_steps);
    const Vec3 du = (b - a) / static_cast<double>(steps), dv = (c - a) / static_cast<double>(steps);
    for (int i = 0; i < steps; ++i)
        for (int j = 0; i + j < steps; ++j) {
            const Vec3 corner = a + du * static_cast<double>(i) + dv * static_cast<double>(j);
            visit(corner + (du + dv) / 3.0); // the sub-triangle pointing up
            if (i + j + 1 < steps)
                visit(corner + (du + dv) * (2.0 / 3.0)); // and the one pointing down
        }
    return static_cast<std::size_t>(steps) * static_cast<std::size_t>(steps);
}

//! An orthonormal frame of a plane (origin, in-plane axes u and v, normal n): a point's coordinates in
//! the plane, its height above it, and back. Fans and regions are judged in their tile's plane.
struct PlaneFrame
{
    Vec3 origin, u, v, n;
    std::array<double, 2> project(const Vec3& p) const
    {
        const Vec3 d = p - origin;
        return {dot(d, u), dot(d, v)};
    }
    double height(const Vec3& p) const { return dot(p - origin, n); }
    Vec3 point(const std::array<double, 2>& uv, double h) const { return origin + u * uv[0] + v * uv[1] + n * h; }
};

//! Barycentric coordinates `l` of the plane point q in the triangle t of the plane (l[k] weighs t[k]);
//! false when the triangle has no area.
inline bool barycentric(const std::array<double, 2>& q, const std::array<std::array<double, 2>, 3>& t, std::array<double, 3>& l)
{
    const double det = (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
    if (!(std::abs(det) > 0.0))
        return false;
    l[1] = ((q[0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (q[1] - t[0][1])) / det;
    l[2] = ((t[1][0] - t[0][0]) * (q[1] - t[0][1]) - (q[0] - t[0][0]) * (t[1][1] - t[0][1])) / det;
    l[0] = 1.0 - l[1] - l[2];
    return true;
}

//! Whether triangle (p, q, r) has an area that is more than rounding noise for its size.
inline bool has_area(const Vec3& p, const Vec3& q, const Vec3& r)
{
    const double scale = std::max({squared_distance(p, q), squared_distance(q, r), squared_distance(r, p)});
    const Vec3 n = cross(q - p, r - p);
    return dot(n, n) > 1e-20 * scale * scale;
}

} // namespace mrt
