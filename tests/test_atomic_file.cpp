// Output safety: outputs checked before any work, temporaries removed when a signal stops the program,
// and a tileset directory replaced only when it holds nothing but a tileset of ours.
#include "formats/write_3d_tiles.h"
#include "libmrtile/atomic_file.h"
#include "libmrtile/errors.h"
#include "test_dir.h"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace mrt {
namespace {

namespace fs = std::filesystem;

void write_text(const fs::path& path, const std::string& text)
{
    std::ofstream(path) << text;
}

std::size_t entries(const fs::path& dir)
{
    std::size_t n = 0;
    for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it)
        ++n;
    return n;
}

std::string read_text(const fs::path& path)
{
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// Outputs committed together: none is in place before commit(); a throw before it leaves every
// target as it was and no temporary; commit() puts all in place, a file written twice with its later
// contents. Without a CommitTogether each commit renames at once.
TEST(AtomicFile, outputs_committed_together_are_all_or_none)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    write_text(dir / "mesh.ply", "old mesh");
    try {
        CommitTogether outputs;
        write_file_atomically(dir / "mesh.ply", "new mesh");
        write_file_atomically(dir / "stats.json", "{}");
        EXPECT_EQ(read_text(dir / "mesh.ply"), "old mesh");
        EXPECT_FALSE(fs::exists(dir / "stats.json"));
        throw IoError("stats.json: write failed");
    } catch (const IoError&) {
    }
    EXPECT_EQ(read_text(dir / "mesh.ply"), "old mesh");
    EXPECT_EQ(entries(dir), 1u);
    {
        CommitTogether outputs;
        write_file_atomically(dir / "mesh.ply", "new mesh");
        write_file_atomically(dir / "stats.json", "{1}");
        write_file_atomically(dir / "stats.json", "{2}");
        outputs.commit();
    }
    EXPECT_EQ(read_text(dir / "mesh.ply"), "new mesh");
    EXPECT_EQ(read_text(dir / "stats.json"), "{2}");
    EXPECT_EQ(entries(dir), 2u);
    write_file_atomically(dir / "stats.json", "{3}");
    EXPECT_EQ(read_text(dir / "stats.json"), "{3}");
}

// The probe names the path and its cause and leaves nothing behind, whether it passes or fails.
TEST(AtomicFile, outputs_are_checked_without_a_trace)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    check_writable_file(dir / "ok.ply");
    check_writable_directory(dir / "tiles");
    EXPECT_EQ(entries(dir), 0u);
    for (const fs::path& bad : {dir / "missing" / "x.ply", dir}) {
        try {
            check_writable_file(bad);
            ADD_FAILURE() << bad;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(check_writable_directory(dir / "missing" / "tiles"), IoError);
    EXPECT_EQ(entries(dir), 0u);
    // Names the file system takes, though not with ".tmp.<pid>" after them (QA round 29: "File name too
    // long"); two that differ only in their last bytes are written side by side.
    const std::string long_name(250, 'n');
    check_writable_file(dir / (long_name + ".a"));
    check_writable_directory(dir / (long_name + "_d"));
    EXPECT_EQ(entries(dir), 0u);
    {
        AtomicFile a(dir / (long_name + ".a")), b(dir / (long_name + ".b"));
        a.stream() << "a";
        b.stream() << "b";
        a.commit();
        b.commit();
    }
    std::ifstream a(dir / (long_name + ".a")), b(dir / (long_name + ".b"));
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), "a");
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(b), {}), "b");
    EXPECT_EQ(entries(dir), 2u);
}

// A write that fails inside a directory built aside names the file where the user will look for it:
// the temporary directory is gone by then (QA round 29: "OUT.tmp.PID/tiles/0.glb: write failed" on a
// full disk). Other errors pass as they are.
TEST(AtomicFile, a_failed_write_in_a_temporary_directory_names_the_final_one)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    const TemporaryDirectory temporary(dir / "tiles");
    try {
        temporary.write([&] { throw IoError((temporary.path() / "t" / "0.glb").string() + ": write failed"); });
        ADD_FAILURE() << "no exception";
    } catch (const IoError& e) {
        EXPECT_EQ(std::string(e.what()), (dir / "tiles" / "t" / "0.glb").string() + ": write failed");
    }
    EXPECT_THROW(temporary.write([] { throw InvalidInput("bad"); }), InvalidInput);
    temporary.write([&] { write_text(temporary.path() / "ok.txt", "ok"); });
    EXPECT_TRUE(fs::exists(temporary.path() / "ok.txt"));
}

