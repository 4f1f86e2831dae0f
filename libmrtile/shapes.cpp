// Analytic sample clouds for the demo (the built-in default input), tests and benchmarks. Every
// generator is seeded (std::mt19937) and uses only the raw generator output through our own
// transforms, so results are identical on every standard library.
#include "libmrtile/shapes.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace mrt::shapes {
namespace {


// Uniform double in [0,1) from mt19937 bits; std::uniform_real_distribution is not specified
// exactly and differs between libraries.
double uniform(std::mt19937& rng)
{
    const double hi = static_cast<double>(rng() >> 5); // 27 bits
    const double lo = static_cast<double>(rng() >> 6); // 26 bits
    return (hi * 67108864.0 + lo) * (1.0 / 9007199254740992.0);
}

double gaussian(std::mt19937& rng)
{
    // Box-Muller on our own uniforms (deterministic across libraries).
    double u1 = uniform(rng);
    while (u1 <= 0.0)
        u1 = uniform(rng);
    const double u2 = uniform(rng);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

} // namespace

PointCloud plane_grid(int n)
{
    PointCloud c;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            c.positions.push_back({i / double(n - 1), j / double(n - 1), 0.0});
    return c;
}

PointCloud sphere(std::size_t count, double radius, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(count);
    while (c.positions.size() < count) {
        const Vec3 g{gaussian(rng), gaussian(rng), gaussian(rng)};
        const double n = norm(g);
        if (n > 1e-9)
            c.positions.push_back(g * (radius / n));
    }
    return c;
}

PointCloud torus(std::size_t count, double R, double r, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(count);
    while (c.positions.size() < count) {
        const double u = 2 * kPi * uniform(rng), v = 2 * kPi * uniform(rng);
        // Area element is proportional to R + r cos v: accept with that weight.
        if (uniform(rng) * (R + r) > R + r * std::cos(v))
            continue;
        c.positions.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
    return c;
}

PointCloud three_holes(std::size_t count, std::uint32_t seed)
{
    // Plate [-100,100] x [-40,40] x [-10,10] with three vertical holes of radius 18 at x = -60, 0, 60.
    const double a = 100, b = 40, h = 10, hr = 18;
    const double hx[3] = {-60, 0, 60};
    const double area_top = 2 * (4 * a * b - 3 * kPi * hr * hr);
    const double area_sides = 2 * (2 * a * 2 * h) + 2 * (2 * b * 2 * h);
    const double area_holes = 3 * 2 * kPi * hr * 2 * h;
    const double total = area_top + area_sides + area_holes;
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(count);
    while (c.positions.size() < count) {
        const double pick = uniform(rng) * total;
        if (pick < area_top) {
            const double x = (2 * uniform(rng) - 1) * a, y = (2 * uniform(rng) - 1) * b;
            bool in_hole = false;
            for (double cx : hx)
                in_hole = in_hole || (x - cx) * (x - cx) + y * y < hr * hr;
            if (in_hole)
                continue;
            c.positions.push_back({x, y, uniform(rng) < 0.5 ? -h : h});
        } else if (pick < area_top + area_sides) {
            const double t = uniform(rng) * (4 * a + 4 * b), z = (2 * uniform(rng) - 1) * h;
            if (t < 2 * a)
                c.positions.push_back({t - a, -b, z});
            else if (t < 4 * a)
                c.positions.push_back({t - 3 * a, b, z});
            else if (t < 4 * a + 2 * b)
                c.positions.push_back({-a, t - 4 * a - b, z});
            else
                c.positions.push_back({a, t - 4 * a - 3 * b, z});
        } else {
            const int k = static_cast<int>(uniform(rng) * 3) % 3;
            const double phi = 2 * kPi * uniform(rng), z = (2 * uniform(rng) - 1) * h;
            c.positions.push_back({hx[k] + hr * std::cos(phi), hr * std::sin(phi), z});
        }
    }
    return c;
}

PointCloud smooth_height_field(std::size_t count, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const double x = uniform(rng), y = uniform(rng);
        c.positions.push_back({x, y, 0.1 * std::sin(2 * kPi * x) * std::cos(2 * kPi * y)});
    }
    return c;
}

PointCloud flat_plate(std::size_t count, const std::function<bool(double, double)>& keep, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(count);
    // Rejection sampling; a keep that leaves (almost) nothing gives fewer points rather than no end.
    for (std::size_t tries = 0; c.positions.size() < count && tries < 1000 * count + 1000; ++tries) {
        const double x = uniform(rng), y = uniform(rng);
        if (keep(x, y))
            c.positions.push_back({x, y, 0.0});
    }
    return c;
}

PointCloud step_function(std::size_t count, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const double x = uniform(rng), y = uniform(rng);
        c.positions.push_back({x, y, y >= x ? 1.0 : 0.0});
    }
    return c;
}

