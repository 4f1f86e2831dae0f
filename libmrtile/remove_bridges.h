#pragma once
//! \file remove_bridges.h
//! \brief Tubes of gap faces across empty space, between two surfaces that face each other, cut (beyond
//! the paper).
//! \details Where two surfaces face each other a few point spacings apart (two links of a chain, an arm
//! beside a body), each tile's local triangulation projects the other surface's points into its own
//! plane, and some of the gap faces across the gap are no larger than the alpha bound lets through.
//! The surface front can then take a ring of them: a tube of 6-8 long faces from a small loop on one
//! surface to a small loop on the other, which joins two objects into one (or adds a handle). QA
//! round 80: links of a chain 25 spacings thick and 5 apart were one piece at the default tolerance
//! in 4 of 10 seeds (gaps of 6 and 7 spacings never), nothing else showing it. Such a tube is told
//! from surface by where it lies: every one of its faces is a gap face with an edge over
//! `min_edge_spacings` spacings and a share of its area over `off_share` farther than
//! `reach_spacings` from every input point (it spans the empty gap; gap faces over sampled surface
//! lie within a spacing of the points; judged only where a long edge's midpoint lies off the sample by
//! 0.15 of the face's longest edge, as the middle of an edge across a gap does and a chord of a curved
//! surface at a coarse cut does not), the faces form an annulus (Euler characteristic 0), and its
//! two boundary loops are short (at most `max_loop_edges` edges each) and border faces outside it on
//! every edge. The tube is taken out and each loop capped: a triangle, or two across the shorter
//! diagonal of a 4-edge loop. Caps are gap faces (f:tile -1, f:gap true). A tube whose caps OpenMesh
//! refuses (a diagonal that is already an edge) is put back as it was; every handle is checked.
//! Single faces, discs (an unsampled hole's fill: one loop) and wide rings (a cylinder sampled at its
//! rims only: long loops) are left alone. Deterministic: tubes are found in face order. mesh_cut runs it
//! first after the surface, but not on a height field (one layer over its plane: no surfaces face each
//! other there, and its unsampled walls are all long faces off the sample, which the test is slow on).

#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>

namespace mrt {

struct BridgeOptions
{
    //! A tube is cut when each of its two loops has at most this many edges (3 or 4; 0 = off).
    std::size_t max_loop_edges = 4;
    //! Each of its faces has an edge longer than this many spacings (gap faces between neighbouring
    //! tiles span about one).
    double min_edge_spacings = 3.0;
    //! ... and at least `off_share` of its area farther than this many spacings from every point.
    double reach_spacings = 1.25;
    double off_share = 0.1;
};

//! Counts of remove_bridges.
struct BridgeStats
{
    std::size_t tubes = 0;   //!< tubes cut
    std::size_t removed = 0; //!< faces taken out with them
    std::size_t caps = 0;    //!< cap faces put on their loops
    //! The work, counted the same on every machine: gap faces with an edge over min_edge_spacings,
    //! and those of them whose area was judged spot by spot (a long edge's midpoint off the sample by
    //! 0.15 of the face's longest edge; a coarse cut's chords across curved surface are not).
    std::size_t long_faces = 0;
    std::size_t judged = 0;
};

//! \throw InvalidInput for options out of range (as remove_bridges).
void check_bridge_options(const BridgeOptions& options);

//! \brief Cuts the tubes of gap faces that join two surfaces across empty space (see the file comment).
//! `spacing_of` gives the point spacing of the tile each vertex names (v:cluster → spacing), as for
//! close_covered_holes; a face whose corners name no spacing is never part of a tube.
//! \throw InvalidInput for options out of range (max_loop_edges other than 0, 3 or 4; a spacing count
//! or share not positive and finite) or a mesh without the v:cluster / f:tile / f:gap properties.
BridgeStats remove_bridges(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
                           const BridgeOptions& options = {});

} // namespace mrt