// QA round qa3: save_model(h, "") and every writer given an empty path made their temporary file in
// the working directory and failed with ": cannot rename temporary file into place". Now an IoError
// that says the path is empty, before anything is made.
TEST(AtomicFile, an_empty_path_is_refused_before_anything_is_made)
{
    for (const auto& make : std::vector<std::function<void()>>{[] { AtomicFile file(""); },
                                                              [] { TemporaryDirectory dir(""); }}) {
        try {
            make();
            ADD_FAILURE() << "no exception";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find("empty path"), std::string::npos) << e.what();
        }
    }
}

// A file written over keeps its permissions (a private model stayed private only until the first
// rewrite: QA), a new one gets the defaults, and a read-only file is not replaced.
TEST(AtomicFile, a_replaced_file_keeps_its_permissions_and_read_only_files_stay)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    const fs::path file = dir / "private.mrt";
    write_file_atomically(file, "one");
    fs::permissions(file, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
    check_writable_file(file);
    write_file_atomically(file, "two");
    EXPECT_EQ(fs::status(file).permissions(), fs::perms::owner_read | fs::perms::owner_write);
    std::ifstream in(file);
    std::string text;
    in >> text;
    EXPECT_EQ(text, "two");
    fs::permissions(file, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read, fs::perm_options::replace);
    try {
        check_writable_file(file);
        ADD_FAILURE() << "a read-only file would be replaced";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("is read-only"), std::string::npos) << e.what();
    }
    EXPECT_EQ(entries(dir), 1u);
}

// An output named by a symbolic link is written through it: the file it points to is replaced (or
// created, when the link dangles), and the link stays a link (QA, session 19: it became a plain file).
TEST(AtomicFile, a_symbolic_link_is_written_through)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    fs::create_directory(dir / "data");
    write_text(dir / "data" / "real.ply", "old");
    fs::create_symlink("data/real.ply", dir / "link.ply"); // relative, as `ln -s` makes them
    fs::create_symlink(dir / "link.ply", dir / "link2.ply"); // a chain, absolute
    write_file_atomically(dir / "link2.ply", "new");
    EXPECT_TRUE(fs::is_symlink(dir / "link.ply"));
    EXPECT_TRUE(fs::is_symlink(dir / "link2.ply"));
    std::ifstream in(dir / "data" / "real.ply");
    std::string text;
    in >> text;
    EXPECT_EQ(text, "new");
    fs::create_symlink("data/later.ply", dir / "dangling.ply");
    write_file_atomically(dir / "dangling.ply", "made");
    EXPECT_TRUE(fs::is_symlink(dir / "dangling.ply"));
    EXPECT_TRUE(fs::is_regular_file(dir / "data" / "later.ply"));
    EXPECT_EQ(entries(dir), 6u); // data, real.ply, later.ply and three links: no temporaries left
    // A loop of links is an error naming the path, not a write onto whichever link the walk stopped at.
    fs::create_symlink("loop_b.ply", dir / "loop_a.ply");
    fs::create_symlink("loop_a.ply", dir / "loop_b.ply");
    EXPECT_THROW(write_file_atomically(dir / "loop_a.ply", "x"), IoError);
    EXPECT_TRUE(fs::is_symlink(dir / "loop_a.ply"));
    EXPECT_TRUE(fs::is_symlink(dir / "loop_b.ply"));
    // A link into a directory that does not exist: the error names where the link leads, not only the
    // link, whose own directory is there (QA round 34).
    fs::create_symlink("nowhere/x.ply", dir / "nowhere.ply");
    try {
        write_file_atomically(dir / "nowhere.ply", "x");
        ADD_FAILURE() << "written";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("nowhere.ply: cannot create file in " + (dir / "nowhere").string()), std::string::npos)
            << e.what();
    }
}

