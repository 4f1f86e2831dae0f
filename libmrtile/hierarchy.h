#pragma once
//! \file hierarchy.h
//! \brief The persistent multiresolution hierarchy: a strict binary tree of clusters over the points.
//! \details Built by build_hierarchy() (cluster_tree.h, paper §4.1), saved and loaded by model_file.h.
//! Invariants (checked by the tests):
//!  - the points are stored in tree order: every node's points are the contiguous range [begin, end)
//!    of `cloud.positions`, a node's range is the concatenation of its children's ranges, so **any
//!    frontier cut of the tree partitions the points exactly**;
//!  - every internal node has exactly two children, every node holds at least one point;
//!  - a node's moments are exactly those of its points (they merge: parent = left ⊕ right);
//!  - nodes are stored parents before children; nodes[0] is the root.

#include "libmrtile/pca.h"
#include "libmrtile/point_cloud.h"
#include "libmrtile/single_view.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace mrt {

//! Which flatness test ended the splitting; kept in the model so cuts can use the same measure.
enum class Criterion : std::uint32_t
{
    //! Scale-free (our default): RMS distance of a cluster's points to its best-fit plane at most
    //! value × Hierarchy::scale (the largest side of the cloud's bounding box, far stray points aside).
    Tolerance = 0,
    //! The paper's τ_PCA,lim: smallest eigenvalue of M = ΔᵀΔ at most value (model units squared).
    Tau = 1,
};

struct Node
{
    std::uint32_t begin = 0; //!< first point (index into Hierarchy::cloud.positions)
    std::uint32_t end = 0;   //!< one past the last point
    std::int32_t parent = -1;
    std::int32_t left = -1;  //!< -1 for a leaf
    std::int32_t right = -1; //!< -1 for a leaf
    std::uint32_t depth = 0; //!< root = 0
    Moments moments;         //!< count, mean (the cluster centre), M = ΔᵀΔ
    //! Paper eq. 1: sum of the distances of the node's points to its centre.
    double internal_error = 0.0;
    //! Largest distance of a point of the node to the node's best-fit plane (model units). Bounds the
    //! geometric error of the node's tile; used for screen-space error and 3D Tiles geometricError.
    double max_plane_distance = 0.0;
    //! Axis-aligned bounding box of the node's points (relative to the cloud's origin). A child's box
    //! lies inside its parent's. Used by region and camera cuts and as 3D Tiles bounding volumes.
    BoundingBox box;
    //! How far the node's tile reaches over surface that no point samples (model units; 0 for none):
    //! the largest coverage gap (coverage_gap.h) of the node or a node under it, whose tiles its tile
    //! covers. A hole or notch shows in a cut only where the tiles around it have gaps under the cut's
    //! tolerance, so cuts refine by it as by the plane distance (cut.h).
    double coverage_gap = 0.0;

    // Derived from `moments` when the hierarchy is built or loaded (not stored in the file).
    Eigen3x3 frame;                  //!< PCA: frame.vectors[0] = normal, frame.values[0] = λ_min(M)
    double rms_plane_distance = 0.0; //!< sqrt(λ_min / count)
    //! RMS plane distance at or under which refining this node fits the noise of the points, not the
    //! surface (model units; 0 where the sample is clean). Cuts by tolerance, region and camera (cut.h)
    //! never refine a node whose rms_plane_distance is at or under it. See derive_noise_floor.
    double noise_floor = 0.0;

    bool is_leaf() const { return left < 0; }
    std::uint32_t count() const { return end - begin; }
    const Vec3& centre() const { return moments.mean; }
};

//! Whether the node's coverage gap is what its tile's error is made of: larger than the distance of
//! its points to its plane. A cluster across a sharp edge is far from its plane anyway (and where the
//! sampling density jumps at the edge its sparse side can look empty); the gap of a flat one is all
//! there is to its error. Cuts, LOD errors and the surface stage count a gap only where it dominates.
inline bool gap_dominates(const Node& n) { return n.coverage_gap > n.max_plane_distance; }

//! The point spacing of a node's points from their spread in its plane: n points spread evenly over a
//! rectangle of sides L1, L2 have variances L² / 12 along them, so the area is 12 σ1 σ2 (0 for an empty
//! node). Unlike a tile's hull area over its node's points, it does not depend on the cut around it.
double node_spacing(const Node& n);

