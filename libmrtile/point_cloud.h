#pragma once
//! \file point_cloud.h
//! \brief The input of the pipeline: positions only (plus optional colours), with a double origin.
//! \details Georeferenced scans have coordinates near 10^6..10^7. Every algorithm works on positions
//! relative to `origin` (set near the points' median by recenter()), so that the same cloud far from
//! the origin gives the same hierarchy and meshes as near it. Writers add `origin` back (or emit it as a
//! transform).

#include "libmrtile/vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace mrt {

struct BoundingBox
{
    Vec3 min{0, 0, 0};
    Vec3 max{0, 0, 0};

    Vec3 centre() const { return (min + max) * 0.5; }
    Vec3 size() const { return max - min; }
    double largest_side() const;
    double diagonal() const;
    //! Whether the two boxes share a point (touching counts).
    bool meets(const BoundingBox& other) const
    {
        return min.x <= other.max.x && other.min.x <= max.x && min.y <= other.max.y && other.min.y <= max.y &&
               min.z <= other.max.z && other.min.z <= max.z;
    }
    bool contains(const Vec3& p) const
    {
        return p.x >= min.x && p.y >= min.y && p.z >= min.z && p.x <= max.x && p.y <= max.y && p.z <= max.z;
    }
    //! Squared distance from p to the box (0 inside).
    double squared_distance_to(const Vec3& p) const
    {
        return squared_norm(mrt::max(mrt::max(min - p, p - max), Vec3{0, 0, 0}));
    }
};

//! \brief A file whose coordinates were stored as 32-bit floats so far from the origin that adjacent
//! float32 values lie more than 1e-4 of the points' extent apart: detail lost before reading began
//! (nearby points stored as one, a stepped surface), which no tolerance brings back.
struct CoarseCoordinates
{
    std::string file;
    double magnitude = 0; //!< the largest absolute coordinate stored as float32
    double spacing = 0;   //!< the distance between adjacent float32 values at that magnitude
    double extent = 0;    //!< the largest side of the bounding box of the file's points
};

struct PointCloud
{
    //! Added to every position to get the input's coordinates.
    Vec3 origin{0, 0, 0};
    //! Positions relative to origin.
    std::vector<Vec3> positions;
    //! Optional per-point RGBA colour: empty, or one entry per position.
    std::vector<std::array<std::uint8_t, 4>> colors;
    //! Where the sensor stood (relative to origin), when the input says so (a depth camera's PCD, a
    //! single-scan PTX). Open surfaces are oriented to face it: a scan's mesh faces its scanner. Empty:
    //! open surfaces face the way their shape suggests (see build_surface).
    std::optional<Vec3> viewpoint;
    //! The coordinate reference system the input declares for its coordinates, as it declares it:
    //! "EPSG:N" or OGC WKT (a LAS file's GeoTIFF keys or WKT record, or the CLI's --crs). Empty: unknown.
    //! Only placement on the globe uses it (3D Tiles export, see formats/lod_tileset.h); the hierarchy
    //! and meshes stay in the input's coordinates.
    std::string crs;
    //! The input files whose float32 coordinates are coarse for the object (see CoarseCoordinates), as
    //! the readers that know the stored type (PLY, PCD) find them; append() keeps every file's. The
    //! library only records them: the caller decides whether to say so (the CLI prints a note).
    std::vector<CoarseCoordinates> coarse_coordinates;

    std::size_t size() const { return positions.size(); }
    bool empty() const { return positions.empty(); }
    bool has_colors() const { return !colors.empty(); }
};

//! Bounding box of the positions (relative to origin). An empty cloud gives a zero box.
BoundingBox bounding_box(const std::vector<Vec3>& positions);
//! Bounding box of positions[0 .. count) (a zero box for none).
BoundingBox bounding_box(const Vec3* positions, std::size_t count);

//! Moves the origin, per axis on which the points do not straddle 0, to the median of the absolute
//! coordinates (of a strided sample of at most 65,536 points), rounded to a whole number so that the
//! origin is exact in every output format; positions change by the same offset. The median, unlike the
//! box centre, stays among the points when a few strays lie far away, so the points keep their digits.
void recenter(PointCloud& cloud);

//! \brief Appends `from` to `into` in absolute coordinates (positions rebased onto `into`'s origin; call
//! recenter afterwards; into an empty cloud, `from` is moved as it is). Colours are kept when either
//! cloud has them; the points of a cloud without colours are white (glTF multiplies vertex colours into
//! the material, and white leaves it as it is). The viewpoint is kept only when both clouds have the
//! same one (scans from different places have none in common); so is the CRS.
void append(PointCloud& into, PointCloud from);

//! \brief Step k for using every k-th of `count` points so that at most about `max_points` are used
//! (1 when max_points is 0 or not below count). Points in a spatially coherent order (the hierarchy's)
//! stay spread over the whole surface under a fixed step.
inline std::size_t sample_stride(std::size_t count, std::size_t max_points)
{
    return max_points == 0 || count <= max_points ? 1 : (count + max_points - 1) / max_points;
}

//! The largest extent (bounding-box side) a cloud may have, in its units.
inline constexpr double kMaxExtent = 1e30;
//! The smallest non-zero extent a cloud may have: 32-bit floats (glTF, STL) keep their 24 bits down to
//! 1.2e-38 only, so a mesh 1e-30 across keeps about a millionth of its extent; the squares of far
//! smaller ones underflow in the build (1e-80 and less: no surface was left).
inline constexpr double kMinExtent = 1e-30;

//! \throw InvalidInput naming `what` unless the colours are empty or one per position (what every
//! stage that moves points together with their colours checks first: QA round 59 found
//! remove_outliers and remove_duplicates writing past a shorter colour buffer).
void check_colors(const PointCloud& cloud, const std::string& what);

//! \brief Checks a cloud before building a hierarchy.
//! \throw InvalidInput naming `what` (typically the file name) if a position is NaN or infinite (with
//! its index), if the points span more than kMaxExtent or less than kMinExtent (but not 0), if colours do not match positions, or if the
//! cloud is empty.
void validate(const PointCloud& cloud, const std::string& what);

//! \brief The length the scale-free tolerance is relative to: the largest side of the bounding box of
//! the points, leaving out far stray points.
//! \details A point is far when it lies more than one box size (the largest side of the box between the
//! 1st and 99th percentiles of each coordinate) outside that box. Far points are a few stray returns
//! (a lidar pulse off a bird, a photogrammetry mismatch): counted, a single one 50 object sizes away
//! made every default tolerance 80 times coarser (the bunny became 9 faces). Anything nearer, or more
//! than 1% of the cloud, counts. Percentiles come from a sample chosen by position (independent of
//! the order of the points); the result is exact for the box it chooses. 0 for fewer than 2 points.
double tolerance_scale(const std::vector<Vec3>& positions);

//! \brief Indices of the first occurrence of each distinct position, in increasing order (so in the
//! input's order). Positions are equal when their coordinates compare equal (-0 == +0).
//! \details Linear time (a hash table of indices). Used by build_hierarchy to merge exact duplicates.
std::vector<std::uint32_t> first_occurrences(const std::vector<Vec3>& positions);

//! Keeps only the first occurrence of each distinct position (and its colour); returns the input
//! indices of the points kept (first_occurrences). \throw InvalidInput unless the colours are empty or one
//! per position (check_colors).
std::vector<std::uint32_t> remove_duplicates(PointCloud& cloud);

} // namespace mrt