// A pipe (or a device: /dev/null) is written as it is, not replaced by a renamed file: run as root,
// `--stats-json /dev/null` turned the system's /dev/null into a regular file. A pipe no process reads
// is refused instead of blocking the write. (Tested on a pipe: a failing test on /dev/null itself
// would break the machine.)
TEST(AtomicFile, a_pipe_is_written_as_it_is)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    const fs::path pipe = dir / "stats.json";
    ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
    EXPECT_THROW(write_file_atomically(pipe, "nobody reads"), IoError);
    EXPECT_THROW(check_writable_file(pipe), IoError); // refused before any work, too (QA round 36)
    // The reading end, opened here without blocking (a reader thread that had not opened it yet when
    // the writes gave up blocked its join for ever on a loaded machine, session 40): the text is in
    // the pipe's buffer once write_file_atomically returns.
    const int reader = ::open(pipe.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    ASSERT_GE(reader, 0);
    EXPECT_NO_THROW(write_file_atomically(pipe, "through the pipe"));
    std::string received;
    char buffer[64];
    for (ssize_t n; (n = ::read(reader, buffer, sizeof buffer)) > 0;)
        received.append(buffer, static_cast<std::size_t>(n));
    ::close(reader);
    EXPECT_EQ(received, "through the pipe");
    struct stat st;
    ASSERT_EQ(::stat(pipe.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode));
    EXPECT_EQ(entries(dir), 1u); // no temporary left
}

// A reader that opens the pipe a moment after the writer starts gets the text (a CLI test's
// `cat pipe &` lost that race on a loaded machine: refused at once, and cat waited for ever).
TEST(AtomicFile, a_pipe_read_a_moment_later_is_written)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    const fs::path pipe = dir / "late.json";
    ASSERT_EQ(::mkfifo(pipe.c_str(), 0600), 0);
    std::string received;
    std::thread reader([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        const int fd = ::open(pipe.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC); // never blocks the join
        if (fd < 0)
            return;
        char buffer[64];
        // Until the text is in or 5 s passed: before the writer opens, a read finds no data.
        for (int polls = 0; received.size() < 16 && polls < 500; ++polls) {
            const ssize_t n = ::read(fd, buffer, sizeof buffer);
            if (n > 0)
                received.append(buffer, static_cast<std::size_t>(n));
            else
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        ::close(fd);
    });
    EXPECT_NO_THROW(write_file_atomically(pipe, "through the pipe"));
    reader.join();
    EXPECT_EQ(received, "through the pipe");
}

// A process stopped by SIGTERM while it holds a temporary file and a half-written temporary
// directory (with a subdirectory, as a tileset has) leaves neither, and still dies of the signal.
TEST(AtomicFile, a_signal_removes_the_temporaries)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        install_signal_cleanup();
        AtomicFile file(dir / "mesh.ply");
        file.write("ply\n", 4);
        const fs::path built = dir / "tiles.tmp.1";
        fs::create_directories(built / "tiles");
        write_text(built / "tileset.json", "{}");
        write_text(built / "tiles" / "0.glb", "glTF");
        remember_temporary(built);
        ::raise(SIGTERM);
        ::_exit(0); // not reached
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
    EXPECT_EQ(entries(dir), 0u);
}

// Replacing a tileset directory removes it as a whole: it is refused when the directory holds a file
// we would not have written, and accepted when it holds only a tileset of ours.
TEST(AtomicFile, a_tileset_directory_with_other_files_is_not_replaced)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file");
    const fs::path ours = dir / "ours", theirs = dir / "theirs", nested = dir / "nested";
    for (const fs::path& d : {ours, theirs, nested}) {
        fs::create_directories(d / "tiles");
        write_text(d / "tileset.json", "{}");
        write_text(d / "tiles" / "0.glb", "glTF");
        write_text(d / "tiles" / "17.glb", "glTF");
    }
    write_text(theirs / "notes.txt", "keep me");
    write_text(nested / "tiles" / "readme.md", "keep me");
    check_tileset_directory(ours);
    check_tileset_directory(dir / "new");
    for (const auto& [d, entry] : {std::pair{theirs, std::string("notes.txt")}, std::pair{nested, std::string("readme.md")}}) {
        try {
            check_tileset_directory(d);
            ADD_FAILURE() << d;
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find(entry), std::string::npos) << e.what();
        }
    }
    EXPECT_TRUE(fs::exists(theirs / "notes.txt"));
    EXPECT_FALSE(fs::exists(dir / "new"));
}

