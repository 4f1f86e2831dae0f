#pragma once
//! \file denoise.h
//! \brief Moving noisy points onto the surface they sample, before the hierarchy is built (beyond
//! the paper, which assumes a clean sample; build_hierarchy does it when the sample is noisy).
//! \details Where a sample's noise is about half its point spacing or more, the hierarchy's leaves are
//! blobs, and the noise floor (hierarchy.h) stops cuts above them; under noise of one spacing or more
//! the tiles' rims stand off by the noise, and the surface breaks up where they meet (the bunny with
//! noise of one spacing: 4–6 pieces; a torus with 3: 71 loops). Each point is moved onto the quadric
//! (a 2-jet, w = a + bu + cv + du² + euv + fv² over the neighbours' PCA plane) fitted by least
//! squares to it and its k nearest neighbours: the fit averages the noise over k points and, unlike a
//! plane, does not flatten a curved surface (a plane fit moves points of a sphere inwards by about
//! r²/4R). One pass, all points from their original positions (the result does not depend on the order).

#include "libmrtile/vec3.h"

#include <cstddef>
#include <functional>
#include <vector>

namespace mrt {

struct DenoiseOptions
{
    //! k: the point and its k - 1 nearest neighbours carry the fit. 48 averages noise down to about
    //! a third without reaching across features several spacings wide (their radius is about 4
    //! spacings): 24 left a torus with noise of 3 spacings 8 loops at tolerance 0.002, 48 none.
    std::size_t neighbours = 48;
    //! A point whose mean distance to its neighbours exceeds this many times the median over all
    //! points is isolated (a stray return) and stays where it is (0 = every point moves).
    double isolated_ratio = 3.0;
    //! Threads (0 = the default, parallel.h). The result does not depend on it.
    std::size_t threads = 0;
    //! Called now and then with the fraction of points moved (0..1, rising; last with 1), one call at
    //! a time but from any of the threads.
    std::function<void(double)> progress;
};

//! \brief Moves every point onto the quadric fitted to its neighbourhood (see the file comment).
//! Returns the RMS distance the points moved. Points whose neighbourhood spans no surface (collinear
//! or coincident) stay, and so do isolated ones (DenoiseOptions::isolated_ratio); a cloud of at most `neighbours` points is left as it is (returns 0).
//! Deterministic whatever the thread count.
//! \throw InvalidInput if neighbours < 6 (a quadric has 6 coefficients) or a position is not finite.
double denoise_points(std::vector<Vec3>& positions, const DenoiseOptions& options = {});

} // namespace mrt
