#pragma once
//! \file fit_vertices.h
//! \brief Beyond the paper: vertex positions fitted to the input points (least squares, along normals),
//! then edge flips where the other diagonal fits better.
//! \details The paper's tiles interpolate: hull points are input points and a fan is a chord of the
//! surface, so on a curved patch every face lies on one side of the points it stands for. Each round of
//! this stage moves every vertex along its normal (or along an axis, for height fields) to minimise the
//! sum of squared distances from the input points to the planes of their closest faces (Hoppe et al.
//! 1993's E_dist, linearized like point-to-plane ICP), with a small damping that holds still any vertex
//! no point constrains, then flips the edges whose two faces fit their points better the other way round
//! (Hoppe's edge swap; no fold beyond 60°). Points are re-assigned to their closest faces every round.
//! A vertex moves at most `max_move` × its shortest edge per round (the shorter of that edge now and
//! before the first round, so that the bound cannot grow with the moves), so fans do not fold and thin parts do
//! not cross. The topology (vertices, boundary loops, genus, manifoldness, orientation) never changes;
//! positions and, through the flips, the diagonals do.
//! \code
//!   Mesh m = mesh_cut(h, cut).mesh;             // mesh_cut runs it by default (MeshOptions::fit)
//!   FitOptions o;
//!   o.rounds = 5;                               // two more assign-solve-flip rounds than the default
//!   FitStats s = fit_vertices(m, h.cloud.positions, o);
//! \endcode

#include "libmrtile/mesh.h"
#include "libmrtile/relax_vertices.h"
#include "libmrtile/vec3.h"

#include <cstddef>
#include <utility>
#include <vector>

namespace mrt {

//! The most FitOptions::rounds accepted: a round costs a closest-point pass over every point, and
//! rounds beyond a few change little (and fold thin tips: the bunny with 100 had 131 crossing pairs).
inline constexpr int kMaxFitRounds = 100;

struct FitOptions
{
    //! Assign-solve-flip rounds (0 = off). The first round does most of the work; later ones follow
    //! points that changed face and flip again (bunny, coarse cut: 2 rounds −22% mean distance against
    //! interpolation, 3 rounds −27%, 4 rounds −29%).
    int rounds = 3;                 //!< at most kMaxFitRounds
    //! Weight pulling each vertex back to where it started, relative to the mean weight the points put
    //! on a vertex (keeps the system well posed where few points are; larger = smaller moves).
    double damping = 0.05;
    //! A vertex moves at most this fraction of its shortest incident edge per round, now or before the
    //! first round, whichever is shorter (moving along the normal, it cannot fold its faces before it
    //! has moved about an edge length).
    double max_move = 0.5;
    //! Use at most about this many points per vertex (every k-th point, k the same for all): the fit
    //! of a vertex needs a few dozen points, and a fine sample under a coarse mesh would cost time
    //! without changing the result much. 0 = every point.
    std::size_t points_per_vertex = 16;
    //! Strays do not count: points farther from the plane of their closest face than this many times
    //! that face's longest edge, or than 8 times the median distance of the points on that face and
    //! its neighbours (at least a tenth of the edge). A bird over a terrain, in least squares, one
    //! point 13 m off, outweighed the dozen under a vertex and lifted it 6 m off the ground (QA round
    //! 60). The median is local, so that where a coarse mesh stands off a curved part or a sharp edge,
    //! the points there, all off by much the same, still pull. 0 = every point counts.
    double stray_reach = 2.0;
    //! After each round's moves, flip the edges whose two faces fit their points better the other way
    //! round (and do not fold). Changes the connectivity, never the topology.
    bool flip_edges = true;
    //! A flip may not make a face with an angle above this (degrees) unless the two old faces had one
    //! as large: a cap fits a ridge of points only as a crease that shading shows (bunny at tolerance
    //! 0.002: flips without this limit left 12% of the faces caps). 180 = no limit.
    double max_flip_angle_degrees = 150.0;
    //! Move vertices along `axis` instead of along their normals, and flip only where both new faces
    //! face up it: a height field stays a graph over the plane normal to the axis.
    bool vertical = false;
    Vec3 axis{0, 0, 1}; //!< the "up" of `vertical` (mesh_cut passes the surface's height-field axis)
    //! After the rounds, vertices of faces that intersect other faces go back to where they started
    //! (repeated while that changes something, at most 4 times): the fit never adds self-intersections
    //! (at sharp edges, points of one side can pull the other side's faces across). Costs one
    //! self-intersection test of the whole mesh (CGAL; ~0.26 s per 100k faces) and small ones around
    //! what is put back; the pairs left are kept (pairs_known) for untangle.
    bool revert_intersections = true;
    //! Threads for the closest-face queries (0 = one per hardware thread). The result does not depend
    //! on it.
    std::size_t threads = 0;
    //! Before each round, the vertices slide within the surface towards the middle of their neighbours
    //! (relax_vertices.h; `iterations` sweeps per round, 0 = never; vertical when the fit is), so every
    //! round fits evenly spread vertices: shape matrix −7.7% mean and −5.4% maximum distance against no
    //! relaxation (two sweeps before the first round only: −5.7% / −4.7%).
    RelaxOptions relax;
};

struct FitStats
{
    int rounds = 0;             //!< rounds run
    std::size_t points = 0;     //!< points used (per round)
    double mean_move = 0.0;     //!< mean |displacement| of the vertices over all rounds (model units)
    std::size_t clamped = 0;    //!< vertex moves cut to max_move (summed over rounds)
    std::size_t flips = 0;      //!< edges flipped (summed over rounds)
    std::size_t reverted = 0;   //!< vertices put back to undo self-intersections
    RelaxStats relax;           //!< the relaxation: moves and refusals summed over rounds, creases of the last
    double seconds = 0.0;       //!< wall time
    //! With revert_intersections: whether intersecting_pairs holds every pair of faces that intersect at
    //! the end (self_intersecting_faces), known because the pass tested the whole mesh; untangle can
    //! start from them (mesh_cut does) instead of testing it again.
    bool pairs_known = false;
    std::vector<std::pair<int, int>> intersecting_pairs;
};

//! \throw InvalidInput if an option is out of range, the relaxation's included (what fit_vertices checks
//! first).
void check_fit_options(const FitOptions& options);

//! \brief Moves the vertices of `mesh` to fit `points` (see the file comment). Deterministic; updates
//! the face and vertex normals. A mesh without faces, or no points, is left unchanged.
//! \throw InvalidInput if an option is out of range or a point or a vertex of the mesh is not finite.
FitStats fit_vertices(Mesh& mesh, const std::vector<Vec3>& points, const FitOptions& options = {});

} // namespace mrt
