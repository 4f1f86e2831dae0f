#pragma once
//! \file read_points.h
//! \brief Point readers: PLY (ascii, binary little/big endian), LAS 1.0-1.4, PTX, PCD, XYZ/PTS/TXT/CSV,
//! OBJ (v lines), OFF, Stanford scan lists (.conf), each optionally gzip-compressed (.gz). Streaming: files are never slurped whole into strings.
//! \details What is read from each format:
//!  - PLY: the x/y/z properties of the `vertex` element (any scalar type), plus red/green/blue[/alpha]
//!    as colours when `keep_colors`. Other properties and elements are skipped, but a file that ends
//!    inside one (after the vertices too) is refused as truncated. ASCII PLY is read one
//!    element instance per line (as every writer produces it); a vertex line holding more values than
//!    its properties (list lengths included) take is refused. Data after the last element, or a second
//!    `vertex` element in the header, is refused (only part of the cloud would be read).
//!  - LAS 1.0-1.4, point formats 0-10: scaled coordinates, and colours (formats 2, 3, 5, 7, 8, 10;
//!    16-bit, or 0-255 as many writers store them: read as 0-255 unless some value exceeds 255).
//!    Withheld points and points classified as noise (classes 7 and 18) are left out. LAZ-compressed
//!    files are refused with a hint (no LASzip here).
//!  - PTX (terrestrial scanners): every scan, each through its registration matrix (row vectors, the
//!    translation in the last row; refused unless its 3x3 part is orthonormal); "0 0 0" points (no
//!    return) are left out; x y z intensity r g b colours are kept when every point has them.
//!  - PCD (the Point Cloud Library's format), DATA ascii, binary or binary_compressed (LZF, stored field
//!    by field), any field layout with x, y, z (F of 4 or 8 bytes; I or U of 1-4 bytes for x, y and z,
//!    of 1-8 for other fields; padding fields "_"; an ASCII line holds exactly the values FIELDS x
//!    COUNT declare, a point at most 64 KB); PCL's
//!    packed 32-bit colour ("rgb" or "rgba", as float bits or, in ASCII, an unsigned integer). Points of
//!    an organized cloud without a measurement (a NaN coordinate) are left out; VIEWPOINT is metadata
//!    (PCL does not apply it either). A binary_compressed block is one LZF stream, so it is held whole.
//!    Data after the declared points (a non-blank ASCII line, or binary bytes of a point record or more)
//!    is refused.
//!  - XYZ/PTS/TXT/CSV: three columns of each line (separated by spaces, tabs, commas or semicolons).
//!    Blank lines, lines starting with '#' or "//" and a UTF-8 byte order mark are skipped, so is a
//!    first line holding a single integer (the point count of PTS files; in a .pts file every such line, as
//!    multi-scan PTS files repeat it before each scan). A first line of column names
//!    ("x,y,z,intensity", CloudCompare's "//X,Y,Z,R,G,B") picks the columns named x, y, z (any case, any
//!    order; a header naming none of them leaves the first three, one naming only some is refused) and
//!    r, g, b or red, green, blue as colours (numbers, clamped to 0-255); without names a .pts line of 6
//!    or 7 values is x y z [intensity] r g b (Leica's convention), and these guessed colours are dropped
//!    unless all are within 0-255 (they were something else, normals say). When the first line holds
//!    a semicolon, semicolons separate and commas are decimal points ("1,5;2,5;3,5", as a European
//!    spreadsheet writes CSV).
//!  - OBJ: `v x y z [w]` lines; `v x y z r g b` colours (0..1) are kept when every v line has them.
//!  - OFF (also COFF, NOFF, STOFF...): the vertices; faces, normals and colours are ignored. A vertex
//!    line holds x y z and exactly the values its keyword announces (3 normals for N, 2 texture
//!    coordinates for ST, up to 4 colour values for C): a face line read as a vertex is refused. The
//!    lines after the vertices must be the declared faces ("n i1 .. in [colour]", indices below the
//!    vertex count, continued on the next lines if need be): a vertex line read as a face, a face too
//!    many or data when no face is declared is refused; fewer faces than declared read.
//!  - CONF (a Stanford scan list, as scanalyze writes it for the raw range scans of the Stanford 3D
//!    Scanning Repository): every `bmesh FILE tx ty tz qx qy qz qw` (or `mesh ...`) line is a point file,
//!    relative to the list's folder, read as above and moved into the common frame (see ScanPlacement);
//!    `camera` lines are ignored.
//!
//! Float32 coordinates (PLY float, PCD F 4) far from the origin for the object's size (adjacent float32
//! values more than 1e-4 of the extent apart) are recorded in PointCloud::coarse_coordinates, not refused.

