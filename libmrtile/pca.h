#pragma once
//! \file pca.h
//! \brief Exact, mergeable point statistics and the principal component analysis of paper §4.1.
//! \details A cluster is summarised by its count, mean and M = ΔᵀΔ (eq. 2-3: the sum of outer products
//! of the points' offsets from the mean, *not* divided by the count). Two summaries merge exactly
//! (Chan et al.'s pairwise update), so a parent node's statistics follow from its children's without
//! touching points, and every frontier cut of the tree has exact statistics.
//! The eigen-decomposition of M gives the tile plane (§4.2): the normal is the eigenvector of the
//! smallest eigenvalue, the plane is spanned by the other two.

#include "libmrtile/vec3.h"

#include <array>
#include <cstdint>

namespace mrt {

struct Moments
{
    std::uint64_t count = 0;
    Vec3 mean{0, 0, 0};
    //! Upper triangle of M = ΔᵀΔ: xx, xy, xz, yy, yz, zz (model units squared).
    std::array<double, 6> m2{0, 0, 0, 0, 0, 0};

    void add(const Vec3& p);
    //! Removes a point previously added (inverse of add; exact up to rounding).
    void remove(const Vec3& p);
    void merge(const Moments& other);
    //! Sum of squared distances of the points to the mean (= trace of M).
    double sum_squared_distances() const { return m2[0] + m2[3] + m2[5]; }
};

//! Adds the outer product d dᵀ to the upper triangle m2 (xx, xy, xz, yy, yz, zz).
inline void add_outer_product(std::array<double, 6>& m2, const Vec3& d)
{
    m2[0] += d.x * d.x;
    m2[1] += d.x * d.y;
    m2[2] += d.x * d.z;
    m2[3] += d.y * d.y;
    m2[4] += d.y * d.z;
    m2[5] += d.z * d.z;
}

//! Statistics of a range of points (two-pass: mean first, then M, for accuracy).
Moments compute_moments(const Vec3* points, std::size_t count);

struct Eigen3x3
{
    //! Ascending: values[0] = smallest (= sum of squared plane distances, the paper's τ quantity).
    std::array<double, 3> values{0, 0, 0};
    //! Unit eigenvectors matching values; vectors[0] is the plane normal, vectors[2] the principal axis.
    std::array<Vec3, 3> vectors{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
};

//! Smallest eigenvalue of M by the closed-form 3x3 solution: fast, accurate to about 1e-9 of the
//! largest eigenvalue. Use it for threshold tests far from the threshold; eigen_decomposition() when
//! the value itself matters.
double smallest_eigenvalue_fast(const Moments& m);

//! Eigen-decomposition of the symmetric matrix M of a Moments. Values are clamped to be >= 0.
//! Vectors are sign-normalised (largest-magnitude component positive) so the result is deterministic.
Eigen3x3 eigen_decomposition(const Moments& m);

//! A 6x6 symmetric matrix by its lower triangle: entry (i, j), i >= j, at [6 * i + j] (the rest unused).
using Symmetric6 = std::array<double, 36>;

//! \brief Solves A x = b for a symmetric positive definite 6x6 A (an LDLᵀ factorisation), as the
//! denoising's quadric fit needs (denoise.h). Returns false, x untouched, where A is not positive
//! definite or its reciprocal condition estimate is not above 1e-9: x would be noise.
bool solve_positive_definite(const Symmetric6& a, const std::array<double, 6>& b, std::array<double, 6>& x);

} // namespace mrt