//! How a node's points spread across the line of their largest axis (RMS along the second axis) and
//! how far apart they lie along it, taken as spread evenly over a segment (variance L² / 12, so the
//! spacing is L / count); model units, both 0 for an empty node. The line tests compare the two, each
//! with its own factor: cut.cpp's is_line (across at most 2 spacings along: a stretch of a scan line
//! with its noise) and the coverage gap's facing rule (a node has a normal when it spreads across more
//! than half a spacing along).
struct LineSpread
{
    double across = 0.0;
    double spacing_along = 0.0;
};
LineSpread line_spread(const Node& n);

struct BuildInfo
{
    Criterion criterion = Criterion::Tolerance;
    double criterion_value = 0.0; //!< tolerance (fraction) or τ (units²)
    std::uint32_t pca_limit = 0;
    std::uint32_t min_cluster = 0;
    bool reclassify = true;
    double build_seconds = 0.0;
    //! Points merged into an earlier point at the same position (BuildOptions::merge_duplicates).
    //! Known at build time only: a loaded model says 0.
    std::size_t duplicates_merged = 0;
    //! The points were denoised before the build (BuildOptions::denoise, denoise.h): the stored
    //! positions are the moved ones.
    bool denoised = false;
};

struct Hierarchy
{
    //! The points in tree order (origin, relative positions, optional colours).
    PointCloud cloud;
    //! input_index[i] = index in the input of the point stored at tree position i. A permutation of
    //! the input's indices, less those of merged duplicates (distinct, increasing nowhere in particular).
    std::vector<std::uint32_t> input_index;
    std::vector<Node> nodes;
    BuildInfo info;
    //! The input's positions before denoising (BuildInfo::denoised), in tree order like cloud.positions,
    //! so that distances can be measured to what was read (measure_quality). Only in a hierarchy just
    //! built: not stored in the model file (a loaded denoised model has the moved points only); empty
    //! otherwise.
    std::vector<Vec3> raw_positions;
    //! How far the denoising moved each point (BuildInfo::denoised; tree order like cloud.positions;
    //! empty otherwise). The moved points keep residual noise, which their own leaves no longer show:
    //! each region's noise floor is raised from its points' typical move (derive_noise_floor), so that
    //! the finest cut of a denoised model stops above the noise where there was noise, and a part that
    //! had none (a clean scan merged with a noisy one) is cut as fine as asked. Stored in the model file.
    std::vector<float> denoise_moves;
    //! The length scale-free tolerances are relative to: tolerance_scale(cloud.positions) (the largest
    //! side of the bounding box, far stray points aside; point_cloud.h). Derived (update_derived).
    double scale = 0.0;
    //! With cloud.viewpoint: how many points hide behind others from it, and whether the cloud is one
    //! view from there (single_view_stats, single_view.h), which build_surface asks of every meshing.
    //! Derived (update_derived): set the viewpoint before, or call update_derived after changing it.
    std::optional<SingleViewStats> view;
    //! The convex hulls of the nodes of more than kHullStoredAbove points (tiles.h) in their PCA planes,
    //! as tree-order point indices, ascending: node k's are hull_points[hull_start[k] .. hull_start[k + 1])
    //! (empty for smaller nodes). A cut builds a large node's tile from a sample of its points and its
    //! hull, so that its cost follows the tiles, not the points under them. Stored in the model file
    //! (since version 3): save_model computes them (compute_node_hulls), load_model reads them, and
    //! set_node_hulls sets them on a hierarchy just built. Both empty: none (node_hull reads the points).
    std::vector<std::size_t> hull_start;
    std::vector<std::uint32_t> hull_points;

    std::size_t leaf_count() const;
    std::uint32_t max_depth() const;
    BoundingBox bbox() const { return bounding_box(cloud.positions); }
    //! The stop criterion's value for this node, in the criterion's own units: RMS plane distance
    //! divided by `largest_side` (pass Hierarchy::scale; Tolerance) or λ_min (Tau).
    double flatness(const Node& node, double largest_side) const;
};

//! \brief The points inside `box` (tree-order indices, ascending), found through the nodes' boxes;
//! with `stride` > 1 only the points whose index is a multiple of it are (a regular sample).
std::vector<std::uint32_t> points_in_box(const Hierarchy& h, const BoundingBox& box, std::size_t stride = 1);

//! \brief For each query k, whether a point of the cloud lies within radii[k] of it (squared distance
//! at most radii[k]²; never for a radius that is negative or NaN), searched through the nodes' boxes:
//! from first_nodes[k]'s subtree when given (a node near the query, or -1), then the rest. No box
//! beyond the radius is opened, so a query with no point near costs a few nodes, where a nearest-point
//! search (squared_nearest_point_distances, mesh_stats.h) goes on to the nearest point however far.
//! Deterministic; `threads` workers (0 = one per hardware thread) give the same result.
//! \throw InvalidInput if `radii` or `first_nodes` does not have one entry per query, or a first node
//! is neither -1 nor a node of `h`.
std::vector<char> has_point_within(const Hierarchy& h, const std::vector<Vec3>& queries, const std::vector<double>& radii,
                                   const std::vector<std::int32_t>* first_nodes = nullptr, std::size_t threads = 0);

