#pragma once
//! \file atomic_file.h
//! \brief Writes that never leave a partial or corrupted output behind.
//! \details Every writer streams into "<path>.tmp.<pid>" next to the target and renames it over the
//! target on commit(); if anything throws before that, the destructor removes the temporary file, so
//! a failed run leaves either the old file or nothing.

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>

namespace mrt {

class AtomicFile
{
public:
    //! Opens the temporary file. \throw IoError naming `path` if it cannot be created.
    explicit AtomicFile(const std::filesystem::path& path);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream() { return out_; }
    void write(const void* data, std::size_t size);
    //! Flushes, closes and renames onto the target. \throw IoError if any write or the rename failed.
    void commit();

private:
    std::filesystem::path path_;
    std::filesystem::path temp_;
    std::ofstream out_;
    bool committed_ = false;
};

//! Writes a whole buffer atomically.
void write_file_atomically(const std::filesystem::path& path, const std::string& bytes);

//! Creates the directory (and parents). \throw IoError naming it if that fails or it is a file.
void ensure_directory(const std::filesystem::path& dir);

} // namespace mrt
