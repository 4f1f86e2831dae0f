#pragma once
//! \file coverage_gap.h
//! \brief How far a cluster's tile reaches over surface its points do not cover (holes and notches).
//! \details A tile is the convex hull of its cluster in the cluster's plane (paper §4.2), so a flat
//! cluster around a window, a hole in a plate or the inner corner of an L-shaped part covers it: the
//! paper's flatness test never splits such a cluster, and its tile fills the hole. The coverage gap
//! measures that error: the radius of the largest disc inside the hull that holds no point, counted
//! only where the surrounding sampling density says the disc should have held points (a real hole,
//! not a sparse patch of an uneven sample). The build splits clusters that have one (BuildOptions::
//! split_gaps) and cuts refine nodes whose gap exceeds their tolerance (cut.h), so holes stay open at
//! every level of detail fine enough to show them.
//!
//! Method, on the points projected into the plane: a grid of cells holding about points_per_cell
//! points each at the mean density; the empty cells whose centres lie inside the hull form connected
//! regions; a region counts when both
//!  - a disc of min_radius_spacings local point spacings fits in it (the spacing from the density of
//!    the occupied cells around it, so that a thinly sampled patch is judged by its own density), and
//!  - at that density it would hold at least min_missing_points points (a uniform random sample leaves
//!    such an empty region with probability about e^-min_missing_points), and
//!  - it surrounds almost no points (max_island_share): the sparse middle of an unevenly sampled
//!    surface is a region around scattered points, a hole is empty;
//! its gap is the distance to the nearest point from its cell centre farthest from occupied cells. Costs
//! O(m log m) for m points (the hull's sort), m capped by max_points (a regular sample of the rest).

#include "libmrtile/hierarchy.h"
#include "libmrtile/vec3.h"

#include <cstddef>
#include <vector>

namespace mrt {

struct CoverageOptions
{
    //! Grid cell size: cells hold about this many points at the cluster's mean density.
    double points_per_cell = 4.0;
    //! A region counts when a disc of this many local point spacings fits inside it. The surface stage
    //! keeps holes open from a mean width of SurfaceOptions::max_gap_width (4) spacings on, so smaller
    //! regions would be filled by the mesh anyway.
    double min_radius_spacings = 4.0;
    //! ... and when the surrounding density says it should hold at least this many points.
    double min_missing_points = 16.0;
    //! The points judged are this fraction of the surface's points (a regular sample: coverage_stride,
    //! or a tile's sample). The spacing the surface stage sees is that of all points, so the radius
    //! needed shrinks to min_radius_spacings × sqrt(sample_fraction) of the sample's spacings, but not
    //! below min_sample_radius_spacings, where an empty disc in a uniform random sample is still
    //! unlikely (it would hold about 20 points).
    double sample_fraction = 1.0;
    //! ... and when the points inside it (groups of points it surrounds) are at most 2 plus this share of
    //! the points it misses: a hole holds no points (a stray few), the sparse part of an uneven sample
    //! holds some.
    double max_island_share = 0.01;
    //! The smallest disc radius (in sample spacings) a sampled cluster's hole must fit (see
    //! sample_fraction above).
    double min_sample_radius_spacings = 2.5;
    //! Callers judge at most about this many points of a cluster (every k-th: coverage_stride); 0 = all.
    std::size_t max_points = 1024;
};

//! \brief The coverage gap (model units, 0 when there is none) of `points` in the plane spanned by the
//! unit vectors axis_u and axis_v.
//! \details Fewer than 8 points, or points without area in the plane, have none. `fill` are points of
//! other clusters near the plane: they occupy the grid but do not widen the hull (a cluster that is
//! not convex has a hull reaching over its neighbours' points, which is no hole in the surface). All
//! points given are judged: sample larger sets with coverage_stride.
//! \throw InvalidInput if a point, fill point or axis is not finite, or an option is out of range.
double coverage_gap(const std::vector<Vec3>& points, const Vec3& axis_u, const Vec3& axis_v,
                    const CoverageOptions& options = {}, const std::vector<Vec3>& fill = {});

//! \brief Half the widest empty strip between two groups of `points` along axis_u or axis_v: two objects
//! whose points lie within the tolerance of one plane through both (two small spheres far apart), whose
//! hull spans the space between them. coverage_gap misses it where the hull is narrower than a few grid
//! cells. Counted when the strip is wider than a quarter of the points' extent along that axis and than
//! `min_width` (from the caller: a cluster's own density cannot tell two far objects from two clumps of
//! near-equal points one spacing apart), and at most 2 + max_island_share × the points of `fill` (other
//! clusters' points) lie in it; else 0. A connected patch projects onto an interval without such a strip.
double separation_gap(const std::vector<Vec3>& points, const Vec3& axis_u, const Vec3& axis_v, double min_width,
                      const CoverageOptions& options = {}, const std::vector<Vec3>& fill = {});

//! The widest gap between consecutive values in sorted order (of equal ones, the lowest), where it
//! starts, and the values' extent (max - min); all 0 for fewer than two values or equal ones.
struct WidestGap
{
    double width = 0.0;
    double from = 0.0;
    double extent = 0.0;
};
//! \brief As sorting `values` and scanning them, in linear time up to 2^20 values (separation_gap's
//! share of building a hierarchy of a 1M-point terrestrial scan was a third, most of it sorting);
//! beyond, by sorting them (taken by value: a caller done with them moves them in, and no copy is
//! made), since the buckets would take 4x the values' memory. Values must be finite.
WidestGap widest_gap(std::vector<double> values);

//! \brief The empty regions that count (coverage_gap), kept to ask where they are: whether a fill
//! between tiles would cover a hole of the sample (surface stage). The hull is that of all `points`.
class CoverageMap
{
public:
    CoverageMap(const std::vector<Vec3>& points, const Vec3& axis_u, const Vec3& axis_v, const CoverageOptions& options = {});
    //! The coverage gap (as coverage_gap).
    double gap() const { return gap_; }
    //! Whether p, projected into the plane, lies in a counted empty region whose radius (its largest
    //! distance to a point) is at least min_radius.
    bool in_gap(const Vec3& p, double min_radius = 0.0) const;
    //! With in_gap(p, min_radius): sets `centre` to the spot of p's region farthest from the points (at
    //! p's height above the plane) and `radius` to its distance to them (the region's radius).
    bool gap_disc(const Vec3& p, double min_radius, Vec3& centre, double& radius) const;

private:
    static constexpr std::size_t kNoCell = static_cast<std::size_t>(-1);
    //! The grid cell of p, projected into the plane, when it lies in a counted empty region of radius
    //! at least min_radius; kNoCell otherwise.
    std::size_t gap_cell(const Vec3& p, double min_radius) const;

