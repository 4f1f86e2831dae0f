#pragma once
//! \file mesh_stats.h
//! \brief Measured quality of an output mesh: exact topology counts (manifoldness, orientation, genus,
//! boundary loops) and exact point <-> surface distances.
//! \details The topology counts are computed on a raw triangle soup, so a triangle set can be checked
//! before it is given to OpenMesh (which refuses a non-manifold edge); the Mesh overload converts the
//! mesh to a soup and gives the same numbers.

#include "libmrtile/mesh.h"
#include "libmrtile/vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace mrt {

//! Topology of a triangle set. Faces whose three indices are not distinct are counted in `faces` and
//! `degenerate_faces` but are left out of every other count (they have no well-defined edges); faces of
//! zero area with distinct indices take part in the topology like any other face.
struct TopologyStats
{
    std::size_t vertices = 0;        //!< all vertices, isolated ones included
    std::size_t faces = 0;           //!< all faces
    std::size_t edges = 0;           //!< undirected edges
    std::size_t boundary_edges = 0;  //!< edges with exactly one incident face
    //! Closed chains of boundary edges; at a pinched vertex a chain follows the fan it came from. On a
    //! mesh with non-manifold edges a chain cut at such an edge is still counted as one loop.
    std::size_t boundary_loops = 0;
    //! Connected components of faces (faces sharing a vertex are connected).
    std::size_t components = 0;
    //! V - E + F over vertices that have a face and faces with three distinct vertices.
    long euler_characteristic = 0;
    //! Sum over components of (2 - χ_c - b_c) / 2; -1 if any component is non-manifold (a non-manifold
    //! edge or vertex) or non-orientable, where this formula does not apply.
    int genus = 0;
    std::size_t nonmanifold_edges = 0;  //!< edges with more than two incident faces
    //! Vertices whose incident faces, connected through edges with exactly two faces, form more than one
    //! fan: bow-ties, pinches, and the end points of non-manifold edges.
    std::size_t nonmanifold_vertices = 0;
    //! Faces with the same vertex set as an earlier face (a face present twice counts once).
    std::size_t duplicate_faces = 0;
    //! Faces with a repeated vertex or with area <= 1e-14 * (bounding-box diagonal of the used vertices)^2.
    std::size_t degenerate_faces = 0;
    std::size_t isolated_vertices = 0;  //!< vertices with no face
    //! Every edge with two or more faces is used equally often in each direction (once each way for an
    //! interior edge). True for a mesh without such edges.
    bool consistently_oriented = true;
};

//! \brief Topology of a mesh (deleted elements are ignored).
TopologyStats topology_stats(const Mesh& mesh);

//! \brief Topology of a triangle soup, without OpenMesh: can count non-manifold edges.
//! \throw InvalidInput if a triangle refers to a vertex index >= positions.size().
TopologyStats topology_stats(const std::vector<Vec3>& positions,
                             const std::vector<std::array<std::uint32_t, 3>>& triangles);

//! Distances as fractions of `diagonal`, the bounding-box diagonal of the points.
struct DistanceStats
{
    double mean = 0.0;
    double max = 0.0;
    double rms = 0.0;
    double median = 0.0;    //!< separates a uniformly loose fit from a few far-off points (holes, bridges)
    double p99 = 0.0;       //!< 99th percentile
    double diagonal = 0.0;  //!< absolute, in the units of the positions
    //! Points farther than kFarFraction of the diagonal and than `far_beyond` (point_to_mesh_distance):
    //! points the mesh leaves out (a far piece too small to mesh, strays), which also widen the diagonal
    //! the fractions are of.
    std::size_t far = 0;
    //! The mean over the points not counted in `far`: what the surface stands for (equals `mean` when
    //! `far` is 0). A few strays far off set most of `mean` on their own (QA round 57: five strays made
    //! 95% of a 20,000-point sphere's mean, which `lods` compares level by level).
    double near_mean = 0.0;
};

constexpr double kFarFraction = 0.05; //!< DistanceStats::far: of the diagonal at the least

//! \brief Distance from each point to the closest point of the mesh surface (exact: closest point on the
//! triangles, not on the vertices). Deterministic; on the default number of threads (parallel.h).
//! \throw InvalidInput if points are given but the mesh has no face, if a point is not finite, or if the
//! points' bounding box has a zero diagonal (the fractions would be undefined). No points gives zeros.
//! `far_beyond` (model units) raises DistanceStats::far's bound above kFarFraction of the diagonal.
DistanceStats point_to_mesh_distance(const std::vector<Vec3>& points, const Mesh& mesh, double far_beyond = 0.0);

//! Which points DistanceStats::far counts, for point_to_mesh_distance.
struct FarPoints
{
    //! Model units: raises the bound above kFarFraction of the diagonal.
    double beyond = 0.0;
    //! One flag per point, nonzero for the points to count far, in place of the bound: the levels of a
    //! chain compared over the same points (QA round 60: a level that left 262 more points out of its
    //! mean looked more accurate for it). Its size must be the points'.
    const std::vector<char>* given = nullptr;
    //! When not null, set to one flag per point: 1 for the points counted far.
    std::vector<char>* found = nullptr;
};

