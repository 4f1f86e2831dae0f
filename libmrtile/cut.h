#pragma once
//! \file cut.h
//! \brief Cuts of the persistent hierarchy: which nodes become tiles.
//! \details A cut is a frontier of the tree: a set of nodes such that every point belongs to exactly
//! one of them (the hierarchy stores each node's points as a contiguous range, so any frontier is a
//! partition). Every cut here is found top-down — a node is kept when it need not be refined, else
//! its two children are examined — so it costs time proportional to the nodes visited, never to the
//! number of points. Cuts are returned in depth-first (= point) order.
//!
//! Errors used to decide refinement, all exact from the node statistics:
//!  - plane error λ_min(M): the sum of squared distances of the node's points to the tile plane (the
//!    paper's τ quantity). It never increases down the tree: the children's best planes fit at least
//!    as well as the parent's plane does, so refining always lowers the total Σ λ_min of a cut.
//!  - RMS plane distance sqrt(λ_min / count), relative to Hierarchy::scale (tolerance): the bounding
//!    box's largest side, far stray points aside (see tolerance_scale in point_cloud.h).
//!  - geometric error (node_error: max distance of a point to its tile plane, or the tile's coverage
//!    gap if larger), for screen-space error and 3D Tiles.
//!  - coverage gap (Node::coverage_gap): how far the tile reaches over a hole or notch of the surface.
//!    Where it exceeds the node's largest plane distance (it dominates the tile's error), cuts by
//!    tolerance and region also refine a node whose gap exceeds their limit, cuts by camera count it in
//!    the screen-space error, and the budget cut weighs it like a plane distance, so holes stay open at
//!    every level of detail fine enough to show them (a window of radius r: from tolerance
//!    r / Hierarchy::scale down).
//!
//! Cuts by tolerance, by region and by camera never refine a node whose RMS plane distance is at
//! or under its Node::noise_floor (0 where the sample is clean): below it a noisy sample's clusters are
//! blobs, not pieces of surface. Cuts by budget, τ and predicate do exactly what they are asked.

#include "libmrtile/hierarchy.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mrt {

using Cut = std::vector<std::int32_t>;

//! "Refine this node?" — asked only for internal nodes, parents before children.
using RefinePredicate = std::function<bool(const Hierarchy& h, std::int32_t node)>;

//! The general form: refine every internal node for which `refine` says yes.
Cut cut_by_predicate(const Hierarchy& h, const RefinePredicate& refine);

//! Scale-free: every tile's RMS plane distance is at most tolerance × Hierarchy::scale, and so is its
//! coverage gap where that exceeds its largest plane distance, or the tile is a leaf, or its parent
//! meets the gap rule and its RMS plane distance is at most the parent's noise floor. \throw InvalidInput if tolerance is negative or not finite.
Cut cut_by_tolerance(const Hierarchy& h, double tolerance);

//! The paper's τ: every tile's λ_min(ΔᵀΔ) is at most tau (or the tile is a leaf).
Cut cut_by_tau(const Hierarchy& h, double tau);

//! The best cut with `tiles` nodes (or all leaves, if fewer): starting from the root, always refine
//! the node with the largest plane error λ_min, or count × coverage gap² if larger and the gap exceeds
//! the node's largest plane distance (ties: smaller id). Exactly min(tiles, leaves) nodes.
//! \throw InvalidInput if tiles is 0.
Cut cut_by_budget(const Hierarchy& h, std::size_t tiles);

//! A sphere or box of interest refined to its own tolerance while the rest stays coarser.
struct FocusRegion
{
    enum class Shape { Sphere, Box };
    Shape shape = Shape::Sphere;
    Vec3 centre{0, 0, 0};       //!< sphere centre (relative to the cloud's origin)
    double radius = 0.0;        //!< sphere radius
    BoundingBox box;            //!< for Shape::Box
    double tolerance = 0.0;     //!< scale-free tolerance inside the region (as cut_by_tolerance)
};

//! True when the node's bounding box meets the region.
bool intersects(const Node& node, const FocusRegion& region);

//! \throw InvalidInput unless the region's tolerance is >= 0 and finite and, for a sphere, its centre
//! is finite and its radius finite and >= 0, or, for a box, its corners are finite with min <= max.
void check_region(const FocusRegion& region);

//! \throw InvalidInput naming the first node id of `cut` that is not in the hierarchy.
void check_node_ids(const Hierarchy& h, const Cut& cut);

//! \brief Checks that `cut` is a frontier of the tree: each point in exactly one of its nodes (in any order).
//! \throw InvalidInput starting with `what` and naming what is wrong: a node id not in the hierarchy, a
//! node listed twice, a node inside another node of the cut, or points in no node of it (a missing subtree).
void check_cut(const Hierarchy& h, const Cut& cut, const std::string& what);

//! Sorts `cut` in point order (by its nodes' first points): the depth-first order every cut of this
//! file comes in, and the one mesh_cut meshes in.
void sort_in_point_order(const Hierarchy& h, Cut& cut);

//! Whether `cut` is in point order (sort_in_point_order).
bool in_point_order(const Hierarchy& h, const Cut& cut);

//! What makes `cut` no frontier of the tree, in words (the text check_cut puts after `what`), or an
//! empty string when it is one. For entry points that say what they expected before naming the problem.
std::string cut_problem(const Hierarchy& h, const Cut& cut);

