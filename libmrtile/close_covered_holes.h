#pragma once
//! \file close_covered_holes.h
//! \brief Small holes of a mesh that the input points cover are capped from the points (beyond the paper).
//! \details The surface stage fills the gaps between tiles with a minimum-area triangulation of each
//! loop, and leaves a loop open where that patch folds or crosses the surface. Along a sharp edge of a
//! closed solid (a CAD part's 90-degree edge) the loop's corners lie on both faces, and a patch made of
//! the loop's own corners cuts through the solid: 1M-point samples of the fandisk kept a loop of 8 or
//! 11 edges there (QA round 43), with points all over it. This pass sees each loop along the mean
//! normal of the faces at its corners and triangulates its outline together with the input points
//! inside it (constrained Delaunay, thinned to about one point per spacing): the cap's inner vertices
//! lie on the sample, a sharp edge's points among them, so the cap follows the edge instead of
//! cutting it. A cap is kept only when
//!  - the loop has at most `max_edges` edges (longer ones are the sample's own borders and wide holes,
//!    which the surface stage judged whole) and its outline is simple and counter-clockwise seen from
//!    the surface's side;
//!  - the input points cover the cap: every spot of it has a point within `cover_spacings` point
//!    spacings;
//!  - no cap face turns more than `max_turn_degrees` from the face it joins across the loop (in a
//!    height field, every cap face faces up its axis);
//!  - no cap face meets a face of the mesh other than in the corners and edges they share, and
//!    OpenMesh's add_face takes every face (each handle checked; a refused cap is undone).
//! Where no cap fits, the faces at the loop's corners are taken out and the wider hole tried, up to 4
//! rings (judged on paper: the mesh changes only once a cap fits): a rim of folded faces, left where
//! tiles straddle an edge, is replaced. A hole of the sample (the points leave an empty disc of twice
//! the cover distance inside its outline: the bunny's base) is left at once. The spacing is the median
//! of the loop's corners' tiles. Cap faces are gap faces
//! (f:tile -1, f:gap true); each new vertex takes the cluster of the loop's nearest corner.
//! Deterministic: loops are taken in half-edge order, each judged alone.

#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace mrt {

struct CoveredHoleOptions
{
    //! Loops of at most this many edges are closed (0 = off).
    std::size_t max_edges = 32;
    //! The input points must cover the cap: every spot of it has a point within this many spacings (a
    //! uniform random sample leaves empty discs of 1.5 spacings often enough that 1.5 refused caps over
    //! sampled surface: a terrain's slit, a star prism's crack).
    double cover_spacings = 2.0;
    //! Each cap face turns at most this much from the face it joins across the loop (degrees).
    double max_turn_degrees = 60.0;
    //! Keep a height field a graph over the plane normal to `axis`: every cap face must face up it.
    bool vertical = false;
    Vec3 axis{0, 0, 1};
};

//! Counts of close_covered_holes.
struct CoveredHoleStats
{
    std::size_t closed = 0;    //!< loops closed
    std::size_t faces = 0;     //!< faces added
    std::size_t removed = 0;   //!< faces taken out around holes whose rim no cap fitted as it was
    std::size_t uncovered = 0; //!< loops of at most max_edges edges left open: the points do not cover them
    std::size_t refused = 0;   //!< loops left open although covered: their cap would fold or cross the mesh
};

//! \brief Closes the holes of `mesh` of at most options.max_edges edges that the points of `h` cover.
//! `spacing_of` gives the point spacing of the tile each vertex names (v:cluster → spacing), as for
//! fill_notches; a loop whose corners name no spacing is left open.
//! \throw InvalidInput for options out of range (a turn outside (0, 180), a cover spacing not positive
//! and finite, a zero axis with `vertical`) or a mesh without the v:cluster / f:tile / f:gap properties.
CoveredHoleStats close_covered_holes(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
                                     const CoveredHoleOptions& options = {});

//! \brief Whether a boundary loop of `mesh` (its border half-edges in order) lies over a hole of the
//! sample: seen along the mean normal of the faces at its corners, the points of `h` leave a spot
//! inside it farther than twice the cover distance (CoveredHoleOptions::cover_spacings × `spacing`)
//! from all of them, as close_covered_holes judges a hole before capping it. The bunny's base: yes; a
//! crack between tiles over sampled surface: no. False for fewer than 3 edges or no usable spacing.
bool is_sample_hole(const Mesh& mesh, const Hierarchy& h, const std::vector<Mesh::HalfedgeHandle>& loop, double spacing);

//! \brief The area of the faces of `mesh` whose bounding boxes meet `box` that lies farther than `reach`
//! from every point of `h`: each face's area times the share of its equal sub-triangles (at most a
//! third of the reach wide, up to 200 along an edge) whose centres have no point within reach. Faces
//! spanning a hole of the sample have some; faces over sampled surface none (how mesh_cut's crack
//! rounds tell a hole's rim from a crack). 0 for a `reach` that is not positive and finite.
double area_off_the_sample(const Mesh& mesh, const Hierarchy& h, const BoundingBox& box, double reach);
//! The same for the given faces. \throw InvalidInput if a handle is no live face of `mesh`.
double area_off_the_sample(const Mesh& mesh, const Hierarchy& h, const std::vector<Mesh::FaceHandle>& faces, double reach);

} // namespace mrt
