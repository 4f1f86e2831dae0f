#pragma once
//! \file atomic_file.h
//! \brief Writes that never leave a partial or corrupted output behind.
//! \details Every writer streams into "<path>.tmp.<pid>" next to the target and renames it over the
//! target on commit(); if anything throws before that, the destructor removes the temporary file, so
//! a failed run leaves either the old file or nothing. A target that exists keeps its permissions, and
//! a read-only one (no write bit, or none for this user) is refused, not replaced. A target that is a
//! symbolic link is written through: the file it points to is replaced (created when the link dangles)
//! and the link stays, as a user who links an output name to a file expects. A target that is a
//! character device or a pipe (/dev/null, a process substitution) is written as it is: replacing it
//! would turn /dev/null into a file; a block device is refused.

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace mrt {

class AtomicFile
{
public:
    //! Opens the temporary file. \throw IoError naming `path` if it cannot be created or `path` is a
    //! read-only file.
    explicit AtomicFile(const std::filesystem::path& path);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    std::ostream& stream() { return out_; }
    void write(const void* data, std::size_t size);
    //! Flushes, closes and renames onto the target. \throw IoError if any write or the rename failed.
    void commit();

private:
    std::filesystem::path path_;   //!< as given (named in messages)
    std::filesystem::path target_; //!< path_ with its symbolic links followed: the file replaced
    std::filesystem::path temp_;
    std::ofstream out_;
    bool committed_ = false;
    bool direct_ = false; //!< a device or pipe, written as it is (no temporary, no rename)
};

//! \brief The outputs of one step committed together: while one is alive, AtomicFile::commit() checks
//! and closes its temporary file but leaves it aside; commit() renames them all into place, in the
//! order they were written. Destroyed without commit() (an exception), it removes them, and every
//! target keeps what it held. A mesh and its --stats-json: a disk full on the statistics left the new
//! mesh written over the old one (QA round 66). Files only: a directory built aside
//! (TemporaryDirectory) moves when it is done, so none may be written while one is alive. One at a
//! time per program.
class CommitTogether
{
public:
    CommitTogether();
    ~CommitTogether();
    CommitTogether(const CommitTogether&) = delete;
    CommitTogether& operator=(const CommitTogether&) = delete;

    //! \throw IoError naming the output whose rename failed (those not yet renamed are removed).
    void commit();
};

//! Writes a whole buffer atomically.
void write_file_atomically(const std::filesystem::path& path, const std::string& bytes);

//! Creates the directory (and parents). \throw IoError naming it if that fails or it is a file.
void ensure_directory(const std::filesystem::path& dir);

//! \brief Checks before any work that `path` can be written as AtomicFile writes it (its temporary file
//! is created and removed again) and is not a directory. A program that writes several outputs checks
//! each first, so that one unwritable output does not leave the others written. A pipe must have a
//! reader; the end opened to ask stays open until the program ends (closed, it would end the reader's
//! input before the output comes).
//! \throw IoError naming `path` and the cause.
void check_writable_file(const std::filesystem::path& path);

//! \brief The same for an output directory built aside as "<dir>.tmp.<pid>" and moved into place
//! (TemporaryDirectory): its parent must exist, and the temporary directory can be created.
void check_writable_directory(const std::filesystem::path& dir);

//! \brief "<dir>.tmp.<pid>", an output directory built aside (a stale one of a killed run with the same
//! pid is replaced) and removed with everything in it when this object ends, or by a signal
//! (install_signal_cleanup). Whoever moves it into place first leaves nothing to remove.
class TemporaryDirectory
{
public:
    //! \throw IoError naming `dir` if the temporary directory cannot be created.
    explicit TemporaryDirectory(const std::filesystem::path& dir);
    ~TemporaryDirectory();
    TemporaryDirectory(const TemporaryDirectory&) = delete;
    TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;

    const std::filesystem::path& path() const { return path_; }

    //! \brief Runs `write`, which writes inside the directory; an IoError it throws is thrown again
    //! naming the final directory instead of this one, which is gone when the message is read (a full
    //! disk was reported as "OUT.tmp.PID/tiles/0.glb: write failed": QA round 29).
    void write(const std::function<void()>& write) const;

private:
    std::filesystem::path path_;
    std::filesystem::path dir_;
};

//! \brief Puts the finished directory `built` (a TemporaryDirectory's) at `dir`, replacing an existing
//! one only now: atomically where the file system can exchange the two, else by two renames with a
//! roll-back. The previous directory is removed. `what` names the output in messages ("tileset").
//! \throw IoError naming `dir` if it cannot be put in place (the previous one is then kept).
void replace_directory(const std::filesystem::path& built, const std::filesystem::path& dir, const std::string& what);

//! \brief Before any work: whether replace_directory may replace what is at `dir` (it removes the old
//! directory whole, so a user's own files in it must stop the write). Nothing there passes; else `dir`
//! must be a directory whose entries are all an output's own: `foreign(dir)` names the first that is
//! not ("" for none), and whose directories can all be emptied (a write bit set, and this user may
//! change them). `what` names the output in the message ("tileset"). A directory `dir` names with a
//! trailing "/" or "/." is that directory, and one reached through a symbolic link is replaced where
//! the link leads (the link stays), as replace_directory and TemporaryDirectory do.
//! \throw IoError naming `dir` and the foreign entry (or what `foreign` throws).
void check_replaceable_directory(const std::filesystem::path& dir, const std::string& what,
                                 const std::function<std::string(const std::filesystem::path&)>& foreign);

//! \brief Names a temporary file or directory to remove if the program is stopped by a signal
//! (install_signal_cleanup) before it is renamed into place; forget_temporary when it is gone or moved.
//! Cheap, thread-safe, best effort (a fixed number of slots).
void remember_temporary(const std::filesystem::path& path);
void forget_temporary(const std::filesystem::path& path);

//! \brief For programs: on SIGINT, SIGTERM or SIGHUP, removes the remembered temporaries (with
//! async-signal-safe calls only) and then dies of the signal as it would have. A library never
//! installs handlers itself.
void install_signal_cleanup();

} // namespace mrt