//! \brief As above, with the far points chosen by `far_points`.
//! \throw InvalidInput as above, or if `far_points.given` does not have one flag per point.
DistanceStats point_to_mesh_distance(const std::vector<Vec3>& points, const Mesh& mesh, const FarPoints& far_points);

//! \brief The other one-sided distance: from the mesh (sampled at its vertices and face centroids) to
//! the closest point of `points`. Deterministic.
//! \throw InvalidInput if the mesh has vertices but no point is given, if a point is not finite, or if
//! the points' bounding box has a zero diagonal. An empty mesh gives zeros.
DistanceStats mesh_to_point_distance(const Mesh& mesh, const std::vector<Vec3>& points);

struct Hierarchy;

//! \brief The same, searching `points` through the hierarchy built over them (its nodes' point
//! ranges; `points` in its tree order: h.cloud.positions or h.raw_positions), so that no search
//! structure is built: a mesh of a 10M-point model measured in 0.1 s instead of 3 s for CGAL's
//! kd-tree. Same result as the overload above.
//! \throw InvalidInput as above, or if `points` does not have one position per point of `h`.
DistanceStats mesh_to_point_distance(const Mesh& mesh, const Hierarchy& h, const std::vector<Vec3>& points);

//! \brief The squared distance from each of `queries` to the nearest of `points`, searched through the
//! hierarchy as mesh_to_point_distance does (`points` in its tree order). Deterministic; `threads`
//! workers (0 = one per hardware thread) give the same result. With `near_enough` (one squared
//! distance per query), a query's search ends at the first leaf that holds a point within it: its
//! result is then at most that bound, not necessarily the nearest (for callers that only ask how far
//! beyond a bound a query lies; most queries end at their first leaf). With `first_nodes` (one node of
//! `h` per query, or -1), a query's search starts in that node's subtree (the node whose tile the query
//! lies on, say) and goes on from the root only where no point there is near enough: the same
//! guarantees, fewer nodes visited when the node holds points near the query.
//! \throw InvalidInput if `points` does not have one position per point of `h`, or is empty while
//! `queries` is not, or if `near_enough` or `first_nodes` does not have one entry per query, or a
//! first node is neither -1 nor a node of `h`.
std::vector<double> squared_nearest_point_distances(const Hierarchy& h, const std::vector<Vec3>& points,
                                                    const std::vector<Vec3>& queries, std::size_t threads = 0,
                                                    const std::vector<double>* near_enough = nullptr,
                                                    const std::vector<std::int32_t>* first_nodes = nullptr);

//! \brief Pairs of faces (handle indices, smaller first, sorted) whose triangles intersect other than in
//! the vertices and edges they share: geometric self-intersections of a combinatorially valid mesh (CGAL's
//! Polygon_mesh_processing::self_intersections). With `among`, only pairs of faces both in that list.
//! \throw InvalidInput if the mesh is not a manifold triangle mesh.
std::vector<std::pair<int, int>> self_intersecting_faces(const Mesh& mesh, const std::vector<int>* among = nullptr);

//! \brief Whether faces f and g meet other than in the corners and edges they share: the test
//! self_intersecting_faces applies (CGAL's strict face intersection, exact predicates). No shared
//! corner: any contact; one: the edge opposite it in either face touching the other face; an edge: the
//! two faces folded onto each other. Faces without area never intersect. \throw InvalidInput if a
//! handle is no face of the mesh (or a deleted one).
bool faces_intersect(const Mesh& mesh, Mesh::FaceHandle f, Mesh::FaceHandle g);

//! The same test for two triangles given by their corners, which need not be faces of the mesh yet (an
//! edit judged before it is made: untangle's edge collapses).
bool corners_intersect(const Mesh& mesh, const std::array<Mesh::VertexHandle, 3>& a, const std::array<Mesh::VertexHandle, 3>& b);

//! Whether two triangles that share no corner meet at all (CGAL's exact predicates); triangles without
//! area never do. For faces not yet in a mesh (the surface stage's hole fills).
bool triangles_meet(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b);

//! \brief The pairs of self_intersecting_faces that have at least one face in `faces` (smaller index
//! first, sorted): after an edit that moved only those faces, the pairs that can have changed, found by
//! box intersection of those faces against all faces instead of a test of the whole mesh. Entries that
//! name no face of the mesh are ignored.
std::vector<std::pair<int, int>> intersecting_pairs_with(const Mesh& mesh, const std::vector<int>& faces);

//! The point of a mesh's surface closest to a query point, and the face it lies on.
struct ClosestPoint
{
    int face = -1; //!< face handle index
    Vec3 point;
};

//! \brief The closest point of the mesh surface to each of `points` (exact; ties go to the face CGAL's
//! AABB tree meets first, the same for the same input), on up to `threads` threads (0 = one per hardware
//! thread). Deterministic: the result does not depend on the thread count.
//! \throw InvalidInput if points are given but the mesh has no face, or a point is not finite.
std::vector<ClosestPoint> closest_points(const std::vector<Vec3>& points, const Mesh& mesh, std::size_t threads = 0);

} // namespace mrt