//! Recomputes the derived fields: every node's frame and rms_plane_distance from its moments, then
//! scale, view and the nodes' noise floors (derive_noise_floor).
void update_derived(Hierarchy& h);

//! \brief Sets every node's noise_floor (update_derived calls it).
//! \details Where a sample's noise is about half its point spacing or more, its 16-point leaves are
//! blobs, not pieces of surface, and a cut made of them breaks into hundreds of pieces. Judged per
//! region: the highest nodes under 32 × min_cluster points partition the points; for each of at least
//! 8 × min_cluster points, its leaves' roughness (median RMS plane distance / RMS extent along the
//! second axis) says how rough the sample is at the finest scale, and the region's own roughness over
//! that says whether roughness rises with scale (curvature: 1.2–55 on every clean scan and CAD part measured) or
//! falls (noise: 0.2–0.5). The floor is 3 × the leaves' median RMS plane distance (a 16-point leaf fits
//! its plane to the noise: about half its σ), weighted from 0 at leaf roughness 0.2 to 1 at 0.4 and from
//! 0 at a ratio of 1 to 1 at 0.7; clean regions get 0. A region under half the largest is judged at its
//! parent's scale too, whichever is smoother (under noise of 1.5 spacings or more a region of 250 points
//! is still blob-like itself). Noise of two spacings or more makes the region a blob as well: its first
//! ancestor that is a slab (roughness under 0.35), if as thick as the region (RMS within 1.5×) and
//! spread about its plane as noise is (kurtosis over 2.2: a thin plate sampled on both sides has about
//! 1.3), sets the floor to 2 × its RMS plane distance. A region with noisy leaves whose own measures
//! give it no floor (across a sharp edge, or curved) takes the median floor of the regions near it in
//! the tree whose leaves look alike (median RMS within 1.5×), when those are half of the regions there,
//! else the whole sample's on the same terms. Smaller regions take the same measure over the whole
//! sample; nodes below a region take its floor, nodes above the smallest of their children's.
void derive_noise_floor(Hierarchy& h);

//! How far the denoising typically moved `count` points of Hierarchy::denoise_moves from `begin`:
//! 3.138 × their lower quartile, the RMS of moves that are Gaussian noise, without the large moves
//! where a quadric cannot follow the surface (a sharp edge can move half a region's points far); 0 for
//! none.
double typical_move(const Hierarchy& h, std::size_t begin, std::size_t count);

//! The share of a denoised region's typical move (typical_move) that is its noise floor.
inline constexpr double kDenoisedFloorShare = 0.7;

//! The noise floor a denoised region takes from its points' typical move (typical_move): the
//! residual noise of its moved points, kDenoisedFloorShare × the move. 0 when the hierarchy was not
//! denoised.
double denoised_noise_floor(const Hierarchy& h, const Node& region);

//! Sets every node's noise_floor to 0 (cut below the noise anyway).
void clear_noise_floor(Hierarchy& h);

//! The largest noise floor of any node (0 for a clean sample).
double max_noise_floor(const Hierarchy& h);

//! Where the noise floors stop the finest cut by tolerance (tolerance 0) above the leaves: the
//! points under those stops and the largest floor that stops it. A floor under a node's own RMS plane
//! distance stops nothing, so a clean sample forced through denoising, whose floors are tiny, has few
//! such points.
struct NoiseFloorStops
{
    std::size_t points = 0; //!< points of the topmost nodes the floor alone keeps from being refined
    double floor_max = 0.0; //!< the largest floor among those nodes (0: none)
};
NoiseFloorStops noise_floor_stops(const Hierarchy& h);

//! \brief Whether the sample is noisy throughout, with noise that breaks meshes: it has 8 regions or
//! more (the nodes derive_noise_floor judges; a smaller cloud is not judged) and its leaves are blobs
//! (median roughness, RMS plane distance / RMS extent along the second axis, 0.4 or more). Measured:
//! clean scans, CAD parts and generated shapes 0.01-0.17; noise of half a point spacing 0.25-0.32, of
//! one 0.48-0.54 (CAD parts too, whose sharp edges hide the noise from the floor's rules). The floors
//! are no measure of this: they come from noise of a fifth of a spacing on.
bool sample_is_noisy(const Hierarchy& h);

} // namespace mrt
