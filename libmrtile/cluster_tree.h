#pragma once
//! \file cluster_tree.h
//! \brief Divisive clustering of a point cloud into a persistent binary hierarchy (paper §4.1).
//! \details
//! \code
//! clusters = { all points }
//! while some cluster fails the flatness test and has more than min_cluster points:
//!     C = that cluster with the largest internal error (eq. 1: sum of distances to its centre)
//!     offset = C.count <= pca_limit ? σ_max · principal axis          (PCA, eq. 2-3)
//!                                   : (farthest point − centre) / 2   (direction of highest deviation)
//!     split C into A, B with centres centre ± offset
//!     reclassify the points of C and of its Gabriel neighbours to their nearest centre among
//!         {A, B} ∪ neighbours(C) (points of a neighbour N: among {N, A, B})
//!     move the centres to the means of their new points; update the Gabriel graph locally
//! \endcode
//! The splits form a binary tree. Reclassification moves points across subtrees while building, so
//! the stored tree is rebuilt exactly for the *final* assignment: points are reordered so every node
//! owns a contiguous range, and each node's statistics are those of exactly its points. Any frontier
//! cut of the result therefore partitions the input exactly (see hierarchy.h).
//! Deviation from the paper (default; BuildOptions::paper_split_order restores the literal rule): only
//! clusters that fail the flatness test are split (the paper splits the highest-error cluster while
//! *any* cluster fails); the order among them is the paper's. The tree then refines only where the
//! surface needs it, which keeps it small; the cut decides the level of detail anyway.

#include "libmrtile/denoise.h"
#include "libmrtile/hierarchy.h"

#include <cstddef>
#include <functional>

namespace mrt {

struct BuildOptions
{
    //! Scale-free flatness (default stop criterion): a cluster is flat enough when the RMS distance
    //! of its points to their best-fit plane is at most `tolerance` × the largest side of the cloud's
    //! bounding box, far stray points aside (tolerance_scale, point_cloud.h). Used when `tau` is 0. The default is fine enough that the hierarchy serves every
    //! level of detail a renderer wants; cuts choose coarser levels later.
    double tolerance = 1e-4;
    //! The paper's τ_PCA,lim: flat enough when the smallest eigenvalue of M = ΔᵀΔ (eq. 2-3, not
    //! divided by the point count) is at most `tau`, in model units squared. > 0 overrides tolerance.
    double tau = 0.0;
    //! τ_PCA: clusters with at most this many points split along their principal axis (PCA); larger
    //! ones along the direction of highest deviation (towards the point farthest from the centre).
    std::size_t pca_limit = 500;
    //! Clusters with at most this many points are never split (leaves may end smaller than this
    //! after reclassification).
    std::size_t min_cluster = 16;
    //! The paper's literal order: while any cluster fails the flatness test, split the cluster with the
    //! largest internal error *whether or not it is flat itself*. Gives more uniform tiles (and more of
    //! them); used to reproduce the paper's Table 2. Off (default): only failing clusters are split.
    bool paper_split_order = false;
    //! Local reclassification over Gabriel neighbours after each split (paper §4.1). Off gives a pure
    //! top-down bisection tree (faster, blockier clusters).
    bool reclassify = true;
    //! Merge points at exactly the same position into one (the first occurrence and its colour stay;
    //! Hierarchy::input_index then skips the others). A duplicate adds no shape but counts towards
    //! min_cluster, so clouds with repeated points (mesh vertices exported per face, quantized
    //! coordinates, concatenated files) would end in leaves of one or two positions that span no
    //! tile, and the surface would break into holes (a sphere with every point ten times: 61 loops).
    bool merge_duplicates = true;
    //! Beyond the paper: also split flat clusters whose tile (the convex hull of their points) would
    //! cover a hole or notch of the sampled surface (coverage_gap.h: a window in a wall, a hole in a
    //! plate, the inside corner of an L-shaped part), until no leaf does. The paper splits by flatness
    //! alone, so such a cluster stays one tile and the hole is filled. Clouds without such holes get
    //! the same hierarchy either way. Not with paper_split_order (the paper's tree exactly).
    bool split_gaps = true;
    //! Beyond the paper: a noisy sample's points are moved onto the surface they sample (denoise.h)
    //! and the hierarchy is built again from them. Auto (default): when the first build finds the
    //! sample noisy (sample_is_noisy, hierarchy.h: its leaves are blobs, as under noise of about a
    //! point spacing; no clean scan, CAD part or generated shape measured comes near). The hierarchy
    //! then holds the moved points (BuildInfo::denoised) and, until saved, the points read
    //! (Hierarchy::raw_positions), which measure_quality measures to.
    enum class Denoise { Auto, Off, On };
    Denoise denoise = Denoise::Auto;
    DenoiseOptions denoising; //!< how points are moved when denoised (denoise.h; defaults: 48-point quadrics)
    //! Called now and then with what the build is doing and how far it is (0..1): "building
    //! hierarchy" (the fraction of points already in flat clusters), and for a noisy sample then
    //! "denoising" (of points moved) and "building hierarchy of the denoised points". Each stage
    //! ends with 1. One call at a time (the denoising calls from any of its threads).
    std::function<void(const char* stage, double fraction)> progress;
};

//! \brief Builds the hierarchy of a point cloud.
//! \param cloud positions relative to cloud.origin (see recenter()); moved into the result, reordered.
//! \throw InvalidInput if the cloud is empty, has non-finite coordinates, more than 2^32-1 points, or
//! an option is out of range (negative tolerance or τ, min_cluster 0).
//! \details Degenerate clouds (one point, duplicates, collinear or coplanar points) give a valid
//! hierarchy (typically a single leaf: they are flat). With merge_duplicates, the hierarchy holds the
//! distinct positions only (BuildInfo::duplicates_merged says how many points went). Deterministic: the same cloud and options give
//! the same hierarchy bit for bit. A denoised build (BuildOptions::denoise) costs a first build (not
//! with Denoise::On), the denoising (about 6-10 µs per point) and the second build.
Hierarchy build_hierarchy(PointCloud cloud, const BuildOptions& options = {});

//! build_hierarchy recentres (recenter(), point_cloud.h) a cloud whose points lie farther than this
//! many times their extent from its origin: the hierarchy's cloud then has another origin, its
//! positions the same points relative to it (meshes are relative to Hierarchy::cloud.origin, which the
//! writers add back). Beyond 1e9 times it refuses the cloud: the input has lost its digits.
inline constexpr double kRecenterBeyond = 1e3;

//! Builds the tree's nodes from a final assignment of points to leaves and their split history; the
//! last step of build_hierarchy(), public for tests and tools that bring their own partition.
//! `parent_of[c]` is the cluster that was split to make cluster c (-1 for the root, which is cluster
//! 0); `leaf_of_point[i]` is the leaf cluster of point i. Empty leaves are dropped and internal nodes
//! left with one child are spliced out, so the result is a strict binary tree. Its BuildInfo records a
//! min_cluster of 1 (build_hierarchy records its own options).
//! \throw InvalidInput if the cloud fails validate() (non-finite points, colours not one per point, ...),
//! a cluster has more than two children, a parent is listed after its child, or a point's cluster is no leaf.
Hierarchy assemble_hierarchy(PointCloud cloud, const std::vector<std::int32_t>& parent_of,
                             const std::vector<std::uint32_t>& leaf_of_point);

} // namespace mrt
