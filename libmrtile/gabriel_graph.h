#pragma once
//! \file gabriel_graph.h
//! \brief Gabriel graph of a point set (paper §4.1: neighbouring clusters are Gabriel neighbours of
//! their centres).
//! \details p and q are Gabriel neighbours when no other point lies strictly inside the ball whose
//! diameter is pq. The Gabriel graph is a subgraph of the Delaunay graph, so candidates come from a
//! 3D Delaunay triangulation (CGAL) and each is kept when the nearest site to the edge's midpoint is
//! no closer than the edge's half length: O(n log n) instead of the O(n³) definition.
//! The builder (cluster_tree.cpp) keeps its graph up to date locally after every split with
//! is_gabriel_edge() over nearby centres, as the paper does; this function gives the exact graph.

#include "libmrtile/vec3.h"

#include <cstdint>
#include <vector>

namespace mrt {

//! The largest coordinate magnitude delaunay_graph() and gabriel_graph() take: squared distances of
//! such points stay far from overflow.
inline constexpr double kMaxGraphCoordinate = 1e100;

//! Adjacency lists (sorted ascending) of the Delaunay graph of `points`: i and j are adjacent when
//! their Voronoi cells share a face. Same precondition as gabriel_graph().
//! \throw InvalidInput if a coordinate is NaN, infinite or larger than kMaxGraphCoordinate in magnitude.
std::vector<std::vector<std::uint32_t>> delaunay_graph(const std::vector<Vec3>& points);

//! Adjacency lists (sorted ascending) of the Gabriel graph of `points`.
//! \pre the points are pairwise distinct (coincident points are merged into the first of them, which
//! then carries their edges).
//! \throw InvalidInput as delaunay_graph().
std::vector<std::vector<std::uint32_t>> gabriel_graph(const std::vector<Vec3>& points);

//! True when no point of `others` lies strictly inside the ball with diameter pq.
inline bool is_gabriel_edge(const Vec3& p, const Vec3& q, const Vec3& other)
{
    const Vec3 m = (p + q) * 0.5;
    return squared_distance(other, m) >= squared_distance(p, m);
}

} // namespace mrt
