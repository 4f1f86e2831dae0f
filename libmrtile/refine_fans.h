#pragma once
//! \file refine_fans.h
//! \brief Beyond the paper: interior vertices for T1 fans that deviate from their tile's points.
//! \details A tile is one planar fan around its apex (§4.3 T1), so on a coarse cut of a curved surface
//! the error is set by the cut's tolerance however the faces are spent. This stage inserts, greedily,
//! the tile point farthest from its fan triangle as a new vertex (a 1-to-3 split of that triangle) while
//! some point deviates by more than `max_deviation` × its tile's RMS plane distance: the largest
//! deviations go first, and flat tiles get nothing. Topology, gap faces and tile borders do not change.
//! \code
//!   MeshOptions o;
//!   o.refine.max_deviation = 1.5;         // on (0 = off): vertices where tiles bend
//!   MeshResult r = mesh_cut(h, cut, o);   // mesh_cut runs it after build_surface
//! \endcode

#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"

#include <cstddef>

namespace mrt {

struct FanRefineOptions
{
    //! Insert points while one deviates from its fan by more than this × its tile's RMS plane distance
    //! (measured along the tile normal). 0 = off (the default: at equal face count it is about even with
    //! a finer cut on the mean distance; it lowers the maximum distance, by a third on a coarse bunny cut
    //! at 2.0 for 8% more faces).
    double max_deviation = 0.0;
    //! At most this many points inserted per tile (bounds the cost on noisy tiles).
    std::size_t max_points_per_tile = 16;
};

//! \brief Inserts the worst-fitting points of every fan of `mesh` (faces with a tile id, see mesh.h) as
//! vertices. Points are the tile node's points in `h`. Returns the number of points inserted.
//! Deterministic. \throw InvalidInput if an option is out of range or a tile id is not a node of `h`.
std::size_t refine_fans(Mesh& mesh, const Hierarchy& h, const FanRefineOptions& options = {});

} // namespace mrt
