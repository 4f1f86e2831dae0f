// Output safety, required of every writer: write to a temporary file, rename on success. A failure
// removes the temporary; so does a signal that stops the program (install_signal_cleanup), so that an
// interrupted run leaves no "<out>.tmp.<pid>" behind either.
#include "libmrtile/atomic_file.h"

#include "libmrtile/errors.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <dirent.h>
#include <functional>
#include <mutex>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

namespace mrt {

namespace {

// The file a path names, its symbolic links followed (as far as they lead: a dangling link gives the
// file it would create). Renaming onto the link itself would replace the link by a plain file.
std::filesystem::path follow_links(const std::filesystem::path& path)
{
    std::filesystem::path at = path;
    for (int hop = 0; hop < 40; ++hop) { // the kernel's own bound on a chain of links
        struct stat link;
        if (::lstat(at.c_str(), &link) != 0 || !S_ISLNK(link.st_mode))
            return at;
        std::error_code ec;
        const std::filesystem::path to = std::filesystem::read_symlink(at, ec);
        if (ec)
            return at;
        at = to.is_absolute() ? to : at.parent_path() / to;
    }
    throw IoError(path.string() + ": too many levels of symbolic links (a loop?)");
}

// The directory an output directory names: written as given, "tiles/" or "./tiles/." named no
// directory entry (their file name is empty or "."), and the temporary beside it became "tiles/.tmp.PID",
// inside it (QA round 38: "cannot create the directory", or a whole export lost to "cannot replace");
// and a symbolic link is written through, as for files: the directory it leads to is replaced and the
// link stays (QA round 38: `-o public/tiles` linked to the served tree replaced the link).
std::filesystem::path directory_target(const std::filesystem::path& dir)
{
    // "FILE/" names a directory: where FILE is anything else (a regular file, a link to one), it is
    // refused here, before it could be taken for the directory to replace (QA round 39: `-o in.ply/`
    // replaced the input with a tileset).
    struct stat status;
    const std::string text = dir.string();
    if (!text.empty() && (text.back() == '/' || dir.filename() == ".") && ::stat(text.c_str(), &status) != 0 && errno == ENOTDIR)
        throw IoError(text + ": is not a directory (a file is named there)");
    std::filesystem::path at = dir.lexically_normal();
    if (!at.has_filename() && at.has_relative_path())
        at = at.parent_path();
    if (at.filename() == "." || at.filename() == "..") {
        std::error_code ec;
        const std::filesystem::path absolute = std::filesystem::absolute(at, ec);
        if (!ec)
            at = absolute.lexically_normal();
        if (!at.has_filename() && at.has_relative_path())
            at = at.parent_path();
    }
    return follow_links(at);
}

std::filesystem::path temporary_name(const std::filesystem::path& path)
{
    const std::string suffix = ".tmp." + std::to_string(static_cast<long>(::getpid()));
    const std::string name = path.filename().string();
    // A name within the file system's 255 bytes can be too long with the suffix: a legal output of 250
    // bytes failed with "File name too long" (QA round 29). Its temporary keeps what fits of the name,
    // and a hash of the whole, so that two such outputs in one directory do not share a temporary.
    constexpr std::size_t kNameMax = 255;
    if (name.size() + suffix.size() <= kNameMax) {
        std::filesystem::path temp = path;
        temp += suffix;
        return temp;
    }
    char hash[24];
    std::snprintf(hash, sizeof hash, ".%016llx", static_cast<unsigned long long>(std::hash<std::string>{}(name)));
    const std::string shortened = name.substr(0, kNameMax - suffix.size() - std::strlen(hash)) + hash + suffix;
    return path.parent_path() / shortened;
}

// The temporaries a signal handler removes: fixed slots, so that the handler needs no allocation or
// lock. A slot is free (0), being written (1) or holds a path (2).
constexpr std::size_t kSlots = 128; // temporaries alive at once: one per thread and a few
constexpr std::size_t kPathBytes = 4096;
struct Slot
{
    std::atomic<int> state{0};
    char path[kPathBytes];
};
std::array<Slot, kSlots> g_slots;

// Removes `name` under directory `dir` (a file, or a directory and what it holds, `depth` levels deep
// at most) with async-signal-safe calls only.
void remove_at(int dir, const char* name, int depth)
{
    if (::unlinkat(dir, name, 0) == 0 || depth <= 0)
        return;
    const int fd = ::openat(dir, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0)
        return;
    alignas(8) char buffer[4096];
    for (;;) {
        const long n = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer);
        if (n <= 0)
            break;
        for (long at = 0; at < n;) {
            struct Entry
            {
                std::uint64_t inode;
                std::int64_t offset;
                unsigned short length;
                unsigned char type;
                char name[1];
            };
            const auto* e = reinterpret_cast<const Entry*>(buffer + at);
            at += e->length;
            if (std::strcmp(e->name, ".") == 0 || std::strcmp(e->name, "..") == 0)
                continue;
            remove_at(fd, e->name, depth - 1);
        }
    }
    ::close(fd);
    ::unlinkat(dir, name, AT_REMOVEDIR);
}

// The files written while a CommitTogether is alive, renamed by its commit().
struct Deferred
{
    std::filesystem::path path;   // as given (named in messages)
    std::filesystem::path target; // the file replaced
    std::filesystem::path temp;
};
std::mutex g_deferred_mutex;
bool g_deferring = false;
std::vector<Deferred> g_deferred;

// Renames a finished temporary onto its target. A file replaced keeps its permissions (a private
// model stays private); a new one gets the process's defaults, as the temporary file has them.
void rename_into_place(const Deferred& d)
{
    struct stat existing;
    if (::stat(d.target.c_str(), &existing) == 0 && S_ISREG(existing.st_mode))
        ::chmod(d.temp.c_str(), existing.st_mode & 07777);
    std::error_code ec;
    std::filesystem::rename(d.temp, d.target, ec);
    if (ec)
        throw IoError(d.path.string() + ": cannot rename temporary file into place (" + ec.message() + ")");
    forget_temporary(d.temp);
}

extern "C" void remove_temporaries_and_die(int signal)
{
    for (Slot& slot : g_slots)
        if (slot.state.load(std::memory_order_acquire) == 2)
            remove_at(AT_FDCWD, slot.path, 3);
    ::signal(signal, SIG_DFL);
    ::raise(signal);
}

// What `path` (links followed) is when it exists and is no regular file or directory: a character
// device such as /dev/null, a pipe or a socket, which an output is written into as it is (its st_mode);
// 0 otherwise. Renamed over, it was replaced by a regular file: `--stats-json /dev/null` run as root
// turned the system's /dev/null into a file. A block device (a disk) is refused.
mode_t special_target(const std::filesystem::path& path)
{
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode) || S_ISDIR(st.st_mode))
        return 0;
    if (S_ISBLK(st.st_mode))
        throw IoError(path.string() + ": is a block device (a disk); not writing to it");
    return st.st_mode;
}

