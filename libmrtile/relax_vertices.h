#pragma once
//! \file relax_vertices.h
//! \brief Beyond the paper: vertices slid within the surface towards the middle of their neighbours,
//! before each round of the vertex fit, so that the fit places evenly spread vertices.
//! \details A cut's vertices are where the tiles put them: hull points of neighbouring tiles bunch up
//! along tile rims and leave wide faces between. Sliding each vertex part of the way to the centroid of
//! its neighbours, projected into its tangent plane (the plane of its area-weighted normal), evens the
//! faces out without moving the surface to first order; the fit then places the vertices on the points.
//! Vertices on a crease (a face of the one-ring turned more than `crease_degrees` from the vertex
//! normal) stay put: sliding across a sharp edge would round it off. Border vertices stay put. A move
//! is taken only if no face of the one-ring turns by more than `max_turn_degrees` (and, for a height
//! field, every one of them still faces up `axis`), so the mesh never folds; vertices are visited in
//! index order, each seeing its neighbours' new positions (deterministic). Positions only: the
//! connectivity and with it the topology never change. Shape matrix (15 shapes × 5 tolerances, one sweep
//! before each of the fit's three rounds): mean distance −7.7%, maximum −5.4%; sphere −32%, torus −29%,
//! Igea −8%, bunny −6%; sharp-edged parts within ±3% and the step function's mesh still exact.
//! \code
//!   Mesh m = ...;                       // fit_vertices runs it before each round (FitOptions::relax)
//!   RelaxOptions o;
//!   o.iterations = 4;                   // four sweeps
//!   RelaxStats s = relax_vertices(m, o);
//! \endcode

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <cstddef>

namespace mrt {

//! Largest RelaxOptions::iterations: each sweep costs about a fit round, and the fit runs the sweeps
//! before each of its rounds (a million took 703 s on a 940-face torus: QA round 51).
inline constexpr int kMaxRelaxIterations = 100;

struct RelaxOptions
{
    //! Sweeps over the vertices (0 = off; at most kMaxRelaxIterations). The fit runs one before each of
    //! its rounds (FitOptions::relax): relaxing more between two fits rounds the mesh off where the
    //! points are too few to pull it back.
    int iterations = 1;
    //! Fraction of the way to the projected centroid moved per sweep (0..1].
    double step = 0.5;
    //! A vertex with a one-ring face turned more than this from its normal (degrees) is on a crease and
    //! stays put (30-45 give the same results on the shape matrix).
    double crease_degrees = 35.0;
    //! A move that turns any one-ring face by more than this (degrees) is not taken.
    double max_turn_degrees = 30.0;
    //! Height fields: every face must still face up `axis` after a move (mesh_cut sets both).
    bool vertical = false;
    Vec3 axis{0, 0, 1};
};

struct RelaxStats
{
    std::size_t moves = 0;    //!< vertex moves taken (summed over sweeps)
    std::size_t creases = 0;  //!< vertices left on creases (last sweep)
    std::size_t refused = 0;  //!< moves refused because a face would turn too far (summed)
};

//! \throw InvalidInput if an option is out of range (what relax_vertices checks first).
void check_relax_options(const RelaxOptions& options);

//! \brief Slides the vertices of `mesh` within the surface (see the file comment). Updates face and
//! vertex normals. \throw InvalidInput if an option is out of range.
RelaxStats relax_vertices(Mesh& mesh, const RelaxOptions& options = {});

} // namespace mrt