//! Every node meeting a region is refined to the smallest tolerance of the regions it meets; every
//! other node to `base_tolerance`. Nodes of cut_by_tolerance(h, base_tolerance) that meet no region
//! are in the result unchanged.
Cut cut_by_regions(const Hierarchy& h, double base_tolerance, const std::vector<FocusRegion>& regions);

//! The tolerance cut_by_regions refines `n` to: the smallest of the regions it meets, else `base_tolerance`.
double region_tolerance(const Node& n, double base_tolerance, const std::vector<FocusRegion>& regions);

//! Incremental refinement: every node of `cut` (a frontier: check_cut) that meets a region is replaced
//! by its subtree's frontier under the same rule as cut_by_regions (the smallest tolerance of the
//! regions a node meets, else `base_tolerance`); nodes meeting no region are kept. Cost: a sort of the
//! cut (check_cut) and the nodes visited under the refined nodes only.
//! refine_cut(cut_by_tolerance(h, base), base, regions) == cut_by_regions(h, base, regions) when every
//! region's tolerance is at most base.
Cut refine_cut(const Hierarchy& h, const Cut& cut, double base_tolerance, const std::vector<FocusRegion>& regions);

//! Incremental coarsening (`cut` a frontier: check_cut): groups of cut nodes are replaced by their highest common ancestor whose box
//! lies inside `region` and that meets the rule of cut_by_tolerance at `tolerance`.
//! Nodes not inside the region never change. So it is no undo of refine_cut with the same region (the
//! nodes refined for meeting it reach out of it): to move a focus or go back, ask for the cut wanted
//! (cut_by_regions with the regions left) and give it to update_mesh (refine_mesh.h).
Cut coarsen_cut(const Hierarchy& h, const Cut& cut, const FocusRegion& region, double tolerance);

//! A pinhole camera for view-dependent cuts (3D Tiles / CesiumJS convention).
struct Camera
{
    Vec3 position{0, 0, 0};          //!< relative to the cloud's origin
    double fov_y_degrees = 60.0;     //!< vertical field of view
    double viewport_height = 1080.0; //!< pixels
    double max_pixel_error = 16.0;   //!< CesiumJS's default maximumScreenSpaceError
    //! Where the camera looks (any length; zero = all around, every node counts as in view). Nodes
    //! wholly outside the view cone are refined against max_pixel_error × out_of_view_factor: a
    //! viewer would cull them, and the mesh keeps them coarser but whole.
    Vec3 direction{0, 0, 0};
    //! ≥ 1; infinity = nodes out of view are never refined. Not refining them at all left a camera
    //! that looks away from a closed object with the root's tile alone, an open disc (QA, session 19);
    //! refined 4× coarser than in view they still close the surface behind the camera.
    double out_of_view_factor = 4.0;
    //! Viewport width / height: the view cone's half-angle is that of the viewport's corners,
    //! atan(tan(fov/2) × sqrt(1 + aspect²)).
    double aspect = 16.0 / 9.0;
};

//! Throws InvalidInput unless 0 < fov_y_degrees < 180, viewport_height, max_pixel_error and aspect
//! are positive and finite, out_of_view_factor ≥ 1 and position and direction are finite. Every
//! function below that takes a camera calls it.
void check_camera(const Camera& camera);

//! A node's geometric error in model units: the largest distance of its points to its tile plane,
//! or its coverage gap if larger.
double node_error(const Node& node);

//! Screen-space error of a node seen from the camera: error × height / (distance × 2 tan(fov/2)),
//! with error = node_error(node) and distance to the node's bounding box (0 inside).
double screen_space_error(const Node& node, const Camera& camera);

//! Whether any of the node's bounding box (its bounding sphere) can be inside the camera's view cone
//! (always true without a direction, or with the camera inside the sphere).
bool in_view(const Node& node, const Camera& camera);

//! Refines every node whose screen-space error exceeds the camera's max_pixel_error, or that many
//! times out_of_view_factor when it is out of view (in_view), down to the noise floor.
Cut cut_for_camera(const Hierarchy& h, const Camera& camera);

//! Whether the camera asks for `node` finer (cut_for_camera's rule before the node's own limits: its
//! noise floor, a leaf): its screen-space error exceeds max_pixel_error in view, or that many times
//! out_of_view_factor out of it.
bool camera_asks_finer(const Node& node, const Camera& camera);

//! Σ λ_min over the cut (a frontier: check_cut): the total squared distance of the points to their tile planes.
double cut_plane_error(const Hierarchy& h, const Cut& cut);

//! True when the nodes of `cut` partition the points (each point in exactly one node).
bool is_partition(const Hierarchy& h, const Cut& cut);

//! \brief Whether `n` spreads over a surface while a child of it lies along one line (across the line
//! its 8 or more points spread under a thirtieth of their spread along it, and under two of their
//! spacings along it: a thin tube is as long and thin, but its points go round it).
//! \details A stretch of a single scan line fits every plane through it, so its plane distance says
//! nothing and its tile is a sliver with no surface: where a scan's lines lie farther apart than a
//! leaf runs along one (30 points along a line per spacing across), the cuts by tolerance, region and
//! camera stop at such a node whatever its plane distance (a terrain scanned 30:1 at tolerance 0.002
//! was meshed from those slivers: 143 pieces, 6,218 crossing pairs). Budget and τ cuts do not.
bool splits_into_lines(const Hierarchy& h, const Node& n);

} // namespace mrt