// An output directory is the directory it names: with a trailing "/" or "/." the temporary was made
// inside it (QA round 38: "tiles/" failed, or failed after the whole export when it existed); through
// a symbolic link the directory where it leads is replaced and the link stays, as for files (QA round
// 38: the link was replaced by a directory, and the tree it served kept the old tileset).
TEST(AtomicFile, an_output_directory_is_what_its_name_names)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file_dirs");
    const auto write_into = [](const fs::path& out, const std::string& text) {
        const TemporaryDirectory temporary(out);
        write_text(temporary.path() / "tileset.json", text);
        replace_directory(temporary.path(), out, "tileset");
    };
    const auto read = [](const fs::path& file) {
        std::ifstream in(file);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    fs::create_directories(dir / "existing");
    write_text(dir / "existing" / "tileset.json", "old");
    fs::create_directories(dir / "real");
    write_text(dir / "real" / "tileset.json", "old");
    fs::create_directory_symlink("real", dir / "link");
    fs::create_directory_symlink("nowhere", dir / "dangling");
    for (const auto& [given, file] : {std::pair{dir / "new" / "", dir / "new" / "tileset.json"},
                                      std::pair{dir / "existing" / "", dir / "existing" / "tileset.json"},
                                      std::pair{dir / "dot" / ".", dir / "dot" / "tileset.json"},
                                      std::pair{dir / "link", dir / "real" / "tileset.json"},
                                      std::pair{dir / "dangling", dir / "nowhere" / "tileset.json"}}) {
        SCOPED_TRACE(given.string());
        check_tileset_directory(given);
        write_into(given, "new");
        EXPECT_EQ(read(file), "new");
        EXPECT_EQ(entries(file.parent_path()), 1u); // no temporary inside
    }
    EXPECT_TRUE(fs::is_symlink(dir / "link"));
    EXPECT_TRUE(fs::is_symlink(dir / "dangling"));
    std::size_t top = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
        ++top;
    }
    EXPECT_EQ(top, 7u); // new existing real link dangling dot nowhere: nothing left beside them

    // "FILE/" names a directory: a regular file there (or a link to one) is refused, not replaced by
    // the tileset (QA round 39: `-o in.ply/` replaced the input).
    write_text(dir / "file", "keep me");
    fs::create_symlink("file", dir / "to_file");
    for (const fs::path& given : {dir / "file" / "", dir / "file" / ".", dir / "to_file" / ""}) {
        SCOPED_TRACE(given.string());
        EXPECT_THROW(check_tileset_directory(given), IoError);
        EXPECT_THROW(write_into(given, "new"), IoError);
        EXPECT_EQ(read(dir / "file"), "keep me");
    }
    EXPECT_THROW(replace_directory(dir / "real", dir / "file", "tileset"), IoError); // never over a file
    EXPECT_EQ(read(dir / "file"), "keep me");
    EXPECT_TRUE(fs::is_symlink(dir / "to_file"));
}

// A previous tileset whose files cannot be removed is refused before any work, as a read-only file is:
// it was left behind as "<dir>.tmp.PID" by a run that said nothing (QA round 38).
TEST(AtomicFile, a_tileset_that_cannot_be_removed_is_not_replaced)
{
    const fs::path dir = testing::fresh_test_dir("atomic_file_locked") / "ts";
    fs::create_directories(dir / "tiles");
    write_text(dir / "tileset.json", "{}");
    write_text(dir / "tiles" / "0.glb", "glTF");
    fs::permissions(dir / "tiles", fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                       fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
    try {
        check_tileset_directory(dir);
        ADD_FAILURE() << "a tileset with a read-only directory passed";
    } catch (const IoError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("tiles"), std::string::npos) << message;
        EXPECT_NE(message.find("read-only"), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
    fs::permissions(dir / "tiles", fs::perms::owner_write, fs::perm_options::add);
    check_tileset_directory(dir);
}

} // namespace
} // namespace mrt
