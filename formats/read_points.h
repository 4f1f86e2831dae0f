#pragma once
//! \file read_points.h
//! \brief Point readers: PLY (ascii, binary little/big endian), XYZ/PTS/TXT/CSV, OBJ (v lines), OFF,
//! each optionally gzip-compressed (.gz). Streaming: files are never slurped whole into strings.

#include "libmrtile/point_cloud.h"

#include <filesystem>

namespace mrt {

struct ReadOptions
{
    //! Keep per-vertex colours (PLY red/green/blue[/alpha]) when the file has them.
    bool keep_colors = true;
    //! Refuse files that declare (or turn out to hold) more points than this; guards against absurd
    //! headers. 0 = no limit beyond what memory allows (the reader still never trusts a header
    //! count for allocation beyond what the file size can hold).
    std::size_t max_points = 0;
};

//! \brief Reads the points of a file, picking the format by extension (case-insensitive, after
//! stripping ".gz").
//! \details Returns absolute coordinates recentred (see recenter()) and validated (finite, at least one
//! point). \throw IoError for missing/unreadable/truncated files, InvalidInput for malformed content;
//! messages start with the file name and give the line number for text formats.
PointCloud read_points(const std::filesystem::path& path, const ReadOptions& options = {});

} // namespace mrt