// How long a pipe may go without a reader before it is refused: a reader started just before the
// writer (`cat pipe > file & mrtile ... -o pipe`, a process substitution) may not have opened its end
// yet. Refused at once, that race was lost on a loaded machine, and the reader then waited for ever
// for a writer (the CLI test of a pipe hung until ctest's timeout).
constexpr int kPipeReaderWaitMilliseconds = 2000;

// Opens the writing end of a special target without blocking: a pipe that no process reads (for
// kPipeReaderWaitMilliseconds) would block the write forever, and is refused instead. Returns the
// descriptor.
int open_without_blocking(const std::filesystem::path& path)
{
    for (int waited = 0;; waited += 10) {
        const int fd = ::open(path.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
        if (fd >= 0)
            return fd;
        const int error = errno;
        if (error == ENXIO && waited < kPipeReaderWaitMilliseconds) {
            ::usleep(10000);
            continue;
        }
        throw IoError(path.string() + (error == ENXIO ? ": is a pipe that no process reads"
                                                      : ": cannot open for writing (" + std::string(std::strerror(error)) + ")"));
    }
}

// An empty path names no file: the temporary was made as ".tmp.<pid>" in the working directory and
// the rename failed with ": cannot rename temporary file into place", naming nothing.
const std::filesystem::path& named(const std::filesystem::path& path, const char* what)
{
    if (path.empty())
        throw IoError(std::string("an empty path was given for the ") + what + " to write; name it");
    return path;
}

} // namespace

void remember_temporary(const std::filesystem::path& path)
{
    const std::string text = path.string();
    if (text.size() >= kPathBytes)
        return;
    for (Slot& slot : g_slots) {
        int free = 0;
        if (slot.state.compare_exchange_strong(free, 1, std::memory_order_acquire)) {
            std::memcpy(slot.path, text.c_str(), text.size() + 1);
            slot.state.store(2, std::memory_order_release);
            return;
        }
    }
}

