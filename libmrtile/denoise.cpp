// Denoising before the hierarchy (beyond the paper; the paper assumes a clean sample): a point is
// moved onto the 2-jet fitted to its k nearest neighbours, as in point-set processing (Cazals and
// Pouget's jet fitting, which CGAL's jet_smooth_point_set also uses). Written here instead of calling
// CGAL's: that one fits in a general-degree basis, 3-4x slower than this fixed quadratic (6-10 µs per
// point with 48 neighbours), and the fit should use our deterministic PCA (pca.h) for its frame.
// See denoise.h.
#include "libmrtile/denoise.h"

#include "libmrtile/errors.h"
#include "libmrtile/median.h"
#include "libmrtile/neighbours.h"
#include "libmrtile/pca.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <mutex>
#include <string>

namespace mrt {
namespace {

// A quadric w(u, v) = c0 + c1 u + c2 v + c3 u² + c4 uv + c5 v² over the plane (e1, e2) with normal n,
// in coordinates about `origin` scaled by `scale`.
struct Jet
{
    Vec3 origin, e1, e2, n;
    double scale = 1.0;
    std::array<double, 6> c{0, 0, 0, 0, 0, 0};
    bool fitted = false; // false: the plane (c = 0)

    void local(const Vec3& p, double& u, double& v, double& w) const
    {
        const Vec3 d = (p - origin) * scale;
        u = dot(d, e1);
        v = dot(d, e2);
        w = dot(d, n);
    }
    double height(double u, double v) const { return c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v; }
    // Least squares over the points; left unfitted (the plane) when they do not determine it
    // (neighbours along a few lines).
    void fit(const std::vector<Vec3>& points)
    {
        Symmetric6 a{}; // the lower triangle of the normal equations' matrix
        std::array<double, 6> b{0, 0, 0, 0, 0, 0};
        for (const Vec3& q : points) {
            double u, v, w;
            local(q, u, v, w);
            const std::array<double, 6> basis{1.0, u, v, u * u, u * v, v * v};
            for (std::size_t j = 0; j < 6; ++j)
                for (std::size_t i = j; i < 6; ++i)
                    a[6 * i + j] += basis[i] * basis[j];
            for (std::size_t i = 0; i < 6; ++i)
                b[i] += basis[i] * w;
        }
        fitted = solve_positive_definite(a, b, c);
    }
};

// The point `p` = points[0] moved onto the quadric fitted to `points`, or p itself when they span no
// surface. (Refitting p to the points on its side of the quadric where the residuals spread as two
// sheets, not as noise, was tried: no better on a noisy plate 6 spacings thick or the bunny's ears.)
Vec3 onto_jet(const std::vector<Vec3>& points)
{
    const Vec3& p = points[0];
    const Moments m = compute_moments(points.data(), points.size());
    const Eigen3x3 frame = eigen_decomposition(m);
    if (!(frame.values[1] > 0.0))
        return p; // collinear or coincident: no surface to move onto
    Jet jet;
    jet.origin = m.mean;
    jet.n = frame.vectors[0];
    jet.e1 = frame.vectors[2];
    jet.e2 = frame.vectors[1];
    // Coordinates scaled to the neighbourhood's radius, for a well-conditioned system.
    double r2 = 0.0;
    for (const Vec3& q : points)
        r2 = std::max(r2, dot(q - m.mean, q - m.mean));
    jet.scale = 1.0 / std::sqrt(r2);
    jet.fit(points);
    double u, v, w;
    jet.local(p, u, v, w);
    double height = jet.fitted ? jet.height(u, v) : 0.0;
    // A quadric that bends away within the neighbourhood is no description of it (a point at the
    // edge of a sparse cluster): the plane instead.
    if (!(std::abs(height) <= 1.0))
        height = 0.0;
    return jet.origin + (jet.e1 * u + jet.e2 * v + jet.n * height) / jet.scale;
}

} // namespace

double denoise_points(std::vector<Vec3>& positions, const DenoiseOptions& options)
{
    if (options.neighbours < 6)
        throw InvalidInput("DenoiseOptions: neighbours must be at least 6 (a quadric has 6 coefficients), got " +
                           std::to_string(options.neighbours));
    // NaN compared false everywhere and kept every isolated point (QA round 51).
    if (!(options.isolated_ratio >= 0.0) || !std::isfinite(options.isolated_ratio))
        throw InvalidInput("DenoiseOptions: isolated_ratio must be finite and >= 0 (0: every point moves)");
    const std::size_t n = positions.size();
    for (std::size_t i = 0; i < n; ++i)
        if (!is_finite(positions[i]))
            throw InvalidInput("denoise_points: position " + std::to_string(i) + " is not finite");
    if (n <= options.neighbours)
        return 0.0;
    const NearestNeighbours search(positions);
    std::vector<Vec3> moved(n);
    std::vector<double> spread(n); // mean distance to the neighbours
    // Progress every kProgressStep points moved; under the lock, the calls rise even when two threads
    // cross a step together.
    constexpr std::size_t kProgressStep = 1 << 16;
    std::atomic<std::size_t> done{0};
    std::mutex progress_lock;
    std::size_t reported = 0;
    const auto count_one = [&] {
        const std::size_t now = done.fetch_add(1) + 1;
        if (now % kProgressStep != 0)
            return;
        const std::lock_guard<std::mutex> hold(progress_lock);
        if (now > reported) {
            reported = now;
            options.progress(static_cast<double>(now) / static_cast<double>(n));
        }
    };
    const auto move_point = [&](std::uint32_t i, const std::vector<std::uint32_t>& index, const std::vector<double>& distance) {
        std::vector<Vec3> points{positions[i]};
        points.reserve(index.size() + 1);
        for (const std::uint32_t j : index)
            points.push_back(positions[j]);
        moved[i] = onto_jet(points);
        double sum = 0.0;
        for (const double d : distance)
            sum += d;
        spread[i] = sum / static_cast<double>(distance.size());
        if (options.progress)
            count_one();
    };
    search.for_each_point(options.neighbours - 1, options.threads, move_point);
    if (options.progress)
        options.progress(1.0);
    // An isolated point (a stray return among others: neighbours far apart) stays where it is: its
    // neighbourhood is no surface, and a quadric through stray points would turn them into a sheet of
    // their own (a sphere with 1.5% stray points: 8 pieces, 1 when they stay).
    const double isolated = options.isolated_ratio * upper_median(spread);
    double sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        if (options.isolated_ratio > 0.0 && spread[i] > isolated)
            moved[i] = positions[i];
        sum += dot(moved[i] - positions[i], moved[i] - positions[i]);
    }
    positions = std::move(moved);
    return std::sqrt(sum / static_cast<double>(n));
}

} // namespace mrt