#include "libmrtile/point_cloud.h"

#include <array>
#include <filesystem>
#include <vector>

namespace mrt {

struct ReadOptions
{
    //! Keep per-vertex colours (PLY red/green/blue[/alpha], OBJ v x y z r g b) when the file has them.
    bool keep_colors = true;
    //! Refuse files that declare (or turn out to hold) more points than this; guards against absurd
    //! headers. 0 = no limit beyond what memory allows (the reader still never trusts a header
    //! count for allocation beyond what the file size can hold).
    std::size_t max_points = 0;
    //! Scan lists (.conf): leave out the scans whose files do not exist instead of failing (the
    //! Stanford lists name every scan of an object while downloads often hold a few). Off by default:
    //! a misspelt name should not silently lose a scan. read_scan_list() tells which files exist.
    bool skip_missing_scans = false;
    //! A named pipe (FIFO) as input is read once something writes to it; if nothing does within this
    //! many seconds (no writer), reading fails instead of waiting forever.
    double pipe_wait_seconds = 30.0;
    //! Memory the points may take once built into a hierarchy, in bytes (0 = this machine's physical
    //! memory): a cloud of more than memory / 128 points is refused while it is read (or by its
    //! declared count), rather than the build running out of memory.
    std::uint64_t memory_bytes = 0;
};

//! \brief One scan of a scan list: its file and the rigid motion that puts it into the common frame.
//! \details A point p of the file goes to R p + translation, where R rotates by the conjugate of
//! the listed quaternion, which is how scanalyze stores it: on the repository's bun045.ply this puts 91% of its
//! points within a millimetre of bun000.ply (median gap 0.33 mm, the scanner's noise), the other sense 0.3%.
struct ScanPlacement
{
    std::filesystem::path path;                  //!< resolved against the list's folder
    Vec3 translation{0, 0, 0};
    std::array<double, 4> rotation{0, 0, 0, 1};  //!< unit quaternion x, y, z, w as listed (normalised)
    std::size_t line = 0;                        //!< line of the list, for messages
    bool missing = false;                        //!< the file did not exist when the list was read
};

//! Whether `path` names a scan list (.conf, optionally .gz), which read_points reads as its scans.
bool is_scan_list(const std::filesystem::path& path);

//! \brief Reads a Stanford scan list (.conf) without reading the scans.
//! \throw IoError if the list cannot be read, InvalidInput for a malformed line (named with its number),
//! a quaternion that is not of unit length, a list naming another list, or a list naming no scan.
std::vector<ScanPlacement> read_scan_list(const std::filesystem::path& path);

//! Moves a cloud read from placement.path into the scan list's common frame (absolute coordinates;
//! positions stay relative to a whole-number origin).
void place_scan(PointCloud& cloud, const ScanPlacement& placement);

//! \brief Reads the points of a file, picking the format by extension (case-insensitive, after
//! stripping ".gz").
//! \details Returns absolute coordinates recentred (see recenter()) and validated (finite, at least one
//! point). Degenerate clouds (one point, duplicates, collinear points) are returned as they are.
//! \throw IoError for missing/unreadable/truncated files, InvalidInput for malformed content, an unknown
//! extension or too many points; messages start with the file name and give the line number for text
//! formats.
PointCloud read_points(const std::filesystem::path& path, const ReadOptions& options = {});

//! \brief Reads several point files into one cloud (the scans of one scene, the tiles of a lidar survey),
//! in absolute coordinates: files in one coordinate system line up. Colours as append() merges them.
//! \throw as read_points, naming the file at fault; InvalidInput if `paths` is empty or the files hold
//! more than max_points together.
PointCloud read_points(const std::vector<std::filesystem::path>& paths, const ReadOptions& options = {});

} // namespace mrt