void forget_temporary(const std::filesystem::path& path)
{
    const std::string text = path.string();
    for (Slot& slot : g_slots) {
        int held = 2;
        if (slot.state.load(std::memory_order_acquire) == 2 && std::strcmp(slot.path, text.c_str()) == 0 &&
            slot.state.compare_exchange_strong(held, 1, std::memory_order_acq_rel)) {
            slot.state.store(0, std::memory_order_release);
            return;
        }
    }
}

void install_signal_cleanup()
{
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP})
        ::sigaction(signal, &action, nullptr);
    // Past a file size limit (ulimit -f) a write raises SIGXFSZ, whose default kills the process and
    // left OUT.tmp.PID (QA round 34). Ignored, the write fails with EFBIG instead, and the error path
    // reports it and removes the temporary.
    ::signal(SIGXFSZ, SIG_IGN);
}

void check_writable_file(const std::filesystem::path& path)
{
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw IoError(path.string() + ": is a directory");
    // A device or a pipe is written as it is, not replaced (AtomicFile). A pipe must have a reader
    // now, not only when the output is written after all the work (QA round 36); the end opened to
    // ask stays open until the program ends, since closing it would end the reader's input before
    // the output comes.
    if (const mode_t mode = special_target(path)) {
        if (S_ISFIFO(mode))
            (void)open_without_blocking(path); // held open (see above)
        return;
    }
    AtomicFile probe(path); // removed again, uncommitted (it refuses a read-only target)
}

void check_writable_directory(const std::filesystem::path& dir)
{
    const TemporaryDirectory probe(dir); // removed again
}

TemporaryDirectory::TemporaryDirectory(const std::filesystem::path& dir)
    : path_(temporary_name(directory_target(named(dir, "directory")))), dir_(dir)
{
    std::error_code ec;
    std::filesystem::remove_all(path_, ec); // a stale leftover of a killed run with the same pid
    if (!std::filesystem::create_directory(path_, ec) || ec)
        throw IoError(dir.string() + ": cannot create the directory (" +
                      (ec ? ec.message() : std::string("already exists")) + ")");
    remember_temporary(path_);
}

TemporaryDirectory::~TemporaryDirectory()
{
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
    forget_temporary(path_);
}

void TemporaryDirectory::write(const std::function<void()>& write) const
{
    try {
        write();
    } catch (const IoError& e) {
        std::string message = e.what();
        const std::string temporary = path_.string(), final = dir_.string();
        for (std::size_t at = message.find(temporary); at != std::string::npos;
             at = message.find(temporary, at + final.size()))
            message.replace(at, temporary.size(), final);
        throw IoError(message);
    }
}

