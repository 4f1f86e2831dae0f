// Paper §4.1 eq. 2-3: the 3x3 matrix M = ΔᵀΔ of a cluster and its eigen-decomposition (PCA).
// This is the only file that includes Eigen, so the rest of the library stays free of it (the 6x6
// solve of the denoising's quadric fit is here for that reason).
#include "libmrtile/pca.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace mrt {

void Moments::add(const Vec3& p)
{
    // Welford's update: numerically stable, exact for a single point.
    ++count;
    const Vec3 d = p - mean;
    mean += d / static_cast<double>(count);
    const Vec3 e = p - mean;
    m2[0] += d.x * e.x;
    m2[1] += d.x * e.y;
    m2[2] += d.x * e.z;
    m2[3] += d.y * e.y;
    m2[4] += d.y * e.z;
    m2[5] += d.z * e.z;
}

void Moments::remove(const Vec3& p)
{
    if (count <= 1) {
        *this = Moments{};
        return;
    }
    const Vec3 e = p - mean;
    --count;
    mean -= e / static_cast<double>(count);
    const Vec3 d = p - mean;
    m2[0] -= d.x * e.x;
    m2[1] -= d.x * e.y;
    m2[2] -= d.x * e.z;
    m2[3] -= d.y * e.y;
    m2[4] -= d.y * e.z;
    m2[5] -= d.z * e.z;
}

void Moments::merge(const Moments& o)
{
    if (o.count == 0)
        return;
    if (count == 0) {
        *this = o;
        return;
    }
    const double na = static_cast<double>(count), nb = static_cast<double>(o.count);
    const double n = na + nb;
    const Vec3 delta = o.mean - mean;
    const double f = na * nb / n;
    m2[0] += o.m2[0] + delta.x * delta.x * f;
    m2[1] += o.m2[1] + delta.x * delta.y * f;
    m2[2] += o.m2[2] + delta.x * delta.z * f;
    m2[3] += o.m2[3] + delta.y * delta.y * f;
    m2[4] += o.m2[4] + delta.y * delta.z * f;
    m2[5] += o.m2[5] + delta.z * delta.z * f;
    mean += delta * (nb / n);
    count += o.count;
}

Moments compute_moments(const Vec3* points, std::size_t count)
{
    Moments m;
    if (count == 0)
        return m;
    Vec3 sum{0, 0, 0};
    for (std::size_t i = 0; i < count; ++i)
        sum += points[i];
    m.count = count;
    m.mean = sum / static_cast<double>(count);
    for (std::size_t i = 0; i < count; ++i)
        add_outer_product(m.m2, points[i] - m.mean);
    return m;
}

double smallest_eigenvalue_fast(const Moments& m)
{
    Eigen::Matrix3d a;
    a << m.m2[0], m.m2[1], m.m2[2], m.m2[1], m.m2[3], m.m2[4], m.m2[2], m.m2[4], m.m2[5];
    const double scale = a.cwiseAbs().maxCoeff();
    if (!(scale > 0.0) || !std::isfinite(scale))
        return 0.0;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(a / scale, Eigen::EigenvaluesOnly);
    return std::max(0.0, solver.eigenvalues()[0] * scale);
}

Eigen3x3 eigen_decomposition(const Moments& m)
{
    Eigen::Matrix3d a;
    a << m.m2[0], m.m2[1], m.m2[2], m.m2[1], m.m2[3], m.m2[4], m.m2[2], m.m2[4], m.m2[5];
    Eigen3x3 out;
    const double scale = a.cwiseAbs().maxCoeff();
    if (!(scale > 0.0) || !std::isfinite(scale))
        return out; // a single point or coincident points: identity frame, zero values
    // The iterative solver (not computeDirect) keeps tiny eigenvalues accurate, which the flatness
    // test of §4.1 depends on.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(a / scale);
    for (int i = 0; i < 3; ++i) {
        out.values[static_cast<std::size_t>(i)] = std::max(0.0, solver.eigenvalues()[i] * scale);
        Eigen::Vector3d v = solver.eigenvectors().col(i);
        int largest = 0;
        for (int k = 1; k < 3; ++k)
            if (std::abs(v[k]) > std::abs(v[largest]))
                largest = k;
        if (v[largest] < 0)
            v = -v;
        out.vectors[static_cast<std::size_t>(i)] = Vec3{v[0], v[1], v[2]};
    }
    // Keep a right-handed frame: normal = axis1 x axis2 (used to orient tiles consistently).
    if (dot(cross(out.vectors[1], out.vectors[2]), out.vectors[0]) < 0)
        out.vectors[1] = -out.vectors[1];
    return out;
}

bool solve_positive_definite(const Symmetric6& a, const std::array<double, 6>& b, std::array<double, 6>& x)
{
    Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
    for (int j = 0; j < 6; ++j)
        for (int i = j; i < 6; ++i)
            m(i, j) = a[static_cast<std::size_t>(6 * i + j)];
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(m.selfadjointView<Eigen::Lower>());
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.rcond() > 1e-9))
        return false;
    const Eigen::Matrix<double, 6, 1> rhs = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(b.data());
    const Eigen::Matrix<double, 6, 1> solution = ldlt.solve(rhs);
    for (int i = 0; i < 6; ++i)
        x[static_cast<std::size_t>(i)] = solution[i];
    return true;
}

} // namespace mrt