    Vec3 origin_{0, 0, 0}, u_, v_;
    double x0_ = 0, y0_ = 0, g_ = 1, gap_ = 0;
    int nx_ = 0, ny_ = 0;
    std::vector<float> counted_; // per grid cell: the radius of its counted region, 0 for none
    std::vector<std::uint32_t> centre_; // per counted cell: its region's cell farthest from the points
};

//! Every how many points to judge out of `count` (1 up to options.max_points).
std::size_t coverage_stride(std::size_t count, const CoverageOptions& options = {});

//! \brief A node's own gap from its children alone (what set_coverage_gaps adds to its own judged gap):
//! the distance between its children's boxes when that exceeds a quarter of its box's diagonal and 8
//! of its point spacings, 4 where the children face each other across it; else 0 (also for a leaf).
//! lod_set.cpp asks it to tell which nodes' gaps stray points far off made (a bird split off the
//! ground is a child 45 m from its sibling).
double children_separation(const Hierarchy& h, const Node& n, const CoverageOptions& options = {});

//! \brief Sets every node's Node::coverage_gap: its own gap in its PCA plane (judged from a regular
//! sample of options.max_points of its points), with the points of other nodes within its largest
//! plane distance of that plane filling the grid, or, if larger, the distance between its children's
//! boxes when that exceeds a quarter of its box's diagonal and 8 of its point spacings (two objects
//! far apart in one cloud: its tile would span the space between them), 4 where the children face each
//! other across it (the two sides of a thin part), then the largest of its own and its children's.
//! Nodes of fewer than options.max_points points get no gap of their own (the build has judged
//! its leaves at full resolution, and mesh_cut judges every tile it makes): that keeps the cost to
//! about two passes over the points (0.15 s for a million, single-threaded). build_hierarchy and load_model call it. Parallel over nodes on up to
//! `threads` threads (0 = default); the result does not depend on it.
void set_coverage_gaps(Hierarchy& h, std::size_t threads = 0, const CoverageOptions& options = {});

} // namespace mrt