AtomicFile::AtomicFile(const std::filesystem::path& path)
    : path_(named(path, "file")), target_(follow_links(path)), temp_(temporary_name(target_))
{
    if (special_target(path_) != 0) {
        // Written as it is (see special_target), once it is known not to block.
        ::close(open_without_blocking(path_));
        direct_ = true;
        out_.open(path_, std::ios::binary);
        if (!out_)
            throw IoError(path_.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
        return;
    }
    // Renaming over a file needs only the directory's permission: a file made read-only (no write
    // bit for anyone, or none for this user) would be replaced all the same.
    struct stat existing;
    if (::stat(path.c_str(), &existing) == 0 && S_ISREG(existing.st_mode) &&
        ((existing.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0 || ::access(path.c_str(), W_OK) != 0))
        throw IoError(path.string() + ": is read-only; not replacing it");
    remember_temporary(temp_);
    out_.open(temp_, std::ios::binary | std::ios::trunc);
    if (!out_) {
        const int error = errno;
        forget_temporary(temp_);
        // Through a link, the file made is its target's: name that too (QA round 34: a dangling link's
        // error named the link only, whose own directory exists).
        const std::string through = target_ != path_ ? " in " + target_.parent_path().string() + ", where the link leads" : "";
        throw IoError(path_.string() + ": cannot create file" + through + " (" + std::strerror(error) + ")");
    }
}

AtomicFile::~AtomicFile()
{
    if (direct_)
        return;
    if (!committed_) {
        out_.close();
        std::error_code ec;
        std::filesystem::remove(temp_, ec);
        forget_temporary(temp_);
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
    if (direct_) {
        committed_ = true;
        return;
    }
    {
        const std::lock_guard<std::mutex> lock(g_deferred_mutex);
        if (g_deferring) {
            // Written twice: the same temporary holds the later contents, renamed once.
            const bool known = std::any_of(g_deferred.begin(), g_deferred.end(), [&](const Deferred& d) { return d.temp == temp_; });
            if (!known)
                g_deferred.push_back({path_, target_, temp_});
            committed_ = true;
            return;
        }
    }
    rename_into_place({path_, target_, temp_});
    committed_ = true;
}

CommitTogether::CommitTogether()
{
    const std::lock_guard<std::mutex> lock(g_deferred_mutex);
    assert(!g_deferring && "one CommitTogether at a time");
    g_deferring = true;
    g_deferred.clear();
}

CommitTogether::~CommitTogether()
{
    const std::lock_guard<std::mutex> lock(g_deferred_mutex);
    for (const Deferred& d : g_deferred) {
        std::error_code ec;
        std::filesystem::remove(d.temp, ec);
        forget_temporary(d.temp);
    }
    g_deferred.clear();
    g_deferring = false;
}

void CommitTogether::commit()
{
    const std::lock_guard<std::mutex> lock(g_deferred_mutex);
    g_deferring = false;
    while (!g_deferred.empty()) {
        rename_into_place(g_deferred.front()); // on a throw, the destructor removes the rest
        g_deferred.erase(g_deferred.begin());
    }
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

void replace_directory(const std::filesystem::path& built, const std::filesystem::path& given, const std::string& what)
{
    namespace fs = std::filesystem;
    const fs::path dir = directory_target(given);
    std::error_code ec;
    struct stat status;
    if (::lstat(dir.c_str(), &status) == 0 && !S_ISDIR(status.st_mode))
        throw IoError(given.string() + ": exists and is not a directory; not replacing it");
    if (!fs::exists(dir, ec)) {
        fs::rename(built, dir, ec);
        if (ec)
            throw IoError(given.string() + ": cannot move the " + what + " into place (" + ec.message() + ")");
        return;
    }
    // Atomic exchange where the file system supports it; otherwise two renames with a roll-back.
    if (::renameat2(AT_FDCWD, built.c_str(), AT_FDCWD, dir.c_str(), RENAME_EXCHANGE) == 0) {
        fs::remove_all(built, ec); // now holds the previous one
        return;
    }
    fs::path old = dir;
    old += ".old." + std::to_string(static_cast<long>(::getpid()));
    fs::rename(dir, old, ec);
    if (ec)
        throw IoError(given.string() + ": cannot replace the existing " + what + " (" + ec.message() + ")");
    fs::rename(built, dir, ec);
    if (ec) {
        std::error_code ignored;
        fs::rename(old, dir, ignored);
        throw IoError(given.string() + ": cannot move the " + what + " into place (" + ec.message() + ")");
    }
    fs::remove_all(old, ec);
}

void check_replaceable_directory(const std::filesystem::path& dir, const std::string& what,
                                 const std::function<std::string(const std::filesystem::path&)>& foreign)
{
    std::error_code ec;
    const std::filesystem::path target = directory_target(dir); // what replace_directory replaces
    struct stat status;
    if (::lstat(target.c_str(), &status) != 0)
        return;
    if (!S_ISDIR(status.st_mode))
        throw IoError(dir.string() + ": exists and is not a directory");
    const std::string entry = foreign(dir);
    if (!entry.empty())
        throw IoError(dir.string() + ": holds " + entry + ", which is not part of a " + what + " we write; refusing "
                      "to replace the directory (move it away or write elsewhere)");
    // The previous output is removed once the new one is in place: where its files cannot be removed
    // (another user's directory), it was left behind as "<dir>.tmp.PID" after a run that said nothing
    // (QA round 38). Refused first instead, as a read-only file is: a directory without a write bit
    // for anyone, or one this user may not change.
    const auto removable = [&](const std::filesystem::path& d) {
        struct stat mode;
        const bool read_only = ::stat(d.c_str(), &mode) == 0 && (mode.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0;
        if (read_only || ::access(d.c_str(), W_OK | X_OK) != 0)
            throw IoError(dir.string() + ": cannot remove the previous " + what + "'s files in " + d.string() + " (" +
                          (read_only ? std::string("read-only") : std::string(std::strerror(errno))) +
                          "); not replacing it");
    };
    removable(dir);
    for (auto it = std::filesystem::recursive_directory_iterator(dir, ec); !ec && it != std::filesystem::recursive_directory_iterator();
         it.increment(ec))
        if (it->is_directory(ec) && !it->is_symlink(ec))
            removable(it->path());
}

} // namespace mrt