PointCloud parallel_planes(std::size_t count, double gap, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    c.positions.reserve(2 * count);
    for (std::size_t i = 0; i < 2 * count; ++i)
        c.positions.push_back({uniform(rng), uniform(rng), (i % 2) ? gap : 0.0});
    return c;
}

PointCloud linked_tori(std::size_t count, double R, double r, double gap, std::uint32_t seed)
{
    PointCloud c = torus(count, R, r, seed);
    const PointCloud other = torus(count, R, r, seed + 1000);
    // The second's centre lies on the x axis where its inner side, R - r from it, keeps `gap` off the
    // first's inner side at x = R - r.
    const double centres = 2.0 * R - 2.0 * r - gap;
    c.positions.reserve(2 * count);
    for (const Vec3& p : other.positions)
        c.positions.push_back({p.x + centres, p.z, p.y});
    return c;
}

PointCloud box_surface(const Vec3& size, double density, double dense_face_factor, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    PointCloud c;
    for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        for (int side = 0; side < 2; ++side) {
            const double factor = axis == 0 && side == 0 ? dense_face_factor : 1.0;
            const auto count = static_cast<std::size_t>(std::llround(density * factor * size[a] * size[b]));
            for (std::size_t i = 0; i < count; ++i) {
                Vec3 p;
                p[axis] = side * size[axis];
                p[a] = uniform(rng) * size[a];
                p[b] = uniform(rng) * size[b];
                c.positions.push_back(p);
            }
        }
    }
    return c;
}

PointCloud cone(std::size_t count, double radius, double height, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    const double lateral = M_PI * radius * std::hypot(radius, height), base = M_PI * radius * radius;
    PointCloud c;
    c.positions.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const bool on_slope = uniform(rng) * (lateral + base) < lateral;
        // Both parts' area grows with the square of the distance t from their centre: sqrt of a uniform.
        const double t = std::sqrt(uniform(rng)), angle = 2.0 * M_PI * uniform(rng);
        const double z = on_slope ? height * (1.0 - t) : 0.0;
        c.positions.push_back({t * radius * std::cos(angle), t * radius * std::sin(angle), z});
    }
    return c;
}

PointCloud mesh_surface(const std::vector<Vec3>& vertices, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                        std::size_t count, std::uint32_t seed)
{
    // A triangle is picked with probability in proportion to its area (binary search in the running
    // sums), then a point in it by the square-root map of two uniforms.
    std::vector<double> running;
    double total = 0.0;
    for (const auto& t : triangles) {
        total += 0.5 * norm(cross(vertices.at(t[1]) - vertices.at(t[0]), vertices.at(t[2]) - vertices.at(t[0])));
        running.push_back(total);
    }
    std::mt19937 rng(seed);
    PointCloud c;
    if (!(total > 0.0))
        return c;
    c.positions.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const double pick = uniform(rng) * total;
        const std::size_t k = std::min<std::size_t>(
            static_cast<std::size_t>(std::upper_bound(running.begin(), running.end(), pick) - running.begin()), triangles.size() - 1);
        const double r = std::sqrt(uniform(rng)), s = uniform(rng);
        const Vec3 &a = vertices[triangles[k][0]], &b = vertices[triangles[k][1]], &d = vertices[triangles[k][2]];
        c.positions.push_back(a * (1.0 - r) + b * (r * (1.0 - s)) + d * (r * s));
    }
    return c;
}

void add_noise(PointCloud& cloud, double sigma, std::uint32_t seed)
{
    std::mt19937 rng(seed);
    for (Vec3& p : cloud.positions)
        p += Vec3{gaussian(rng), gaussian(rng), gaussian(rng)} * sigma;
}

void translate(PointCloud& cloud, const Vec3& offset)
{
    for (Vec3& p : cloud.positions)
        p += offset;
}

} // namespace mrt::shapes
