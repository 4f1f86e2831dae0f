// Output safety, required of every writer: write to a temporary file, rename on success.
#include "libmrtile/atomic_file.h"

#include "libmrtile/errors.h"

#include <cerrno>
#include <cstring>
#include <system_error>
#include <unistd.h>

namespace mrt {

AtomicFile::AtomicFile(const std::filesystem::path& path) : path_(path)
{
    temp_ = path_;
    temp_ += ".tmp." + std::to_string(static_cast<long>(::getpid()));
    out_.open(temp_, std::ios::binary | std::ios::trunc);
    if (!out_)
        throw IoError(path_.string() + ": cannot create file (" + std::strerror(errno) + ")");
}

AtomicFile::~AtomicFile()
{
    if (!committed_) {
        out_.close();
        std::error_code ec;
        std::filesystem::remove(temp_, ec);
    }
}

void AtomicFile::write(const void* data, std::size_t size)
{
    out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
}

void AtomicFile::commit()
{
    out_.flush();
    const bool ok = static_cast<bool>(out_);
    out_.close();
    if (!ok || out_.fail())
        throw IoError(path_.string() + ": write failed (disk full or not writable?)");
    std::error_code ec;
    std::filesystem::rename(temp_, path_, ec);
    if (ec)
        throw IoError(path_.string() + ": cannot rename temporary file into place (" + ec.message() + ")");
    committed_ = true;
}

void write_file_atomically(const std::filesystem::path& path, const std::string& bytes)
{
    AtomicFile file(path);
    file.write(bytes.data(), bytes.size());
    file.commit();
}

void ensure_directory(const std::filesystem::path& dir)
{
    std::error_code ec;
    if (std::filesystem::is_directory(dir, ec))
        return;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir))
        throw IoError(dir.string() + ": cannot create directory (" +
                      (ec ? ec.message() : std::string("exists and is not a directory")) + ")");
}

} // namespace mrt
