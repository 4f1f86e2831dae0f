// Point input (formats/): the method starts from an unorganized point set (paper §3), which arrives as
// a scan file. Parsers stream through a buffered reader (zlib's inflate for gzip files, which it tells
// by their magic bytes) so that a large scan never sits in memory twice, and they distrust every count a
// header declares: a corrupt or hostile file ends in a one-line error, never a crash, hang or an
// allocation sized by a number the file made up.
#include "formats/read_points.h"

#include "libmrtile/errors.h"
#include "libmrtile/georef.h"

#include <zlib.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <future>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <vector>

namespace mrt {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kBufferSize = std::size_t{1} << 18;
// A text line longer than this is binary data, not a point record.
constexpr std::size_t kMaxLineLength = std::size_t{1} << 20;
// Points reserved ahead of a count that the file size has not confirmed.
constexpr std::size_t kReserveCap = std::size_t{1} << 20;

using Rgba = std::array<std::uint8_t, 4>;

// Quotes a token for an error message: short, printable, one line.
std::string quote_token(std::string_view token)
{
    std::string s = "'";
    for (std::size_t i = 0; i < token.size() && i < 32; ++i) {
        const unsigned char c = static_cast<unsigned char>(token[i]);
        s += std::isprint(c) ? static_cast<char>(c) : '?';
    }
    if (token.size() > 32)
        s += "...";
    return s + "'";
}

// A path's extension in lower case (".PLY" -> ".ply").
std::string lower_extension(const fs::path& path)
{
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext;
}

// Buffered input with transparent gzip decompression, line splitting and byte access.
class Input
{
public:
    //! `pipe_wait_seconds`: how long a named pipe may go without a writer (ReadOptions).
    Input(const fs::path& path, std::string name, double pipe_wait_seconds = ReadOptions{}.pipe_wait_seconds)
        : name_(std::move(name)), buffer_(kBufferSize)
    {
        std::error_code ec;
        const fs::file_status status = fs::status(path, ec);
        if (!fs::exists(status))
            throw IoError(name_ + (ec && ec != std::errc::no_such_file_or_directory
                                       ? ": cannot access (" + ec.message() + ")"
                                       : std::string(": no such file")));
        if (fs::is_directory(status))
            throw IoError(name_ + ": is a directory, not a point file");
        errno = 0;
        if (fs::is_fifo(status))
            file_.reset(open_pipe(path, pipe_wait_seconds));
        else
            file_.reset(std::fopen(path.c_str(), "rb"));
        if (!file_)
            throw IoError(name_ + ": cannot open (" + (errno ? std::strerror(errno) : "unknown error") + ")");
        // gzip's magic bytes make a compressed file, whatever its name (as gzopen read them).
        compressed_ = request_raw(2) && static_cast<unsigned char>(raw_[raw_begin_]) == 0x1f &&
                      static_cast<unsigned char>(raw_[raw_begin_ + 1]) == 0x8b;
        if (compressed_) {
            stream_ = std::make_unique<Inflater>();
            if (inflateInit2(&stream_->z, 16 + MAX_WBITS) != Z_OK)
                throw IoError(name_ + ": cannot start decompressing (out of memory)");
            stream_->ready = true;
        } else if (lower_extension(path) == ".gz") {
            // A zlib stream or a plain file under a .gz name was read as text, and its first bytes were
            // quoted as a number (QA round 34).
            throw IoError(name_ + ": named .gz but not gzip-compressed (no gzip header)");
        } else if (fs::is_regular_file(status)) {
            // The size bounds what an uncompressed file can hold (checked against header counts).
            const auto size = fs::file_size(path, ec);
            if (!ec)
                file_size_ = size;
        }
    }
    Input(const Input&) = delete;
    Input& operator=(const Input&) = delete;

    const std::string& name() const { return name_; }
    //! Size of an uncompressed regular file, 0 if unknown (compressed or not a regular file).
    std::uint64_t file_size() const { return file_size_; }
    //! Bytes consumed so far (of the uncompressed stream).
    std::uint64_t offset() const { return discarded_ + begin_; }
    //! Number of the last line returned by next_line (1-based).
    std::uint64_t line_number() const { return line_number_; }

    //! Makes at least n bytes available at data(); false if the input ends first.
    bool request(std::size_t n)
    {
        while (end_ - begin_ < n) {
            if (eof_)
                return false;
            if (begin_ > 0) {
                std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
                end_ -= begin_;
                discarded_ += begin_;
                begin_ = 0;
            }
            if (n > buffer_.size())
                buffer_.resize(std::max(n, 2 * buffer_.size()));
            fill();
        }
        return true;
    }
    const char* data() const { return buffer_.data() + begin_; }
    std::size_t available() const { return end_ - begin_; }
    void consume(std::size_t n) { begin_ += n; }

    //! Returns n contiguous bytes and consumes them, or nullptr if the input ends first.
    const char* take(std::size_t n)
    {
        if (!request(n))
            return nullptr;
        const char* p = data();
        begin_ += n;
        return p;
    }

    //! Consumes n bytes; false if the input ends first.
    bool skip(std::uint64_t n)
    {
        while (n > 0) {
            if (available() == 0 && !request(1))
                return false;
            const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(n, available()));
            begin_ += step;
            n -= step;
        }
        return true;
    }

    //! The next line without its "\n" or "\r\n"; false at the end of the input. The view stays valid
    //! until the next call.
    bool next_line(std::string_view& line)
    {
        std::size_t scanned = 0;
        for (;;) {
            const std::size_t avail = available();
            const void* newline = std::memchr(data() + scanned, '\n', avail - scanned);
            if (newline) {
                const std::size_t length = static_cast<const char*>(newline) - data();
                line = std::string_view(data(), length);
                begin_ += length + 1;
                break;
            }
            scanned = avail;
            if (avail >= kMaxLineLength) {
                if (line_number_ == 0 && carriage_returns_alone(std::string_view(data(), avail)))
                    throw_carriage_returns_alone();
                throw InvalidInput(name_ + ": line " + std::to_string(line_number_ + 1) +
                                   " is longer than 1 MiB (binary data in a text file?)");
            }
            if (!request(avail + 1)) {
                if (available() == 0)
                    return false;
                line = std::string_view(data(), available());
                // A first line that is the whole file, with more after a carriage return: its lines end
                // in one alone ("'3.9975\r1.2' is not a number" said nothing of why). A file with line
                // feeds and a stray carriage return in its first line is read as before.
                if (line_number_ == 0 && carriage_returns_alone(line))
                    throw_carriage_returns_alone();
                begin_ = end_;
                break;
            }
        }
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        // Windows tools open text files with a UTF-8 byte order mark.
        if (line_number_ == 0 && line.substr(0, 3) == "\xEF\xBB\xBF")
            line.remove_prefix(3);
        // UTF-16 text (Windows' "Unicode"): every other byte of its digits is NUL (QA round 50: "'??1?' is
        // not a number", nothing of why).
        if (line_number_ == 0) {
            const bool utf16_mark = line.substr(0, 2) == "\xFF\xFE" || line.substr(0, 2) == "\xFE\xFF";
            if (utf16_mark || line.find('\0') != std::string_view::npos)
                throw InvalidInput(name_ + ": line 1 " + (utf16_mark ? "opens with a UTF-16 byte order mark" : "has NUL bytes") +
                                   ": UTF-16 text or binary data; save text as UTF-8 or ASCII");
        }
        ++line_number_;
        return true;
    }

    //! Whether text has a carriage return with more than blanks after it.
    static bool carriage_returns_alone(std::string_view text)
    {
        const std::size_t cr = text.find('\r');
        return cr != std::string_view::npos && text.find_first_not_of(" \t\r", cr) != std::string_view::npos;
    }

    [[noreturn]] void throw_carriage_returns_alone() const
    {
        throw InvalidInput(name_ + ": its lines end in a carriage return alone (classic Mac OS text); convert them "
                                   "to line feeds (\\n or \\r\\n)");
    }

private:
    // A named pipe blocks its reader's open until a writer opens it, forever if none does (QA round 42:
    // `mkfifo p.xyz` and no writer hung the command). The open waits on a thread of its own for
    // `wait_seconds`; without a writer by then, the pipe is opened for writing here, which ends that
    // open, and reading fails. A writer that opened the pipe may take as long as it likes to write
    // (QA round 44: polling for the first byte refused a slow producer). An error leaves errno set.
    std::FILE* open_pipe(const fs::path& path, double wait_seconds)
    {
        // The opener owns its end of the result, so that it may outlive this call if it cannot be woken.
        auto opened = std::make_shared<std::promise<std::pair<int, int>>>(); // descriptor, errno
        std::future<std::pair<int, int>> result = opened->get_future();
        std::thread([opened, file = path.string()] {
            const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
            opened->set_value({fd, fd < 0 ? errno : 0});
        }).detach();
        if (result.wait_for(std::chrono::duration<double>(std::min(wait_seconds, 1e6))) != std::future_status::ready) {
            const int writer = ::open(path.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
            if (writer >= 0 && result.wait_for(std::chrono::seconds(1)) == std::future_status::ready) {
                const int fd = result.get().first; // the opener's open returned once a writer was there
                if (fd >= 0)
                    ::close(fd);
            }
            if (writer >= 0)
                ::close(writer);
            throw IoError(name_ + ": a named pipe that nothing opened for writing in " +
                          std::to_string(std::lround(wait_seconds)) + " s (no writer?)");
        }
        const auto [fd, error] = result.get();
        if (fd < 0) {
            errno = error;
            return nullptr;
        }
        std::FILE* file = ::fdopen(fd, "rb");
        if (!file)
            ::close(fd);
        return file;
    }

    // Makes at least n bytes of the file itself available at raw_[raw_begin_]; false if it ends first.
    bool request_raw(std::size_t n)
    {
        if (raw_end_ - raw_begin_ >= n)
            return true;
        if (raw_.empty())
            raw_.resize(kBufferSize);
        std::memmove(raw_.data(), raw_.data() + raw_begin_, raw_end_ - raw_begin_);
        raw_end_ -= raw_begin_;
        raw_begin_ = 0;
        while (raw_end_ < n && !raw_eof_) {
            const std::size_t got = std::fread(raw_.data() + raw_end_, 1, raw_.size() - raw_end_, file_.get());
            if (got == 0) {
                if (std::ferror(file_.get()))
                    throw IoError(name_ + ": read error (" + std::strerror(errno) + ")");
                raw_eof_ = true;
            }
            raw_end_ += got;
        }
        return raw_end_ - raw_begin_ >= n;
    }

    void fill()
    {
        const std::size_t room = buffer_.size() - end_;
        std::size_t got = 0;
        if (!compressed_ && raw_begin_ < raw_end_) { // the bytes read to tell whether it is compressed
            got = std::min(room, raw_end_ - raw_begin_);
            std::memcpy(buffer_.data() + end_, raw_.data() + raw_begin_, got);
            raw_begin_ += got;
        } else if (!compressed_ && !raw_eof_) {
            got = std::fread(buffer_.data() + end_, 1, room, file_.get());
            if (got == 0 && std::ferror(file_.get()))
                throw IoError(name_ + ": read error (" + std::strerror(errno) + ")");
        } else if (compressed_) {
            got = inflate_into(buffer_.data() + end_, room);
        }
        if (got == 0)
            eof_ = true;
        end_ += got;
    }

    // Decompresses up to `room` bytes into `out`; 0 only at the end of the last gzip member. Members
    // written one after another are one stream (as gzip -d reads them); anything else after a member
    // is refused: zlib's gzread ignored it, so a file with a damaged or foreign tail read as complete.
    std::size_t inflate_into(char* out, std::size_t room)
    {
        z_stream& z = stream_->z;
        z.next_out = reinterpret_cast<Bytef*>(out);
        z.avail_out = static_cast<uInt>(std::min<std::size_t>(room, UINT_MAX));
        while (z.avail_out > 0 && !stream_done_) {
            if (member_done_) {
                // Another member, the end of the file, or junk.
                if (!request_raw(1)) {
                    stream_done_ = true;
                    break;
                }
                if (!request_raw(2) || static_cast<unsigned char>(raw_[raw_begin_]) != 0x1f ||
                    static_cast<unsigned char>(raw_[raw_begin_ + 1]) != 0x8b)
                    throw IoError(name_ + ": data after the end of the gzip stream (at byte " +
                                  std::to_string(compressed_offset_) +
                                  "; not another gzip member): the file is damaged or has something appended");
                inflateReset(&z);
                member_done_ = false;
            }
            if (raw_begin_ == raw_end_ && !request_raw(1))
                throw IoError(name_ + ": truncated compressed data (the file ends inside the gzip stream)");
            z.next_in = reinterpret_cast<Bytef*>(raw_.data() + raw_begin_);
            z.avail_in = static_cast<uInt>(std::min<std::size_t>(raw_end_ - raw_begin_, UINT_MAX));
            const uInt before = z.avail_in;
            const int status = inflate(&z, Z_NO_FLUSH);
            raw_begin_ += before - z.avail_in;
            compressed_offset_ += before - z.avail_in;
            if (status == Z_STREAM_END)
                member_done_ = true;
            else if (status == Z_MEM_ERROR)
                throw IoError(name_ + ": out of memory while decompressing");
            else if (status != Z_OK && status != Z_BUF_ERROR)
                throw IoError(name_ + ": corrupt compressed data (" + (z.msg ? z.msg : "zlib error") + ")");
        }
        return room - z.avail_out;
    }

    // zlib's stream state, released however the Input ends (a constructor that throws included).
    struct Inflater
    {
        z_stream z{};
        bool ready = false;
        Inflater() = default;
        Inflater(const Inflater&) = delete;
        Inflater& operator=(const Inflater&) = delete;
        ~Inflater()
        {
            if (ready)
                inflateEnd(&z);
        }
    };

    std::string name_;
    struct FileCloser
    {
        void operator()(std::FILE* f) const { std::fclose(f); }
    };
    std::unique_ptr<std::FILE, FileCloser> file_;
    std::vector<char> raw_; // bytes of the file not yet decompressed (or copied)
    std::size_t raw_begin_ = 0;
    std::size_t raw_end_ = 0;
    bool raw_eof_ = false;
    bool compressed_ = false;
    std::unique_ptr<Inflater> stream_;
    bool member_done_ = false;          // a gzip member ended: another may follow
    bool stream_done_ = false;          // the last member ended with the file
    std::uint64_t compressed_offset_ = 0; // bytes of the file decompressed so far
    std::vector<char> buffer_;
    std::size_t begin_ = 0;
    std::size_t end_ = 0;
    std::uint64_t discarded_ = 0;
    std::uint64_t file_size_ = 0;
    std::uint64_t line_number_ = 0;
    bool eof_ = false;
};

// Which bytes separate tokens: a 256-entry table, since this test runs for every byte of a text file.
struct Separators
{
    bool table[256] = {};
    explicit constexpr Separators(const char* chars)
    {
        for (; *chars; ++chars)
            table[static_cast<unsigned char>(*chars)] = true;
    }
    bool operator()(char c) const { return table[static_cast<unsigned char>(c)]; }
};

constexpr Separators kBlanks(" \t");

// A PLY line up to trailing blanks, '\r' among them (next_line drops one): lines ending in "\r\r\n" (a
// CRLF file converted twice) kept a '\r' that made "element vertex 4\r" no element line, "end_header\r"
// unknown and "1 2 3\r" no number (QA round qa-fuzz); rply, tinyply and plyfile read them.
constexpr const char* kPlyTrailingBlanks = " \t\r\v\f";
std::string_view without_trailing_blanks(std::string_view line)
{
    return line.substr(0, line.find_last_not_of(kPlyTrailingBlanks) + 1);
}

// Splits a text line into tokens; a token starting with '#' ends the line (comment).
class Tokens
{
public:
    Tokens(std::string_view line, const Separators& separators)
        : next_(line.data()), end_(line.data() + line.size()), separators_(&separators)
    {
    }

    bool next(std::string_view& token)
    {
        while (next_ != end_ && (*separators_)(*next_))
            ++next_;
        if (next_ == end_ || *next_ == '#') {
            next_ = end_;
            return false;
        }
        const char* start = next_;
        while (next_ != end_ && !(*separators_)(*next_))
            ++next_;
        token = std::string_view(start, static_cast<std::size_t>(next_ - start));
        return true;
    }

private:
    const char* next_;
    const char* end_;
    const Separators* separators_;
};

// Splits a line of a column file into fields: a run of blanks separates two fields, and so does one
// delimiter (',' or ';') with any blanks around it, so that two delimiters with nothing between them
// enclose an empty field, as spreadsheets and pandas write a missing value or an unnamed index column
// (",x,y,z"). Merged like blanks (until QA round 28), such fields moved every later value one column
// to the left: pandas' CSV of a sphere was read as x = row number, y = x, z = y. A field starting with
// '#' ends the line (comment); a delimiter ending the line ends it without a field after it.
class Fields
{
public:
    Fields(std::string_view line, const Separators& delimiters)
        : next_(line.data()), end_(line.data() + line.size()), delimiters_(&delimiters)
    {
    }

    bool next(std::string_view& field)
    {
        skip_blanks();
        if (next_ == end_ || *next_ == '#') {
            next_ = end_;
            return false;
        }
        const char* start = next_;
        if ((*delimiters_)(*next_)) {
            ++next_; // nothing before this delimiter: an empty field
            field = std::string_view(start, 0);
            return true;
        }
        while (next_ != end_ && !kBlanks(*next_) && !(*delimiters_)(*next_))
            ++next_;
        field = std::string_view(start, static_cast<std::size_t>(next_ - start));
        skip_blanks(); // the separator after the field: blanks, then at most one delimiter
        if (next_ != end_ && (*delimiters_)(*next_))
            ++next_;
        return true;
    }

private:
    void skip_blanks()
    {
        while (next_ != end_ && kBlanks(*next_))
            ++next_;
    }

    const char* next_;
    const char* end_;
    const Separators* delimiters_;
};

enum class Parsed { number, not_a_number, not_finite };

Parsed parse_number(std::string_view token, double& value)
{
    const char* first = token.data();
    const char* last = first + token.size();
    if (first != last && *first == '+')
        ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec == std::errc::result_out_of_range && ptr == last)
        return Parsed::not_finite;
    if (ec != std::errc() || ptr != last)
        return Parsed::not_a_number;
    return std::isfinite(value) ? Parsed::number : Parsed::not_finite;
}

bool parse_count(std::string_view token, std::uint64_t& value)
{
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    return ec == std::errc() && ptr == token.data() + token.size();
}

// The bytes from here to the end of the input (read through when the size is unknown: compressed).
std::uint64_t bytes_left(Input& in)
{
    if (in.file_size() > 0)
        return in.file_size() - in.offset();
    std::uint64_t rest = 0;
    while (in.available() > 0 || in.request(1)) {
        rest += in.available();
        in.consume(in.available());
    }
    return rest;
}

[[noreturn]] void fail_line(const Input& in, const std::string& cause)
{
    throw InvalidInput(in.name() + ": line " + std::to_string(in.line_number()) + ": " + cause);
}

double number_on_line(const Input& in, std::string_view token)
{
    double value = 0;
    const Parsed parsed = parse_number(token, value);
    if (parsed == Parsed::not_finite)
        fail_line(in, quote_token(token) + " is not a finite number (NaN, infinite or out of range)");
    if (parsed == Parsed::not_a_number)
        fail_line(in, quote_token(token) + " is not a number");
    return value;
}

// Reads the first three numbers of the tokens as a position.
Vec3 position_on_line(const Input& in, Tokens& tokens, std::string_view first)
{
    Vec3 p;
    std::string_view token = first;
    for (int axis = 0; axis < 3; ++axis) {
        if (axis > 0 && !tokens.next(token))
            fail_line(in, "expected 3 coordinates, found " + std::to_string(axis));
        p[axis] = number_on_line(in, token);
    }
    return p;
}

// This machine's physical memory in bytes, 0 if unknown.
std::uint64_t physical_memory()
{
#if defined(_SC_PHYS_PAGES) && defined(_SC_PAGE_SIZE)
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    if (pages > 0 && page > 0)
        return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page);
#endif
    return 0;
}

// What a point costs from reading to a built hierarchy, at least: its position (24 bytes) and the
// build's 110 bytes above the input (README: Results). A cloud of more points than memory / this is
// refused while it is read, with a message, instead of the build running out of memory and the
// process being killed (QA round 42: 1.8 MB of gzip held 200M points, 8.9 GB when read).
constexpr std::uint64_t kBuildBytesPerPoint = 128;
// MiB are counted as points per MiB (count × 128 wrapped from 2^57 points: "about 0 MiB", QA round 66).
static_assert((std::uint64_t{1} << 20) % kBuildBytesPerPoint == 0, "whole points per MiB");

void check_memory(const Input& in, std::uint64_t count, const ReadOptions& options)
{
    const std::uint64_t memory = options.memory_bytes > 0 ? options.memory_bytes : physical_memory();
    if (memory > 0 && count > memory / kBuildBytesPerPoint)
        throw IoError(in.name() + ": " + std::to_string(count) + " points or more, which take about " +
                           std::to_string(count / ((std::uint64_t{1} << 20) / kBuildBytesPerPoint)) + " MiB to build (" +
                           std::to_string(kBuildBytesPerPoint) + " bytes a point), more than the " +
                           std::to_string(memory >> 20) + " MiB of memory here; read a part of the file");
}

void check_max_points(const Input& in, std::uint64_t count, const ReadOptions& options)
{
    if (options.max_points > 0 && count > options.max_points)
        throw InvalidInput(in.name() + ": " + std::to_string(count) + " points, more than max_points " +
                           std::to_string(options.max_points));
    if (count % 65536 == 0) // counted point by point: checked now and then
        check_memory(in, count, options);
}

// A count a header declares: within max_points, and where the input's size is unknown (compressed, or
// not a regular file) its positions alone (24 bytes each) within this machine's memory. A compressed
// file's size bounds nothing: 1 MB of gzip expanding to 1 GiB of zeros under a LAS header declaring
// 4,294,967,295 points took 1.6 GB before "truncated" (QA round 34); 10 MB would have taken 16 GB.
// (An uncompressed file's size is checked against the count by each reader.)
void check_declared_points(const Input& in, std::uint64_t count, const ReadOptions& options)
{
    check_max_points(in, count, options);
    const std::uint64_t memory = physical_memory();
    if (in.file_size() == 0 && memory > 0 && count > memory / sizeof(Vec3))
        throw IoError(in.name() + ": the header declares " + std::to_string(count) + " points, whose positions alone (" +
                           std::to_string(static_cast<std::uint64_t>(static_cast<double>(count) * sizeof(Vec3) / 1073741824.0)) + " GiB) exceed this machine's memory (" +
                           std::to_string(memory >> 30) + " GiB)");
    // An uncompressed file's count is checked against its size first (by each reader): a count no
    // file of this size can hold is a truncated or corrupt file, not a large one.
    if (in.file_size() == 0)
        check_memory(in, count, options);
}

// Float32 keeps 24 significant bits: at a coordinate m, adjacent values lie 2^(e-24) apart (m in
// [2^(e-1), 2^e)). Far from the origin that step can be a visible part of the object (the bunny 2e5
// away: steps of 1/64 on a 0.15 object, most points stored as one): detail the file lost before it
// was read. Recorded for the caller (the library does not print) when the step exceeds 1e-4 of the
// points' extent. `float32`: which axes the file stores as float32; the positions are the file's
// coordinates still (origin 0).
void record_float32_spacing(PointCloud& cloud, const std::string& file, const std::array<bool, 3>& float32)
{
    if (cloud.positions.size() < 2 || !(float32[0] || float32[1] || float32[2]))
        return;
    const BoundingBox box = bounding_box(cloud.positions);
    double magnitude = 0;
    for (int a = 0; a < 3; ++a)
        if (float32[static_cast<std::size_t>(a)])
            magnitude = std::max({magnitude, std::abs(box.min[a]), std::abs(box.max[a])});
    if (!(magnitude > 0 && std::isfinite(magnitude)))
        return;
    int exponent = 0;
    std::frexp(magnitude, &exponent);
    const double spacing = std::ldexp(1.0, exponent - 24);
    const double extent = box.largest_side();
    if (extent > 0 && spacing > 1e-4 * extent)
        cloud.coarse_coordinates.push_back({file, magnitude, spacing, extent});
}

void reserve_capped(PointCloud& cloud, std::uint64_t count, std::size_t cap, bool colors)
{
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(count, cap));
    cloud.positions.reserve(n);
    if (colors)
        cloud.colors.reserve(n);
}

std::uint8_t unit_to_byte(double v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); }

// Colours whose file does not say their range (named text columns, OBJ's "v x y z r g b", PLY colours
// wider than a byte) are read at the range the file's largest value says, as the LAS reader does for
// 16-bit fields: up to 1 it is 0-1 (OBJ's convention, float PLY), up to 255 bytes, beyond 16 bits.
// Until QA round 48 each reader assumed one range: 0-1 floats in a CSV came out nearly black, 16-bit
// values in a CSV and 0-255 in an OBJ white, 0-255 in a PLY ushort nearly black. Points are read as a
// stream, so the bytes kept under a narrower range are converted when a later value widens it (at most
// twice a file; they lie within the narrower range, so their value under the wider one is 0 or 1).
class ColorRange
{
public:
    enum class Range { unit, byte, word };

    //! `narrowest`: Range::byte for integer fields (a 1 in a ushort is no full intensity).
    explicit ColorRange(Range narrowest = Range::unit) : range_(narrowest) {}

    //! One point's channels (alpha last, if any) as bytes; `kept` holds the points read so far, which
    //! are converted if these values widen the range.
    Rgba to_bytes(const double* channels, int count, std::vector<Rgba>& kept)
    {
        Range needed = range_;
        for (int c = 0; c < count; ++c)
            needed = std::max(needed, channels[c] <= 1.0 ? Range::unit : channels[c] <= 255.0 ? Range::byte : Range::word);
        if (needed != range_) {
            // Under the wider range a kept value (within the narrower one) is 0 or 1: 1 from half of it.
            const int half = range_ == Range::unit ? (needed == Range::byte ? 128 : 256) : 129;
            for (Rgba& rgba : kept)
                for (int c = 0; c < count; ++c)
                    rgba[static_cast<std::size_t>(c)] = rgba[static_cast<std::size_t>(c)] >= half ? 1 : 0;
            range_ = needed;
        }
        Rgba out{0, 0, 0, 255};
        for (int c = 0; c < count; ++c)
            out[static_cast<std::size_t>(c)] = byte(channels[c]);
        return out;
    }

private:
    std::uint8_t byte(double v) const
    {
        switch (range_) {
        case Range::unit:
            return unit_to_byte(v);
        case Range::byte:
            return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
        case Range::word:
            break;
        }
        return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 65535.0) / 257.0));
    }

    Range range_;
};

// ---------------------------------------------------------------------------------------------------
// XYZ / PTS / TXT / CSV

constexpr Separators kCommaOrSemicolon(",;");
constexpr Separators kSemicolon(";");

// Where the coordinates are on a line of a column file, decided on its first content line: files come
// from spreadsheets and scanner software whose conventions differ, and a misread layout would give a
// wrong cloud without any error.
struct ColumnLayout
{
    std::array<int, 3> column = {0, 1, 2}; // x, y, z
    std::array<int, 3> color = {-1, -1, -1}; // red, green, blue (0-255), when the file has them
    // The header named the colour columns: their values are colours, so a word there is an error and a
    // value beyond 0-255 is clamped. Columns guessed by the PTS convention may be something else
    // (normals, say), so values that are not colours drop the guess instead.
    bool colors_named = false;
    int columns_needed = 3;
    // "1,5;2,5;3,5" (a European spreadsheet's CSV): semicolons separate, commas are decimal points.
    bool decimal_comma = false;
    const Separators* delimiters = &kCommaOrSemicolon; // besides blanks; see Fields
};

// Whether a data line is numbers with decimal commas separated by blanks ("0,5 -1,25 2"): three or
// more blank-separated words, each a number whose one comma stands between digits (or a whole number),
// with no point anywhere and at least one such comma. Read with commas as separators, such a line gave
// (0, 5, -1) and so on without a word (QA round 34).
bool blank_separated_decimal_commas(std::string_view content)
{
    std::size_t words = 0;
    bool comma = false;
    std::string_view word;
    for (Tokens split(content, kBlanks); split.next(word); ++words) {
        std::size_t i = (word[0] == '-' || word[0] == '+') ? 1 : 0;
        const auto digits = [&] {
            const std::size_t start = i;
            while (i < word.size() && word[i] >= '0' && word[i] <= '9')
                ++i;
            return i > start;
        };
        if (!digits())
            return false;
        if (i < word.size() && word[i] == ',') {
            ++i;
            if (!digits())
                return false;
            comma = true;
        }
        if (i < word.size() && (word[i] == 'e' || word[i] == 'E')) { // an exponent: "1,234e-01"
            ++i;
            if (i < word.size() && (word[i] == '-' || word[i] == '+'))
                ++i;
            if (!digits())
                return false;
        }
        if (i != word.size())
            return false;
    }
    return words >= 3 && comma;
}

std::string lower_name(std::string_view token)
{
    std::string name;
    for (char c : token)
        if (c != '"' && c != '\'')
            name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return name;
}

bool has_all(const std::array<int, 3>& columns) { return columns[0] >= 0 && columns[1] >= 0 && columns[2] >= 0; }

// A line of column names ("x,y,z,intensity", CloudCompare's "//X,Y,Z,R,G,B"): the coordinates are in the
// columns named x, y and z; a header naming none of them leaves them in the first three, one naming some
// but not all is refused (reading "intensity,x,y" as x y z would give a wrong cloud without a word).
// Colours (0-255) are in the columns named r, g, b or red, green, blue.
void read_column_names(const Input& in, std::string_view line, bool keep_colors, ColumnLayout& layout)
{
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t'))
        line.remove_prefix(1);
    if (line.substr(0, 2) == "//")
        line.remove_prefix(2);
    Fields tokens(line, *layout.delimiters);
    static const char* const kColorNames[3][2] = {{"r", "red"}, {"g", "green"}, {"b", "blue"}};
    std::array<int, 3> named = {-1, -1, -1};
    std::array<int, 3> color = {-1, -1, -1};
    std::string columns; // as written, for the message
    bool columns_cut = false;
    std::string_view token;
    for (int index = 0; tokens.next(token); ++index) {
        const std::string name = lower_name(token);
        for (int axis = 0; axis < 3; ++axis) {
            // A coordinate named twice ("x,y,z,x": two exports' columns run together) leaves which
            // column holds it a guess; the first was taken without a word (QA round 29), as PCD's
            // fields were until QA round 28.
            if (named[axis] >= 0 && name == std::string(1, static_cast<char>('x' + axis)))
                fail_line(in, "the header names " + name + " twice (columns " + std::to_string(named[axis] + 1) + " and " +
                                  std::to_string(index + 1) + "): which one holds the coordinate is a guess");
            if (named[axis] < 0 && name == std::string(1, static_cast<char>('x' + axis)))
                named[axis] = index;
            if (color[axis] < 0 && (name == kColorNames[axis][0] || name == kColorNames[axis][1]))
                color[axis] = index;
        }
        if (columns.size() < 200) {
            const std::string quoted = quote_token(token); // printable and short
            columns += (index > 0 ? ", " : "") + quoted.substr(1, quoted.size() - 2);
        } else if (!columns_cut) {
            columns += ", ...";
            columns_cut = true;
        }
    }
    if (has_all(named)) {
        layout.column = named;
    } else if (named[0] >= 0 || named[1] >= 0 || named[2] >= 0) {
        std::string missing;
        for (int axis = 0; axis < 3; ++axis)
            if (named[axis] < 0)
                missing += (missing.empty() ? "" : " or ") + std::string(1, static_cast<char>('x' + axis));
        fail_line(in, "the header names no " + missing + " column (columns: " + columns + ")");
    }
    if (has_all(color) && keep_colors) {
        layout.color = color;
        layout.colors_named = true;
    }
    for (int axis = 0; axis < 3; ++axis)
        layout.columns_needed = std::max({layout.columns_needed, layout.column[axis] + 1, layout.color[axis] + 1});
}

// Leica's PTS convention without a header: x y z intensity r g b, or x y z r g b.
void read_pts_colors(std::string_view line, bool keep_colors, ColumnLayout& layout)
{
    Fields tokens(line, *layout.delimiters);
    std::string_view token;
    int count = 0;
    while (tokens.next(token))
        ++count;
    if (!keep_colors || (count != 6 && count != 7))
        return;
    const int first = count - 3;
    layout.color = {first, first + 1, first + 2};
    layout.columns_needed = count;
}

// A colour channel from 0 to 255; false for anything else.
bool color_byte(std::string_view token, std::uint8_t& byte)
{
    double value = 0;
    if (parse_number(token, value) != Parsed::number || value < 0 || value > 255)
        return false;
    byte = static_cast<std::uint8_t>(std::lround(value));
    return true;
}

// Whether a first line names the columns: it opens with CloudCompare's "//", or its first field that is
// not empty (an unnamed index column leaves the first one empty) is a word.
bool is_column_names(std::string_view line, const ColumnLayout& layout)
{
    Fields fields(line, *layout.delimiters);
    std::string_view first;
    while (fields.next(first) && first.empty()) {
    }
    if (first.empty())
        return false;
    if (first.substr(0, 2) == "//")
        return true;
    double ignored = 0;
    const unsigned char c = static_cast<unsigned char>(first.front());
    return parse_number(first, ignored) == Parsed::not_a_number && (std::isalpha(c) || c == '"');
}

double column_number(const Input& in, std::string_view token, const ColumnLayout& layout)
{
    if (!layout.decimal_comma || token.find(',') == std::string_view::npos)
        return number_on_line(in, token);
    char buffer[64];
    if (token.size() > sizeof buffer)
        return number_on_line(in, token); // too long to be a number: reports it as it is
    std::replace_copy(token.begin(), token.end(), buffer, ',', '.');
    return number_on_line(in, std::string_view(buffer, token.size()));
}

PointCloud read_columns(Input& in, const ReadOptions& options, bool pts)
{
    PointCloud cloud;
    ColumnLayout layout;
    ColorRange named_colors;
    bool layout_known = false;
    std::string_view line;
    bool first_content_line = true;
    bool header_possible = true; // on the first content line, or on the line after a leading point count
    bool separators_known = false;
    // A count line declares the points of the scan after it, up to the next count line or the end: a
    // scan with fewer is truncated, one with more is no scan of that count (QA round 34: counts of 10
    // and 99999999999 before 300 points were read without a word).
    std::uint64_t declared = 0;
    std::size_t declared_line = 0, scan_start = 0;
    bool counted = false;
    const auto check_count = [&] {
        const std::size_t found = cloud.positions.size() - scan_start;
        if (counted && found != declared)
            throw IoError(in.name() + ": line " + std::to_string(declared_line) + " declares " + std::to_string(declared) +
                          " points, but " + (found < declared ? "only " : "") + std::to_string(found) + " follow it" +
                          (found < declared ? " (truncated?)" : ""));
    };
    while (in.next_line(line)) {
        // The first line with data (not a comment, not a point count) says whether semicolons separate.
        if (!separators_known) {
            std::string_view content = line.substr(0, 0), token;
            std::size_t tokens_seen = 0;
            std::uint64_t count = 0;
            for (Tokens words(line, kBlanks); words.next(token); ++tokens_seen)
                content = line.substr(0, static_cast<std::size_t>(token.data() + token.size() - line.data()));
            if (content.find(';') != std::string_view::npos || blank_separated_decimal_commas(content)) {
                layout.delimiters = &kSemicolon;
                layout.decimal_comma = true;
            }
            separators_known = tokens_seen > 1 || (tokens_seen == 1 && !parse_count(content.substr(content.find_first_not_of(" \t")), count));
        } else if (!layout.decimal_comma && line.find(',') != std::string_view::npos &&
                   blank_separated_decimal_commas(line.substr(0, line.find('#')))) {
            // Decimal commas after a first data line without any ("0 0 1", then "0,5 -1,25 2"): read
            // with commas separating, such a line gave (0, 5, -1) without a word (QA round 35).
            fail_line(in, "numbers with decimal commas, but the first data line had none and set commas to separate "
                          "columns; write that line with decimal commas too (\"0,0 0,0 1,0\")");
        }
        Fields tokens(line, *layout.delimiters);
        std::string_view token;
        if (!tokens.next(token))
            continue;
        // PTS files (and some XYZ exports) open with the point count on a line of its own, and a PTS file
        // of several scans repeats it before each scan.
        std::string_view second;
        Fields rest = tokens;
        std::uint64_t count = 0;
        if ((first_content_line || pts) && !rest.next(second) && parse_count(token, count)) {
            check_count();
            counted = true;
            declared = count;
            declared_line = in.line_number();
            scan_start = cloud.positions.size();
            // A header may follow the count ("3", then "x y z": it was read as a point, QA round 28).
            header_possible = first_content_line;
            first_content_line = false;
            continue;
        }
        first_content_line = false;
        if (header_possible) {
            header_possible = false;
            if (is_column_names(line, layout)) {
                read_column_names(in, line, options.keep_colors, layout);
                layout_known = true;
                // Names between blanks ("x y z") say nothing of the numbers' commas: the first data
                // line decides (QA round 35: "0,5 -1,25 2" after them was split at the commas).
                if (line.find_first_of(",;") == std::string_view::npos)
                    separators_known = false;
                continue;
            }
        }
        // CloudCompare and other tools write "//" comment lines.
        if (token.substr(0, 2) == "//")
            continue;
        if (!layout_known) {
            layout_known = true;
            if (pts)
                read_pts_colors(line, options.keep_colors, layout);
        }
        std::array<std::string_view, 3> fields;
        std::array<std::string_view, 3> color_fields;
        for (int index = 0; index < layout.columns_needed; ++index) {
            if (index > 0 && !tokens.next(token)) {
                if (layout.columns_needed == 3)
                    fail_line(in, "expected 3 coordinates, found " + std::to_string(index));
                fail_line(in, "expected " + std::to_string(layout.columns_needed) + " columns (as " +
                                  (pts ? "the first line" : "the header") + " has), found " + std::to_string(index));
            }
            for (int axis = 0; axis < 3; ++axis) {
                if (layout.column[axis] == index)
                    fields[axis] = token;
                if (layout.color[axis] == index)
                    color_fields[axis] = token;
            }
        }
        Vec3 p;
        for (int axis = 0; axis < 3; ++axis) {
            if (fields[axis].empty())
                fail_line(in, std::string("no ") + static_cast<char>('x' + axis) + " value (column " +
                                  std::to_string(layout.column[axis] + 1) + " is empty)");
            p[axis] = column_number(in, fields[axis], layout);
        }
        check_max_points(in, cloud.positions.size() + 1, options);
        cloud.positions.push_back(p);
        if (has_all(layout.color) && layout.colors_named) {
            // Named colours: a word is an error as in a coordinate column; their range is the file's
            // (ColorRange), negative values are 0.
            double channels[3];
            for (int k = 0; k < 3; ++k)
                channels[k] = column_number(in, color_fields[k], layout);
            cloud.colors.push_back(named_colors.to_bytes(channels, 3, cloud.colors));
        } else if (has_all(layout.color)) {
            Rgba c = {0, 0, 0, 255};
            if (color_byte(color_fields[0], c[0]) && color_byte(color_fields[1], c[1]) &&
                color_byte(color_fields[2], c[2])) {
                cloud.colors.push_back(c);
            } else {
                // Not colours after all (normals, say): the file is read without them.
                layout.color = {-1, -1, -1};
                cloud.colors.clear();
                cloud.colors.shrink_to_fit();
            }
        }
    }
    check_count();
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// OBJ

PointCloud read_obj(Input& in, const ReadOptions& options)
{
    PointCloud cloud;
    std::vector<Rgba> colors;
    ColorRange color_range;
    bool all_colored = true;
    std::string_view line;
    while (in.next_line(line)) {
        // Statements other than "v" are skipped, so a damaged vertex line would go without a word: a NUL
        // byte (binary data in the text) and a vertex keyword run into its first number ("v1 2 3") are
        // refused (QA round 42: both were skipped, the point lost).
        if (std::memchr(line.data(), '\0', line.size())) {
            std::string without(line);
            without.erase(std::remove(without.begin(), without.end(), '\0'), without.end());
            Tokens words(without, kBlanks);
            std::string_view first;
            if (words.next(first) && first[0] == 'v' && (first.size() == 1 || std::strchr("0123456789+-.", first[1])))
                fail_line(in, "a NUL byte in a vertex line (binary data in a text file?)");
            continue; // in a comment, another statement or padding: no point lost
        }
        Tokens tokens(line, kBlanks);
        std::string_view token;
        if (!tokens.next(token))
            continue;
        if (token.size() > 1 && token[0] == 'v' && std::strchr("0123456789+-.", token[1]))
            fail_line(in, quote_token(token) + ": expected 'v x y z' (a blank after the v)");
        if (token != "v")
            continue;
        double values[7];
        int count = 0;
        while (tokens.next(token)) {
            if (count == 7)
                fail_line(in, "a vertex has more than 7 values");
            values[count++] = number_on_line(in, token);
        }
        if (count < 3)
            fail_line(in, "expected 3 coordinates, found " + std::to_string(count));
        check_max_points(in, cloud.positions.size() + 1, options);
        cloud.positions.push_back({values[0], values[1], values[2]});
        // "v x y z r g b" is the common vertex-colour extension (0-1, but 0-255 is written too:
        // ColorRange); "v x y z w" is a weight.
        if (count == 6 && all_colored && options.keep_colors)
            colors.push_back(color_range.to_bytes(values + 3, 3, colors));
        else
            all_colored = false;
    }
    if (all_colored && options.keep_colors)
        cloud.colors = std::move(colors);
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// OFF

// Next line with a token; false at the end of the input.
bool next_content_line(Input& in, Tokens& tokens, std::string_view& first)
{
    std::string_view line;
    while (in.next_line(line)) {
        tokens = Tokens(line, kBlanks);
        if (tokens.next(first))
            return true;
    }
    return false;
}

PointCloud read_off(Input& in, const ReadOptions& options)
{
    Tokens tokens("", kBlanks);
    std::string_view token;
    if (!next_content_line(in, tokens, token))
        throw InvalidInput(in.name() + ": empty file");
    // The keyword is [ST][C][N][4][n]OFF; only 3D vertices are supported.
    const std::size_t off_at = token.rfind("OFF");
    if (off_at == std::string_view::npos || off_at + 3 != token.size())
        fail_line(in, "expected an OFF header keyword, found " + quote_token(token));
    const std::string_view prefix = token.substr(0, off_at);
    if (prefix.find_first_of("4n") != std::string_view::npos)
        fail_line(in, quote_token(token) + " files (not 3D) are not supported");
    if (prefix.find_first_not_of("STCN") != std::string_view::npos)
        fail_line(in, "unknown OFF variant " + quote_token(token));
    // The counts may follow the keyword on the same line.
    if (!tokens.next(token) && !next_content_line(in, tokens, token))
        throw IoError(in.name() + ": truncated: no vertex count after the OFF header");
    if (token == "BINARY")
        fail_line(in, "binary OFF is not supported");
    std::uint64_t vertex_count = 0;
    if (!parse_count(token, vertex_count))
        fail_line(in, "expected the vertex count, found " + quote_token(token));
    check_declared_points(in, vertex_count, options);
    // The face count checks what follows the vertices (below); without one, any number of faces may follow.
    std::uint64_t face_count = UINT64_MAX;
    if (tokens.next(token) && !parse_count(token, face_count))
        fail_line(in, "expected the face count, found " + quote_token(token));

    // A vertex line holds x y z, then 3 normal values (N), 2 texture coordinates (ST) and a colour (C:
    // a colour map index, or 3 or 4 components; writers differ in what they put first) as the keyword
    // says. More or fewer mean the counts do not describe the lines: a vertex count larger than the
    // vertex lines reads face lines ("3 0 1 2") as points without a word.
    const auto has = [&](char c) { return prefix.find(c) != std::string_view::npos; };
    const std::size_t fewest = 3 + (has('N') ? 3 : 0) + (has('S') ? 2 : 0);
    const std::size_t most = fewest + (has('C') ? 4 : 0);
    PointCloud cloud;
    reserve_capped(cloud, vertex_count, kReserveCap, false);
    // COFF colours (QA round 50: dropped without a word): 3 or 4 components after the normals (the
    // Geomview order: normals, colour, texture), in 0-1 or 0-255 (ColorRange); a colour map index, or
    // any vertex without components, leaves the cloud without colours.
    bool all_colored = options.keep_colors && has('C');
    ColorRange color_range;
    std::vector<Rgba> colors;
    const std::size_t colour_at = 3 + (has('N') ? 3 : 0);
    for (std::uint64_t i = 0; i < vertex_count; ++i) {
        if (!next_content_line(in, tokens, token))
            throw IoError(in.name() + ": truncated: file ends at line " + std::to_string(in.line_number()) +
                          " after " + std::to_string(i) + " of " + std::to_string(vertex_count) + " vertices");
        cloud.positions.push_back(position_on_line(in, tokens, token));
        std::size_t values = 3;
        double channels[4] = {0, 0, 0, 255};
        while (tokens.next(token)) {
            if (all_colored && values >= colour_at && values < colour_at + 4)
                channels[values - colour_at] = number_on_line(in, token);
            ++values;
        }
        const std::size_t components = values >= fewest ? values - fewest : 0;
        if (all_colored && (components == 3 || components == 4))
            colors.push_back(color_range.to_bytes(channels, static_cast<int>(components), colors));
        else
            all_colored = false;
        if (values < fewest || values > most)
            fail_line(in, "vertex " + std::to_string(i) + " of " + std::to_string(vertex_count) + " has " +
                              std::to_string(values) + " values, a " + std::string(prefix) + "OFF vertex has " +
                              (fewest == most ? std::to_string(fewest) : std::to_string(fewest) + " to " + std::to_string(most)) +
                              " (is the vertex count in line 2 right?)");
    }
    // The faces are not read, but what follows the vertices must be the faces the header declares:
    // more data means a vertex count lower than the vertex lines (100 declared, 500 written), and the
    // cloud read would be part of the file's, as if it were whole. A face is "n i1 .. in [colour]": a
    // count, then n indices of declared vertices (on the following lines too, as the format allows),
    // then its colour up to the line's end. A vertex line where a face belongs (a coordinate that is no
    // count or index), a face too many, or any data when no face is declared is refused. A file that
    // ends inside its faces, or before the faces it declares, is truncated as a PLY file so cut is,
    // though its vertices are whole: a copy that stopped early (QA round 66 found the two formats
    // judged apart).
    if (all_colored && vertex_count > 0)
        cloud.colors = std::move(colors);
    const auto counted = [](std::uint64_t n, const char* one, const char* many) {
        return std::to_string(n) + " " + (n == 1 ? one : many);
    };
    const std::string declared = counted(vertex_count, "vertex", "vertices") +
                                 (face_count == UINT64_MAX ? "" : " and " + counted(face_count, "face", "faces"));
    std::uint64_t f = 0;
    for (; next_content_line(in, tokens, token); ++f) {
        if (f == face_count)
            fail_line(in, "data after the " + declared + " the header declares: the header does not describe the data");
        const auto face = [&] {
            return "face " + std::to_string(f) + (face_count == UINT64_MAX ? "" : " of " + std::to_string(face_count)) + ": ";
        };
        std::uint64_t n = 0;
        if (!parse_count(token, n))
            fail_line(in, face() + quote_token(token) + " is not a vertex count (a vertex line? the header declares " +
                              std::to_string(vertex_count) + " vertices)");
        for (std::uint64_t k = 0; k < n; ++k) {
            if (!tokens.next(token) && !next_content_line(in, tokens, token))
                throw IoError(in.name() + ": truncated: file ends at line " + std::to_string(in.line_number()) +
                              " inside face " + std::to_string(f) + " (after " + std::to_string(k) + " of its " +
                              std::to_string(n) + " indices)");
            std::uint64_t index = 0;
            if (!parse_count(token, index))
                fail_line(in, face() + quote_token(token) + " is not a vertex index (a vertex line? the header declares " +
                                  std::to_string(vertex_count) + " vertices)");
            if (index >= vertex_count)
                fail_line(in, face() + "vertex index " + std::to_string(index) + " is not below the " +
                                  std::to_string(vertex_count) + " vertices the header declares");
        }
    }
    if (face_count != UINT64_MAX && f < face_count)
        throw IoError(in.name() + ": truncated: file ends at line " + std::to_string(in.line_number()) + " after " +
                      std::to_string(f) + " of the " + counted(face_count, "face", "faces") + " the header declares");
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// PLY

enum class PlyType : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };
enum class PlyEncoding { ascii, binary_le, binary_be };

// The PLY type names, the classic spelling of each type before its sized one (type_name gives the first).
struct PlyTypeName
{
    const char* name;
    PlyType type;
};
constexpr PlyTypeName kPlyTypeNames[] = {
    {"char", PlyType::int8},     {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
    {"uint8", PlyType::uint8},   {"short", PlyType::int16},     {"int16", PlyType::int16},
    {"ushort", PlyType::uint16}, {"uint16", PlyType::uint16},   {"int", PlyType::int32},
    {"int32", PlyType::int32},   {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
    {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64},
    {"float64", PlyType::float64}};

bool parse_ply_type(std::string_view name, PlyType& type)
{
    for (const PlyTypeName& e : kPlyTypeNames)
        if (name == e.name) {
            type = e.type;
            return true;
        }
    return false;
}

std::size_t type_size(PlyType t)
{
    switch (t) {
    case PlyType::int8: case PlyType::uint8: return 1;
    case PlyType::int16: case PlyType::uint16: return 2;
    case PlyType::int32: case PlyType::uint32: case PlyType::float32: return 4;
    case PlyType::float64: return 8;
    }
    return 1;
}

bool is_float_type(PlyType t) { return t == PlyType::float32 || t == PlyType::float64; }

// Whether an ASCII value is one the property's type can hold: a whole number within its range for the
// integer types. A binary file could never hold 3.7 as an int or 300 as a uchar; an ASCII one that
// does was written by something other than what its header says (QA round 42).
bool fits_type(double value, PlyType t)
{
    const auto within = [&](double lo, double hi) { return value == std::floor(value) && value >= lo && value <= hi; };
    switch (t) {
    case PlyType::int8: return within(-128.0, 127.0);
    case PlyType::uint8: return within(0.0, 255.0);
    case PlyType::int16: return within(-32768.0, 32767.0);
    case PlyType::uint16: return within(0.0, 65535.0);
    case PlyType::int32: return within(-2147483648.0, 2147483647.0);
    case PlyType::uint32: return within(0.0, 4294967295.0);
    case PlyType::float32: case PlyType::float64: return true;
    }
    return true;
}

const char* type_name(PlyType t)
{
    for (const PlyTypeName& e : kPlyTypeNames)
        if (e.type == t)
            return e.name;
    return "?";
}

bool host_is_little_endian()
{
    const std::uint16_t one = 1;
    unsigned char first = 0;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

template <typename T>
T load(const char* p, bool swap)
{
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, p, sizeof(T));
    if (swap)
        std::reverse(bytes, bytes + sizeof(T));
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
}

double decode(const char* p, PlyType t, bool swap)
{
    switch (t) {
    case PlyType::int8: return load<std::int8_t>(p, swap);
    case PlyType::uint8: return load<std::uint8_t>(p, swap);
    case PlyType::int16: return load<std::int16_t>(p, swap);
    case PlyType::uint16: return load<std::uint16_t>(p, swap);
    case PlyType::int32: return load<std::int32_t>(p, swap);
    case PlyType::uint32: return load<std::uint32_t>(p, swap);
    case PlyType::float32: return load<float>(p, swap);
    case PlyType::float64: return load<double>(p, swap);
    }
    return 0;
}

struct PlyProperty
{
    std::string name;
    PlyType type = PlyType::float32;  // the item type for lists
    bool is_list = false;
    PlyType count_type = PlyType::uint8;
    std::size_t offset = 0;  // byte offset in a fixed-size binary record
};

struct PlyElement
{
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
    bool has_lists = false;
    //! Record size without list items (the exact size when there are no lists).
    std::size_t min_size = 0;

    int find(std::string_view property) const
    {
        for (std::size_t i = 0; i < properties.size(); ++i)
            if (properties[i].name == property)
                return static_cast<int>(i);
        return -1;
    }
};

struct PlyHeader
{
    PlyEncoding encoding = PlyEncoding::ascii;
    std::vector<PlyElement> elements;
};

PlyHeader read_ply_header(Input& in)
{
    std::string_view line;
    // "ply" up to trailing blanks, as every other header line is read: "ply \n" (a writer's trailing
    // space) and "ply\r\r\n" were refused as no PLY file, though rply, tinyply and plyfile read them.
    // A binary body can hold a line feed, so a header of carriage returns alone is told by its start.
    if (in.next_line(line) && line.substr(0, 4) == "ply\r" && line.find_first_not_of(kPlyTrailingBlanks, 3) != std::string_view::npos)
        throw InvalidInput(in.name() + ": its lines end in a carriage return alone (classic Mac OS text); convert them "
                                       "to line feeds (\\n or \\r\\n)");
    if (without_trailing_blanks(line) != "ply")
        throw InvalidInput(in.name() + ": not a PLY file (no 'ply' on the first line)");
    PlyHeader header;
    bool have_format = false;
    std::uint64_t vertex_line = 0;
    for (;;) {
        if (!in.next_line(line))
            throw InvalidInput(in.name() + ": PLY header has no end_header line");
        line = without_trailing_blanks(line); // as the first line
        Tokens tokens(line, kBlanks);
        std::string_view keyword;
        if (!tokens.next(keyword) || keyword == "comment" || keyword == "obj_info")
            continue;
        std::string_view a, b, c, d;
        if (keyword == "end_header") {
            break;
        } else if (keyword == "format") {
            tokens.next(a);
            if (a == "ascii")
                header.encoding = PlyEncoding::ascii;
            else if (a == "binary_little_endian")
                header.encoding = PlyEncoding::binary_le;
            else if (a == "binary_big_endian")
                header.encoding = PlyEncoding::binary_be;
            else
                fail_line(in, "unknown PLY format " + quote_token(a));
            have_format = true;
        } else if (keyword == "element") {
            PlyElement element;
            if (!tokens.next(a) || !tokens.next(b) || tokens.next(c))
                fail_line(in, "expected 'element <name> <count>'");
            // A count that is no whole number from 0 up, or too large for any file (QA round 50: 2e19 and
            // -5 were told only the expected form).
            if (!parse_count(b, element.count))
                fail_line(in, "element " + quote_token(a) + " has count " + quote_token(b) +
                                  ": not a whole number from 0 to 2^64 - 1");
            element.name = std::string(a);
            // Two vertex elements (two clouds' headers run together, 250 + 250): only the first would be
            // read, the second skipped as an element the reader does not need.
            if (element.name == "vertex") {
                if (vertex_line > 0)
                    fail_line(in, "a second 'vertex' element (the first is on line " + std::to_string(vertex_line) +
                                      "): the header does not describe one cloud");
                vertex_line = in.line_number();
            }
            header.elements.push_back(std::move(element));
        } else if (keyword == "property") {
            if (header.elements.empty())
                fail_line(in, "property before any element");
            PlyElement& element = header.elements.back();
            PlyProperty property;
            tokens.next(a);
            if (a == "list") {
                if (!tokens.next(b) || !tokens.next(c) || !tokens.next(d) || tokens.next(a))
                    fail_line(in, "expected 'property list <count type> <item type> <name>'");
                if (!parse_ply_type(b, property.count_type) || is_float_type(property.count_type))
                    fail_line(in, "bad list count type " + quote_token(b));
                if (!parse_ply_type(c, property.type))
                    fail_line(in, "unknown property type " + quote_token(c));
                property.is_list = true;
                property.name = std::string(d);
                element.has_lists = true;
                element.min_size += type_size(property.count_type);
            } else {
                if (!tokens.next(b) || tokens.next(c))
                    fail_line(in, "expected 'property <type> <name>'");
                if (!parse_ply_type(a, property.type))
                    fail_line(in, "unknown property type " + quote_token(a));
                property.name = std::string(b);
                property.offset = element.min_size;
                element.min_size += type_size(property.type);
            }
            element.properties.push_back(std::move(property));
        } else {
            fail_line(in, "unexpected " + quote_token(keyword) + " in the PLY header");
        }
    }
    if (!have_format)
        throw InvalidInput(in.name() + ": PLY header has no format line");
    return header;
}

std::uint64_t saturating_mul(std::uint64_t a, std::uint64_t b)
{
    std::uint64_t r = 0;
    return __builtin_mul_overflow(a, b, &r) ? UINT64_MAX : r;
}

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b)
{
    std::uint64_t r = 0;
    return __builtin_add_overflow(a, b, &r) ? UINT64_MAX : r;
}

// Where the fields the reader keeps sit in a vertex record.
struct VertexLayout
{
    int xyz[3] = {-1, -1, -1};
    int rgba[4] = {-1, -1, -1, -1};
    bool colors = false;
};

VertexLayout vertex_layout(const Input& in, const PlyElement& vertex, bool keep_colors)
{
    VertexLayout layout;
    // Two vertex properties of a name the reader uses (two x): which one holds the coordinate is
    // anyone's guess, and the first was read without a word (QA round 42). Other names may repeat.
    for (const char* used : {"x", "y", "z", "X", "Y", "Z", "red", "green", "blue", "alpha", "diffuse_red", "diffuse_green", "diffuse_blue",
                             "diffuse_alpha"})
        if (std::count_if(vertex.properties.begin(), vertex.properties.end(),
                          [&](const PlyProperty& p) { return p.name == used; }) > 1)
            throw InvalidInput(in.name() + ": the PLY vertex element has two '" + used + "' properties: the header is ambiguous");
    // Older PDAL wrote X, Y and Z (QA round 66: refused as "no scalar 'x'"); PLY names are case-sensitive,
    // so capitals are read only where no axis has a small letter.
    const bool capitals = vertex.find("x") < 0 && vertex.find("y") < 0 && vertex.find("z") < 0 && vertex.find("X") >= 0 &&
                          vertex.find("Y") >= 0 && vertex.find("Z") >= 0;
    const char* small_axes[3] = {"x", "y", "z"};
    const char* capital_axes[3] = {"X", "Y", "Z"};
    const char* const* axes = capitals ? capital_axes : small_axes;
    for (int i = 0; i < 3; ++i) {
        layout.xyz[i] = vertex.find(axes[i]);
        if (layout.xyz[i] < 0 || vertex.properties[static_cast<std::size_t>(layout.xyz[i])].is_list)
            throw InvalidInput(in.name() + ": PLY vertex element has no scalar '" + axes[i] + "' property");
    }
    const char* channels[4] = {"red", "green", "blue", "alpha"};
    // Scanalyze-era Stanford files and some MeshLab exports name them diffuse_red and so on (dropped
    // without a word until QA round 48).
    const char* diffuse[4] = {"diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"};
    const bool plain = vertex.find("red") >= 0 || vertex.find("green") >= 0 || vertex.find("blue") >= 0;
    for (int i = 0; i < 4; ++i) {
        const int index = vertex.find(plain ? channels[i] : diffuse[i]);
        if (index >= 0 && !vertex.properties[static_cast<std::size_t>(index)].is_list)
            layout.rgba[i] = index;
    }
    layout.colors = keep_colors && layout.rgba[0] >= 0 && layout.rgba[1] >= 0 && layout.rgba[2] >= 0;
    return layout;
}


[[noreturn]] void fail_truncated(const Input& in, const PlyElement& element, std::uint64_t done)
{
    throw IoError(in.name() + ": truncated: file ends after " + std::to_string(done) + " of " +
                  std::to_string(element.count) + " " + element.name + " elements");
}

std::uint64_t list_length(const Input& in, const PlyElement& element, double value)
{
    if (!(value >= 0) || value != std::floor(value) || value > 4294967295.0) {
        // Where it is, and the value as written (QA round 50: "bad list length -1.000000").
        char written[32];
        std::snprintf(written, sizeof written, "%.17g", value);
        throw InvalidInput(in.name() + ": bad list length " + written + " in a " + element.name + " element (its count ends at byte " +
                           std::to_string(in.offset()) + "): not a whole number from 0 to 2^32 - 1");
    }
    return static_cast<std::uint64_t>(value);
}

// Reads one binary element instance property by property (needed when it has lists). Returns the
// decoded scalar values the caller asked for in `wanted` (indices into properties) via `values`.
bool read_binary_instance(Input& in, const PlyElement& element, bool swap, double* values)
{
    for (std::size_t i = 0; i < element.properties.size(); ++i) {
        const PlyProperty& property = element.properties[i];
        if (property.is_list) {
            const char* p = in.take(type_size(property.count_type));
            if (!p)
                return false;
            const std::uint64_t n = list_length(in, element, decode(p, property.count_type, swap));
            if (!in.skip(n * type_size(property.type)))
                return false;
        } else {
            const char* p = in.take(type_size(property.type));
            if (!p)
                return false;
            if (values)
                values[i] = decode(p, property.type, swap);
        }
    }
    return true;
}

void skip_binary_element(Input& in, const PlyElement& element, bool swap)
{
    if (!element.has_lists) {
        if (!in.skip(saturating_mul(element.count, element.min_size)))
            fail_truncated(in, element, 0);
        return;
    }
    for (std::uint64_t i = 0; i < element.count; ++i)
        if (!read_binary_instance(in, element, swap, nullptr))
            fail_truncated(in, element, i);
}

// Next non-blank line of an ascii PLY body; throws at the end of the input.
Tokens next_ascii_record(Input& in, const PlyElement& element, std::uint64_t index)
{
    std::string_view line;
    while (in.next_line(line)) {
        line = without_trailing_blanks(line);
        if (std::any_of(line.begin(), line.end(), [](char c) { return !kBlanks(c); }))
            return Tokens(line, kBlanks);
    }
    throw IoError(in.name() + ": truncated: file ends at line " + std::to_string(in.line_number()) + " after " +
                  std::to_string(index) + " of " + std::to_string(element.count) + " " + element.name +
                  " elements");
}

// Reads past every instance of an element that is not needed; throws if the input ends first.
void skip_element(Input& in, const PlyElement& element, bool binary, bool swap)
{
    if (binary) {
        skip_binary_element(in, element, swap);
        return;
    }
    for (std::uint64_t i = 0; i < element.count; ++i)
        next_ascii_record(in, element, i);
}

PointCloud read_ply(Input& in, const ReadOptions& options)
{
    const PlyHeader header = read_ply_header(in);
    const bool binary = header.encoding != PlyEncoding::ascii;
    const bool swap = (header.encoding == PlyEncoding::binary_be) == host_is_little_endian();

    std::size_t vertex_index = header.elements.size();
    for (std::size_t i = 0; i < header.elements.size(); ++i)
        if (header.elements[i].name == "vertex") {
            vertex_index = i;
            break;
        }
    if (vertex_index == header.elements.size())
        throw InvalidInput(in.name() + ": PLY file has no vertex element");
    const PlyElement& vertex = header.elements[vertex_index];
    const VertexLayout layout = vertex_layout(in, vertex, options.keep_colors);
    check_declared_points(in, vertex.count, options);

    // Before allocating anything, check that an uncompressed binary file can hold what it declares,
    // the elements after the vertices too (their smallest size: a file cut off after its vertices is
    // truncated all the same, and says so, though the vertices are whole). The message names the
    // element that does not fit: an absurd count ahead of the vertices is the fault then, not the
    // vertex count.
    bool count_confirmed = false;
    if (binary && in.file_size() > 0) {
        std::uint64_t needed = in.offset();
        for (std::size_t i = 0; i < header.elements.size(); ++i) {
            const PlyElement& element = header.elements[i];
            needed = saturating_add(needed, saturating_mul(element.count, element.min_size));
            if (needed <= in.file_size())
                continue;
            const std::string declared = i == vertex_index
                                             ? std::to_string(vertex.count) + " vertices"
                                             : std::to_string(element.count) + " " + quote_token(element.name) +
                                                   (i < vertex_index ? " elements ahead of the vertices"
                                                                     : " elements after the vertices");
            throw IoError(in.name() + ": truncated: the header declares " + declared + " (at least " +
                          std::to_string(needed) + " bytes) but the file has " + std::to_string(in.file_size()) +
                          " bytes");
        }
        count_confirmed = true;
    }

    for (std::size_t e = 0; e < vertex_index; ++e)
        skip_element(in, header.elements[e], binary, swap);

    PointCloud cloud;
    reserve_capped(cloud, vertex.count, count_confirmed ? SIZE_MAX : kReserveCap, layout.colors);
    std::vector<double> values(vertex.properties.size(), 0.0);
    // Only the kept fields are decoded (and must be finite numbers); the others are skipped unread.
    std::vector<int> fields(layout.xyz, layout.xyz + 3);
    if (layout.colors)
        for (int c : layout.rgba)
            if (c >= 0)
                fields.push_back(c);
    std::vector<bool> kept(vertex.properties.size(), false), is_coordinate(vertex.properties.size(), false);
    for (int f : fields)
        kept[static_cast<std::size_t>(f)] = true;
    for (int f : layout.xyz)
        is_coordinate[static_cast<std::size_t>(f)] = true;
    // Colours have the range their values say (ColorRange): floats 0-1 or 0-255, integer fields 0-255
    // (a byte's own range, never widened) or, beyond it, 0-65535.
    const PlyType color_type = layout.colors ? vertex.properties[static_cast<std::size_t>(layout.rgba[0])].type : PlyType::uint8;
    ColorRange color_range(is_float_type(color_type) ? ColorRange::Range::unit : ColorRange::Range::byte);
    const auto store = [&](const double* v) {
        cloud.positions.push_back({v[layout.xyz[0]], v[layout.xyz[1]], v[layout.xyz[2]]});
        if (layout.colors) {
            double channels[4];
            const int count = layout.rgba[3] >= 0 ? 4 : 3; // red, green and blue are there (vertex_layout)
            for (int c = 0; c < count; ++c) {
                channels[c] = v[layout.rgba[c]];
                // A binary float colour of NaN became an unspecified byte without a word (QA round
                // 29); in an ASCII file the same value is refused, as a coordinate is in both.
                if (!std::isfinite(channels[c]))
                    throw InvalidInput(in.name() + ": vertex " + std::to_string(cloud.positions.size() - 1) + ": its " +
                                       vertex.properties[static_cast<std::size_t>(layout.rgba[c])].name +
                                       " value is not a finite number");
            }
            cloud.colors.push_back(color_range.to_bytes(channels, count, cloud.colors));
        }
    };

    if (binary && !vertex.has_lists) {
        // The common case: fixed-size records.
        for (std::uint64_t i = 0; i < vertex.count; ++i) {
            const char* record = in.take(vertex.min_size);
            if (!record)
                fail_truncated(in, vertex, i);
            for (int f : fields) {
                const PlyProperty& property = vertex.properties[static_cast<std::size_t>(f)];
                values[static_cast<std::size_t>(f)] = decode(record + property.offset, property.type, swap);
            }
            store(values.data());
        }
    } else if (binary) {
        for (std::uint64_t i = 0; i < vertex.count; ++i) {
            if (!read_binary_instance(in, vertex, swap, values.data()))
                fail_truncated(in, vertex, i);
            store(values.data());
        }
    } else {
        for (std::uint64_t i = 0; i < vertex.count; ++i) {
            Tokens tokens = next_ascii_record(in, vertex, i);
            std::string_view token;
            std::size_t found = 0;
            std::uint64_t list_items = 0;
            for (std::size_t p = 0; p < vertex.properties.size(); ++p) {
                const PlyProperty& property = vertex.properties[p];
                if (!tokens.next(token))
                    fail_line(in, "vertex " + std::to_string(i) + " has " + std::to_string(found) +
                                      " values, expected " + std::to_string(vertex.properties.size()));
                ++found;
                if (property.is_list) {
                    std::uint64_t n = 0;
                    if (!parse_count(token, n))
                        fail_line(in, "bad list length " + quote_token(token));
                    for (std::uint64_t k = 0; k < n; ++k)
                        if (!tokens.next(token))
                            fail_line(in, "list " + property.name + " is shorter than its length " +
                                              std::to_string(n));
                    list_items += n;
                } else if (kept[p]) {
                    values[p] = number_on_line(in, token);
                    // Coordinates only: colours of any value are clamped as before (a uchar alpha of
                    // 0.5 is a writer's unit scale, not another layout).
                    if (is_coordinate[p] && !fits_type(values[p], property.type))
                        fail_line(in, "vertex " + std::to_string(i) + ": " + property.name + " " + quote_token(token) +
                                          " is no " + type_name(property.type) + " value, as the header declares it");
                }
            }
            // Each vertex is one line: more values than the properties take mean the header does not
            // describe the data (a missing property, or two vertices run together), so the values
            // read may be the wrong ones.
            if (tokens.next(token)) {
                std::uint64_t total = found + list_items + 1;
                while (tokens.next(token))
                    ++total;
                const std::string lists = vertex.has_lists ? " (" + std::to_string(found + list_items) +
                                                                 " values with the list lengths this line gives)"
                                                           : std::string();
                fail_line(in, "vertex " + std::to_string(i) + " has " + std::to_string(total) +
                                  " values, the header declares " + std::to_string(vertex.properties.size()) +
                                  " properties" + lists);
            }
            store(values.data());
        }
    }
    // The elements after the vertices are not needed, but a file that ends inside them was cut off
    // (a download or copy that stopped): it is refused as truncated like any other, rather than read
    // as if it were whole. Skipping them costs a pass over the rest of the file, no parsing.
    for (std::size_t e = vertex_index + 1; e < header.elements.size(); ++e)
        skip_element(in, header.elements[e], binary, swap);
    // Data after the last element means a header that declares fewer elements than the file holds (a
    // count written before the data was complete, or two files run together): what was read is part
    // of the cloud, refused rather than read as if it were whole. Blank lines, or binary padding
    // shorter than one vertex record, are not data.
    const auto declared = [&] {
        std::string text;
        for (const PlyElement& element : header.elements)
            text += (text.empty() ? "" : ", ") + std::to_string(element.count) + " " + element.name;
        return " (the header declares " + text + " elements): the header does not describe the data";
    };
    if (binary) {
        if (in.request(std::max<std::size_t>(vertex.min_size, 1)))
            throw InvalidInput(in.name() + ": " + std::to_string(bytes_left(in)) + " bytes after the last element" +
                               declared());
    } else {
        std::string_view line;
        while (in.next_line(line))
            if (std::any_of(line.begin(), line.end(), [](char c) { return !kBlanks(c); }))
                fail_line(in, "data after the last element" + declared());
    }
    std::array<bool, 3> float32{};
    for (int a = 0; a < 3; ++a)
        float32[static_cast<std::size_t>(a)] =
            vertex.properties[static_cast<std::size_t>(layout.xyz[a])].type == PlyType::float32;
    record_float32_spacing(cloud, in.name(), float32);
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// PTX (Leica, FARO and other terrestrial scanners' export): scans one after another, each a header of
// columns, rows, the scanner position and axes and a 4x4 registration matrix, then columns x rows
// lines "x y z intensity [r g b]" in the scanner's frame, "0 0 0" where the laser saw nothing.

// The next line's numbers; false at the end of the input. Blank lines are skipped.
bool next_numbers(Input& in, std::vector<double>& values)
{
    std::string_view line;
    while (in.next_line(line)) {
        Tokens tokens(line, kBlanks);
        std::string_view token;
        values.clear();
        while (tokens.next(token))
            values.push_back(number_on_line(in, token));
        if (!values.empty())
            return true;
    }
    return false;
}

PointCloud read_ptx(Input& in, const ReadOptions& options)
{
    PointCloud cloud;
    std::vector<Rgba> colors;
    bool all_colored = options.keep_colors;
    std::vector<double> v;
    int scans = 0;
    for (int scan = 1; next_numbers(in, v); ++scan) {
        scans = scan;
        const std::string where = "scan " + std::to_string(scan);
        std::uint64_t size[2] = {0, 0};
        for (int k = 0; k < 2; ++k) {
            if (k > 0 && !next_numbers(in, v))
                throw IoError(in.name() + ": truncated: " + where + " header ends early");
            if (v.size() != 1 || !(v[0] >= 0 && v[0] <= 1e9) || v[0] != std::floor(v[0]))
                fail_line(in, "expected the " + where + (k == 0 ? " column" : " row") + " count");
            size[k] = static_cast<std::uint64_t>(v[0]);
        }
        double m[4][4];
        std::uint64_t matrix_line = 0;
        for (int row = 0; row < 8; ++row) {
            if (!next_numbers(in, v))
                throw IoError(in.name() + ": truncated: " + where + " header ends early");
            if (row == 4)
                matrix_line = in.line_number();
            const std::size_t expected = row < 4 ? 3 : 4;
            if (v.size() != expected)
                fail_line(in, "expected " + std::to_string(expected) + " numbers in the " + where + " header, found " +
                                  std::to_string(v.size()));
            if (row >= 4)
                std::copy(v.begin(), v.end(), m[row - 4]);
        }
        // The registration is a rigid motion: its 3x3 part must be a rotation (orthonormal rows). An
        // all-zero or otherwise degenerate matrix would collapse or distort the scan without a word.
        // Real files print the rotation with 6-8 digits, far within the tolerance.
        double worst = 0;
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const double dot = m[a][0] * m[b][0] + m[a][1] * m[b][1] + m[a][2] * m[b][2];
                worst = std::max(worst, std::abs(dot - (a == b ? 1.0 : 0.0)));
            }
        const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        const std::string matrix = in.name() + ": " + where + ": the registration matrix (line " +
                                   std::to_string(matrix_line) + ") is not a rigid motion: ";
        if (!(worst <= 1e-3)) {
            char detail[64];
            std::snprintf(detail, sizeof detail, "%.6g", det);
            throw InvalidInput(matrix + "its rotation part is not orthonormal (determinant " + detail + ")");
        }
        // Orthonormal with determinant -1 is a mirror image of the scan, and a last column other than
        // 0 0 0 1 a projective or rescaled matrix: neither is a registration (both were read as given
        // or ignored, QA round 28).
        if (det < 0)
            throw InvalidInput(matrix + "it mirrors the scan (determinant -1)");
        if (!(std::abs(m[0][3]) <= 1e-6 && std::abs(m[1][3]) <= 1e-6 && std::abs(m[2][3]) <= 1e-6 &&
              std::abs(m[3][3] - 1.0) <= 1e-6))
            throw InvalidInput(matrix + "its last column is not 0 0 0 1");
        // The scanner stands at the registration's translation (the scan's own origin).
        cloud.viewpoint = Vec3{m[3][0], m[3][1], m[3][2]};
        const std::uint64_t count = size[0] * size[1];
        for (std::uint64_t i = 0; i < count; ++i) {
            if (!next_numbers(in, v))
                throw IoError(in.name() + ": truncated: " + where + " has " + std::to_string(i) + " of " +
                              std::to_string(count) + " points");
            if (v.size() < 3)
                fail_line(in, "expected 3 coordinates, found " + std::to_string(v.size()));
            if (v[0] == 0 && v[1] == 0 && v[2] == 0)
                continue; // no return
            // Row vectors: [x y z 1] times the matrix, whose last row is the translation.
            Vec3 p;
            for (int axis = 0; axis < 3; ++axis)
                p[axis] = v[0] * m[0][axis] + v[1] * m[1][axis] + v[2] * m[2][axis] + m[3][axis];
            check_max_points(in, cloud.positions.size() + 1, options);
            cloud.positions.push_back(p);
            if (all_colored && v.size() == 7 && v[4] >= 0 && v[4] <= 255 && v[5] >= 0 && v[5] <= 255 &&
                v[6] >= 0 && v[6] <= 255)
                colors.push_back({static_cast<std::uint8_t>(std::lround(v[4])), static_cast<std::uint8_t>(std::lround(v[5])),
                                  static_cast<std::uint8_t>(std::lround(v[6])), 255});
            else if (all_colored) {
                all_colored = false; // one point without colour: the file is read without colours
                colors = {};
            }
        }
    }
    if (all_colored)
        cloud.colors = std::move(colors);
    if (scans > 1)
        cloud.viewpoint.reset(); // several scanner positions: none stands for all points
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// LAS (ASPRS LAS 1.0-1.4, uncompressed): airborne and terrestrial lidar's exchange format.

// Where the public header keeps what we read (the LAS specification's byte offsets).
constexpr std::size_t kLasHeaderMin = 227; // LAS 1.0-1.2; 1.3 adds 8 bytes, 1.4 adds 148
constexpr std::size_t kLasHeader13 = 235;
constexpr std::size_t kLasHeader14 = 375;

// Smallest point record of each point data format 0-10; records may carry extra bytes after it.
constexpr std::uint16_t kLasRecordSize[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
// Where red/green/blue start in the formats that have them, else 0.
constexpr std::uint16_t kLasColorOffset[11] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};

constexpr std::uint64_t kLasMaxRecordBytes = 16u << 20;
constexpr std::uint64_t kLasExtendedRecordHeader = 60; // LAS 1.4's extended variable-length record header
constexpr std::uint64_t kMaxLasWktBytes = 1u << 20;    // a WKT is a few kilobytes

// The CRS of the LASF_Projection records: the OGC WKT record (2112) when the header says WKT is
// authoritative or no EPSG code is given, else the EPSG code of the GeoTIFF keys (record 34735:
// ProjectedCSTypeGeoKey 3072, else GeographicTypeGeoKey 2048). Malformed records are ignored: the CRS
// only places the result on the globe, and the points themselves are still readable.
// The WKT of a LAS 1.4 extended record (LASF_Projection, 2112) from `start`, which the stream has not
// passed yet; "" if none among the first kMaxExtendedRecordsRead, or if the file ends first (the points
// before are whole). Records are 60-byte headers (2 reserved bytes, a 16-byte user id, the record id, a
// 64-bit length, a 32-byte description) and data.
std::string las_extended_wkt(Input& in, std::uint64_t start, std::uint32_t count, bool swap)
{
    constexpr std::uint32_t kMaxExtendedRecordsRead = 1024;
    if (start < in.offset() || !in.skip(start - in.offset()))
        return {};
    for (std::uint32_t k = 0; k < std::min(count, kMaxExtendedRecordsRead); ++k) {
        const char* header = in.take(kLasExtendedRecordHeader);
        if (!header)
            return {};
        const std::string user(header + 2, strnlen(header + 2, 16));
        const std::uint16_t id = load<std::uint16_t>(header + 18, swap);
        const std::uint64_t length = load<std::uint64_t>(header + 20, swap);
        if (user == "LASF_Projection" && id == 2112 && length <= kMaxLasWktBytes) {
            const char* data = in.take(static_cast<std::size_t>(length));
            if (!data)
                return {};
            return std::string(data, strnlen(data, static_cast<std::size_t>(length)));
        }
        if (!in.skip(length))
            return {};
    }
    return {};
}

std::string las_crs(const char* records, std::size_t size, std::uint32_t count, bool swap, bool wkt_flag)
{
    constexpr std::size_t kRecordHeader = 54;
    std::string wkt;
    unsigned projected = 0, geographic = 0;
    std::size_t at = 0;
    for (std::uint32_t k = 0; k < count && at + kRecordHeader <= size; ++k) {
        const std::string user(records + at + 2, strnlen(records + at + 2, 16));
        const std::uint16_t id = load<std::uint16_t>(records + at + 18, swap);
        const std::uint16_t length = load<std::uint16_t>(records + at + 20, swap);
        const char* data = records + at + kRecordHeader;
        at += kRecordHeader + length;
        if (at > size)
            break;
        if (user != "LASF_Projection")
            continue;
        if (id == 2112) {
            wkt.assign(data, strnlen(data, length));
        } else if (id == 34735 && length >= 8) {
            // GeoKeyDirectoryTag: a 4-short header whose last short is the key count, then 4 shorts per
            // key (id, location, count, value); location 0 means the value is the short itself.
            const std::size_t keys = std::min<std::size_t>(load<std::uint16_t>(data + 6, swap), (length - 8) / 8);
            for (std::size_t i = 0; i < keys; ++i) {
                const char* key = data + 8 + 8 * i;
                if (load<std::uint16_t>(key + 2, swap) != 0)
                    continue;
                const unsigned key_id = load<std::uint16_t>(key, swap);
                const unsigned value = load<std::uint16_t>(key + 6, swap);
                if (key_id == 3072)
                    projected = value;
                else if (key_id == 2048)
                    geographic = value;
            }
        }
    }
    // 32767 is GeoTIFF's "user-defined": the parameters are spread over further keys we do not read.
    const auto known = [](unsigned code) { return code > 0 && code < 32767; };
    if (!wkt.empty() && (wkt_flag || !known(projected)))
        return wkt;
    if (known(projected))
        return "EPSG:" + std::to_string(projected);
    if (known(geographic))
        return "EPSG:" + std::to_string(geographic);
    return {};
}

PointCloud read_las(Input& in, const ReadOptions& options)
{
    const char* header = in.take(kLasHeaderMin);
    if (!header) {
        if (in.request(4) && std::memcmp(in.data(), "LASF", 4) == 0)
            throw IoError(in.name() + ": truncated: the file ends inside the LAS header");
        throw InvalidInput(in.name() + ": not a LAS file (no 'LASF' signature)");
    }
    if (std::memcmp(header, "LASF", 4) != 0)
        throw InvalidInput(in.name() + ": not a LAS file (no 'LASF' signature)");
    const bool swap = !host_is_little_endian();
    const unsigned major = static_cast<unsigned char>(header[24]);
    const unsigned minor = static_cast<unsigned char>(header[25]);
    // What is needed of the header later is copied now: a later take() may move or reallocate the
    // buffer `header` points into.
    const std::uint32_t record_count = load<std::uint32_t>(header + 100, swap);
    const bool wkt_flag = (load<std::uint16_t>(header + 6, swap) & 0x10) != 0;
    const std::uint16_t header_size = load<std::uint16_t>(header + 94, swap);
    const std::uint32_t point_offset = load<std::uint32_t>(header + 96, swap);
    const unsigned format_byte = static_cast<unsigned char>(header[104]);
    const std::uint16_t record_size = load<std::uint16_t>(header + 105, swap);
    std::uint64_t count = load<std::uint32_t>(header + 107, swap);
    double scale[3], offset[3];
    for (int axis = 0; axis < 3; ++axis) {
        scale[axis] = load<double>(header + 131 + 8 * axis, swap);
        offset[axis] = load<double>(header + 155 + 8 * axis, swap);
    }
    const std::string version = std::to_string(major) + "." + std::to_string(minor);
    if (major != 1 || minor > 4)
        throw InvalidInput(in.name() + ": LAS version " + version + " is not supported (1.0 to 1.4 are)");
    // LASzip marks compressed point data by setting bit 7 (bit 6 in its early versions) of a valid
    // format, 0-10: a format byte that is not one of those with such bits (99, say) is no LAZ file.
    if ((format_byte & 0xC0) && (format_byte & 0x3F) <= 10)
        throw InvalidInput(in.name() + ": LAZ-compressed points; decompress first (laszip -i IN.laz -o OUT.las, "
                                       "or pdal translate)");
    const unsigned format = format_byte;
    if (format > 10)
        throw InvalidInput(in.name() + ": unsupported LAS point data format " + std::to_string(format) +
                           " (formats 0 to 10 are read)");
    if (record_size < kLasRecordSize[format])
        throw InvalidInput(in.name() + ": LAS point records of " + std::to_string(record_size) +
                           " bytes are shorter than format " + std::to_string(format) + " needs (" +
                           std::to_string(kLasRecordSize[format]) + ")");
    if (header_size < kLasHeaderMin || point_offset < header_size)
        throw InvalidInput(in.name() + ": malformed LAS header (header size " + std::to_string(header_size) +
                           ", points at byte " + std::to_string(point_offset) + ")");
    for (int axis = 0; axis < 3; ++axis)
        if (!std::isfinite(scale[axis]) || scale[axis] == 0 || !std::isfinite(offset[axis]))
            throw InvalidInput(in.name() + ": LAS scale or offset of " + std::string(1, static_cast<char>('x' + axis)) +
                               " is zero or not finite");
    // LAS 1.3 and 1.4 say where waveform data and extended records start, after the points: data
    // between the points' end and there, or the end of the file, is points the header does not count.
    std::uint64_t waveform_start = 0, evlr_start = 0;
    std::uint32_t evlr_count = 0;
    if (minor >= 3 && header_size >= kLasHeader13) {
        const std::size_t extended_size = (minor >= 4 && header_size >= kLasHeader14 ? kLasHeader14 : kLasHeader13) -
                                          kLasHeaderMin;
        const char* extended = in.take(extended_size);
        if (!extended)
            throw IoError(in.name() + ": truncated: the LAS header ends early");
        waveform_start = load<std::uint64_t>(extended, swap);
        // LAS 1.4 keeps a 64-bit count; the legacy 32-bit one must be 0 (formats 6-10, more than 2^32
        // points) or the same. Two different counts leave the file's extent unknown (QA round 28: a
        // legacy 5,000 and a 64-bit 1,000 read 1,000 of the 5,000 points without a word).
        if (extended_size == kLasHeader14 - kLasHeaderMin) {
            evlr_start = load<std::uint64_t>(extended + (235 - kLasHeaderMin), swap);
            evlr_count = load<std::uint32_t>(extended + (243 - kLasHeaderMin), swap);
            const std::uint64_t count64 = load<std::uint64_t>(extended + (247 - kLasHeaderMin), swap);
            if (count != 0 && count64 != 0 && count != count64)
                throw InvalidInput(in.name() + ": malformed LAS 1.4 header: its legacy point count " + std::to_string(count) +
                                   " differs from its 64-bit point count " + std::to_string(count64));
            if (count64 != 0)
                count = count64;
        }
    }
    // Formats 6-10 came with LAS 1.4, whose writers leave the legacy count 0 and give the 64-bit one,
    // which an older header has no room for (QA round 34: a 1.0 header with format 6 was refused as
    // "9000 bytes after the 0 points the header declares").
    if (format >= 6 && minor < 4 && count == 0)
        throw InvalidInput(in.name() + ": LAS point format " + std::to_string(format) + " is a LAS 1.4 format, but the header "
                           "says version " + version + " and has no 1.4 point count (its legacy count is 0)");
    check_declared_points(in, count, options);
    // Before allocating anything, check that an uncompressed file can hold what the header declares.
    const std::uint64_t needed = saturating_add(point_offset, saturating_mul(count, record_size));
    if (in.file_size() > 0 && needed > in.file_size())
        throw IoError(in.name() + ": truncated: the header declares " + std::to_string(count) + " points (" +
                      std::to_string(needed) + " bytes) but the file has " + std::to_string(in.file_size()) + " bytes");
    // LAS 1.4's extended records follow the points (QA round 34: records said to start inside the
    // points were accepted).
    if (evlr_count > 0) {
        if (evlr_start < needed)
            throw InvalidInput(in.name() + ": malformed LAS 1.4 header: its " + std::to_string(evlr_count) +
                               " extended records start at byte " + std::to_string(evlr_start) + ", before the point data ends (at byte " +
                               std::to_string(needed) + ")");
        // Past the end they start at: a header that does not describe the file. (Records cut short after
        // the points leave the points whole: they are read, without those records; QA round 35.)
        if (in.file_size() > 0 && evlr_start > in.file_size())
            throw IoError(in.name() + ": truncated: the header places " + std::to_string(evlr_count) +
                          " extended records at byte " + std::to_string(evlr_start) + " but the file has " +
                          std::to_string(in.file_size()) + " bytes");
    }
    // The variable-length records between the header and the points may say where the points are
    // on the Earth; a region beyond kLasMaxRecordBytes (waveform tables and the like) is not searched.
    std::string crs;
    const std::uint64_t record_bytes = point_offset - header_size;
    if (in.offset() <= header_size && in.skip(header_size - in.offset()) && record_bytes <= kLasMaxRecordBytes) {
        const char* records = in.take(static_cast<std::size_t>(record_bytes));
        if (!records)
            throw IoError(in.name() + ": truncated: the file ends before its point data");
        crs = las_crs(records, static_cast<std::size_t>(record_bytes), record_count, swap, wkt_flag);
    }
    if (!in.skip(point_offset - in.offset()))
        throw IoError(in.name() + ": truncated: the file ends before its point data");

    PointCloud cloud;
    cloud.crs = std::move(crs);
    reserve_capped(cloud, count, in.file_size() > 0 ? SIZE_MAX : kReserveCap, false);
    const std::uint16_t color_offset = options.keep_colors ? kLasColorOffset[format] : 0;
    std::vector<std::array<std::uint16_t, 3>> colors16;
    bool colors_16_bit = false;
    for (std::uint64_t i = 0; i < count; ++i) {
        const char* record = in.take(record_size);
        if (!record)
            throw IoError(in.name() + ": truncated: " + std::to_string(i) + " of " + std::to_string(count) +
                          " points");
        // Withheld points and points classified as noise are not part of the surface.
        const unsigned char flags = static_cast<unsigned char>(record[15]);
        const bool withheld = format < 6 ? (flags & 0x80) != 0 : (flags & 0x04) != 0;
        const unsigned classification = format < 6 ? (flags & 0x1Fu) : static_cast<unsigned char>(record[16]);
        if (withheld || classification == 7 || classification == 18)
            continue;
        Vec3 p;
        for (int axis = 0; axis < 3; ++axis)
            p[axis] = load<std::int32_t>(record + 4 * axis, swap) * scale[axis] + offset[axis];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw InvalidInput(in.name() + ": point " + std::to_string(i) + " is out of range after scaling");
        cloud.positions.push_back(p);
        if (color_offset > 0) {
            std::array<std::uint16_t, 3> c;
            for (int k = 0; k < 3; ++k) {
                c[static_cast<std::size_t>(k)] = load<std::uint16_t>(record + color_offset + 2 * k, swap);
                colors_16_bit = colors_16_bit || c[static_cast<std::size_t>(k)] > 255;
            }
            colors16.push_back(c);
        }
    }
    // A point count lower than the file holds would read part of the cloud: refused like the PLY and
    // PCD readers' data after the declared points (QA round 28: a legacy count of 1,000 read 1,000 of
    // 5,000 points). What may follow the points starts where the header says; padding shorter than a
    // point record is not data.
    std::uint64_t next = 0; // where the next declared data starts; 0: nothing declared, the file's end
    for (const std::uint64_t start : {waveform_start, evlr_start})
        if (start >= in.offset() && (next == 0 || start < next))
            next = start;
    if ((next == 0 || next - in.offset() >= record_size) && in.request(record_size)) {
        const std::uint64_t rest = next != 0 && in.file_size() > 0 ? std::min(next, in.file_size()) - in.offset()
                                                                    : bytes_left(in);
        throw InvalidInput(in.name() + ": " + std::to_string(rest) + " bytes after the " + std::to_string(count) +
                           " points the header declares: the header does not describe the data");
    }
    // A LAS 1.4 file may keep its WKT in an extended record, after the points: read when the records
    // before the points gave none (or gave GeoTIFF keys the WKT bit says not to use).
    if (evlr_count > 0 && (cloud.crs.empty() || (wkt_flag && cloud.crs.rfind("EPSG:", 0) == 0)))
        if (std::string wkt = las_extended_wkt(in, evlr_start, evlr_count, swap); !wkt.empty())
            cloud.crs = std::move(wkt);
    if (count > 0 && cloud.positions.empty())
        throw InvalidInput(in.name() + ": no points: all " + std::to_string(count) +
                           " are withheld or classified as noise (classes 7 and 18), which are left out");
    // The specification asks for 16-bit colours, but many writers store 0-255 values: any value above
    // 255 means the file uses the full range.
    for (const auto& c : colors16)
        cloud.colors.push_back({static_cast<std::uint8_t>(colors_16_bit ? c[0] >> 8 : c[0]),
                                static_cast<std::uint8_t>(colors_16_bit ? c[1] >> 8 : c[1]),
                                static_cast<std::uint8_t>(colors_16_bit ? c[2] >> 8 : c[2]), 255});
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// PCD (the Point Cloud Library's format; robotics and depth cameras): an ASCII header, then the points
// as text, as packed binary records, or LZF-compressed field by field. Organized clouds (depth images)
// mark pixels without a measurement with NaN coordinates: those points are left out, as PTX's "0 0 0".

// Largest binary PCD point record read (see read_pcd_header).
constexpr std::uint64_t kMaxPcdRecordBytes = std::uint64_t{1} << 16;

struct PcdField
{
    std::string name;
    char type = 'F';             // F float, I signed, U unsigned
    std::size_t size = 4;        // bytes of one element
    std::uint64_t count = 1;     // elements
    std::size_t offset = 0;      // in a binary record (padding fields "_" included)
    std::uint64_t column = 0;    // first value of the field on an ASCII line
};

enum class PcdData { ascii, binary, compressed };

struct PcdHeader
{
    std::vector<PcdField> fields;
    std::uint64_t points = 0;
    PcdData data = PcdData::ascii;
    std::size_t record_size = 0;   // bytes per point, padding included
    std::size_t packed_size = 0;   // bytes per point in compressed data (padding fields are not stored)
    std::uint64_t values = 0;      // numbers per ASCII line
    int x = -1, y = -1, z = -1, rgb = -1;
    std::optional<Vec3> viewpoint; // the sensor's position, when the file tells it
};

std::uint64_t pcd_number(const Input& in, std::string_view token, std::uint64_t largest)
{
    std::uint64_t value = 0;
    if (!parse_count(token, value) || value > largest)
        fail_line(in, quote_token(token) + " is not a count (0.." + std::to_string(largest) + ")");
    return value;
}

PcdHeader read_pcd_header(Input& in)
{
    PcdHeader h;
    std::vector<std::string_view> tokens;
    std::vector<std::size_t> sizes;
    std::string types;
    std::vector<std::uint64_t> counts;
    std::uint64_t width = 0, height = 1, points = 0;
    bool have_width = false, have_points = false, have_data = false;
    std::optional<Vec3> viewpoint;
    std::string_view line;
    while (!have_data && in.next_line(line)) {
        Tokens split(line, kBlanks);
        std::string_view keyword, token;
        if (!split.next(keyword))
            continue; // blank or "# .PCD v0.7" comment
        tokens.clear();
        while (split.next(token))
            tokens.push_back(token);
        if (keyword == "VERSION")
            continue;
        if (keyword == "VIEWPOINT") {
            // tx ty tz qw qx qy qz: where the sensor stood. PCL does not move the points by it.
            if (tokens.size() != 7)
                fail_line(in, "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
            Vec3 t;
            for (int k = 0; k < 3; ++k)
                t[k] = number_on_line(in, tokens[static_cast<std::size_t>(k)]);
            viewpoint = t;
            continue;
        }
        if (keyword == "FIELDS" || keyword == "COLUMNS") {
            for (std::string_view name : tokens)
                h.fields.push_back({std::string(name)});
        } else if (keyword == "SIZE") {
            for (std::string_view t : tokens) {
                const std::uint64_t s = pcd_number(in, t, 8);
                if (s != 1 && s != 2 && s != 4 && s != 8)
                    fail_line(in, "field size " + std::string(t) + " is not 1, 2, 4 or 8");
                sizes.push_back(static_cast<std::size_t>(s));
            }
        } else if (keyword == "TYPE") {
            for (std::string_view t : tokens) {
                if (t != "F" && t != "I" && t != "U")
                    fail_line(in, "field type " + quote_token(t) + " is not F, I or U");
                types.push_back(t[0]);
            }
        } else if (keyword == "COUNT") {
            for (std::string_view t : tokens) {
                counts.push_back(pcd_number(in, t, 1u << 20));
                if (counts.back() == 0)
                    fail_line(in, "a field count of 0");
            }
        } else if (keyword == "WIDTH" || keyword == "HEIGHT" || keyword == "POINTS") {
            if (tokens.size() != 1)
                fail_line(in, std::string(keyword) + " needs one number");
            const std::uint64_t value = pcd_number(in, tokens[0], std::uint64_t{1} << 40);
            if (keyword == "WIDTH") {
                width = value;
                have_width = true;
            } else if (keyword == "HEIGHT") {
                height = value;
            } else {
                points = value;
                have_points = true;
            }
        } else if (keyword == "DATA") {
            if (tokens.size() != 1 || (tokens[0] != "ascii" && tokens[0] != "binary" && tokens[0] != "binary_compressed"))
                fail_line(in, "DATA must be ascii, binary or binary_compressed");
            h.data = tokens[0] == "ascii" ? PcdData::ascii : tokens[0] == "binary" ? PcdData::binary : PcdData::compressed;
            have_data = true;
        } else {
            fail_line(in, quote_token(keyword) + " is not a PCD header line");
        }
    }
    if (!have_data)
        throw IoError(in.name() + ": truncated: the PCD header ends without a DATA line");
    const std::size_t n = h.fields.size();
    if (n == 0 || sizes.size() != n || types.size() != n || (!counts.empty() && counts.size() != n))
        throw InvalidInput(in.name() + ": malformed PCD header: FIELDS, SIZE, TYPE and COUNT must name the same " +
                           "number of fields (" + std::to_string(n) + ", " + std::to_string(sizes.size()) + ", " +
                           std::to_string(types.size()) + ", " + std::to_string(counts.empty() ? n : counts.size()) + ")");
    if (!have_width && !have_points)
        throw InvalidInput(in.name() + ": malformed PCD header: neither WIDTH nor POINTS");
    const std::uint64_t grid = saturating_mul(width, height);
    if (have_width && have_points && grid != points)
        throw InvalidInput(in.name() + ": malformed PCD header: POINTS " + std::to_string(points) + " but WIDTH x HEIGHT = " +
                           std::to_string(width) + " x " + std::to_string(height));
    h.points = have_points ? points : grid;
    // Every PCL writer puts a VIEWPOINT line, the origin by default: it means the sensor only for an
    // organized cloud (a depth image, taken from the camera's origin) or when it was set.
    if (viewpoint && (height > 1 || *viewpoint != Vec3{0, 0, 0}))
        h.viewpoint = viewpoint;
    std::uint64_t record = 0, packed = 0, values = 0;
    for (std::size_t i = 0; i < n; ++i) {
        PcdField& f = h.fields[i];
        f.type = types[i];
        f.size = sizes[i];
        f.count = counts.empty() ? 1 : counts[i];
        if (f.type == 'F' && f.size != 4 && f.size != 8)
            throw InvalidInput(in.name() + ": malformed PCD header: float field " + f.name + " of size " + std::to_string(f.size));
        f.offset = static_cast<std::size_t>(record);
        f.column = values;
        record += f.size * f.count;
        if (f.name != "_")
            packed += f.size * f.count;
        values += f.count;
        // A field read twice (two clouds' headers run together, a copy of x kept as "x"): which one the
        // points are would be a guess (QA round 28: the second x, all zeros, flattened a sphere).
        if ((f.name == "x" && h.x >= 0) || (f.name == "y" && h.y >= 0) || (f.name == "z" && h.z >= 0) ||
            ((f.name == "rgb" || f.name == "rgba") && f.size == 4 && h.rgb >= 0))
            throw InvalidInput(in.name() + ": malformed PCD header: two fields are named " + f.name +
                               (f.name == "rgba" || f.name == "rgb" ? " (or rgb and rgba)" : ""));
        const int index = static_cast<int>(i);
        if (f.name == "x") h.x = index;
        if (f.name == "y") h.y = index;
        if (f.name == "z") h.z = index;
        if ((f.name == "rgb" || f.name == "rgba") && f.size == 4)
            h.rgb = index;
    }
    if (h.x < 0 || h.y < 0 || h.z < 0)
        throw InvalidInput(in.name() + ": the PCD fields have no x, y and z");
    for (int axis : {h.x, h.y, h.z})
        if (h.fields[static_cast<std::size_t>(axis)].size == 8 && h.fields[static_cast<std::size_t>(axis)].type != 'F')
            throw InvalidInput(in.name() + ": 64-bit integer coordinates are not read");
    // A binary point is read as one contiguous record: a header whose SIZE x COUNT make a record
    // larger than any real descriptor (PCL's largest, VFH, is 1.2 KB) would otherwise size the read
    // buffer by a number it made up, unchecked when the file size is unknown (gzip).
    if (record > kMaxPcdRecordBytes)
        throw InvalidInput(in.name() + ": malformed PCD header: a point of " + std::to_string(record) +
                           " bytes (the fields' SIZE x COUNT), more than the " + std::to_string(kMaxPcdRecordBytes) +
                           " this reader takes");
    h.record_size = static_cast<std::size_t>(record);
    h.packed_size = static_cast<std::size_t>(packed);
    h.values = values;
    return h;
}

PlyType pcd_type(const PcdField& f)
{
    if (f.type == 'F')
        return f.size == 4 ? PlyType::float32 : PlyType::float64;
    const bool is_signed = f.type == 'I';
    switch (f.size) {
    case 1: return is_signed ? PlyType::int8 : PlyType::uint8;
    case 2: return is_signed ? PlyType::int16 : PlyType::uint16;
    default: return is_signed ? PlyType::int32 : PlyType::uint32;
    }
}

// PCL packs a colour into 32 bits, 0xAARRGGBB, stored in a float ("rgb") or an unsigned ("rgba").
Rgba pcd_color(std::uint32_t bits)
{
    return {static_cast<std::uint8_t>(bits >> 16), static_cast<std::uint8_t>(bits >> 8), static_cast<std::uint8_t>(bits), 255};
}

// Adds one point unless a coordinate is NaN (no measurement); other non-finite values are errors.
void add_pcd_point(const Input& in, const Vec3& p, const Rgba* color, PointCloud& cloud, std::uint64_t index)
{
    if (std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z))
        return;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw InvalidInput(in.name() + ": point " + std::to_string(index) + " has an infinite coordinate");
    cloud.positions.push_back(p);
    if (color)
        cloud.colors.push_back(*color);
}

// LZF (Marc Lehmann's format, as PCL writes it): a control byte below 32 is a run of control + 1
// literal bytes; above, a back-reference of length (control >> 5) + 2 (7 meaning "plus the next byte")
// at distance ((control & 31) << 8 | next byte) + 1. False when the data is not valid LZF or does not
// decompress to exactly out.size() bytes.
bool lzf_decompress(const std::vector<unsigned char>& in, std::vector<unsigned char>& out)
{
    std::size_t ip = 0, op = 0;
    while (ip < in.size()) {
        const unsigned control = in[ip++];
        if (control < 32) {
            const std::size_t length = control + 1;
            if (in.size() - ip < length || out.size() - op < length)
                return false;
            std::memcpy(out.data() + op, in.data() + ip, length);
            ip += length;
            op += length;
            continue;
        }
        std::size_t length = control >> 5;
        if (length == 7) {
            if (ip >= in.size())
                return false;
            length += in[ip++];
        }
        if (ip >= in.size())
            return false;
        const std::size_t distance = ((static_cast<std::size_t>(control & 31) << 8) | in[ip++]) + 1;
        length += 2;
        if (distance > op || out.size() - op < length)
            return false;
        for (std::size_t k = 0; k < length; ++k, ++op) // may overlap: byte by byte
            out[op] = out[op - distance];
    }
    return op == out.size();
}

PointCloud read_pcd(Input& in, const ReadOptions& options)
{
    const PcdHeader h = read_pcd_header(in);
    check_declared_points(in, h.points, options);
    const bool colors = options.keep_colors && h.rgb >= 0;
    const PcdField& fx = h.fields[static_cast<std::size_t>(h.x)];
    const PcdField& fy = h.fields[static_cast<std::size_t>(h.y)];
    const PcdField& fz = h.fields[static_cast<std::size_t>(h.z)];
    PointCloud cloud;
    cloud.viewpoint = h.viewpoint;
    const std::array<bool, 3> float32{fx.type == 'F' && fx.size == 4, fy.type == 'F' && fy.size == 4,
                                      fz.type == 'F' && fz.size == 4};
    if (h.data == PcdData::ascii) {
        reserve_capped(cloud, h.points, kReserveCap, colors);
        std::vector<std::string_view> values;
        std::string_view line, token;
        for (std::uint64_t i = 0; i < h.points;) {
            if (!in.next_line(line))
                throw IoError(in.name() + ": truncated: " + std::to_string(i) + " of " + std::to_string(h.points) + " points");
            Tokens tokens(line, kBlanks);
            values.clear();
            while (values.size() < h.values && tokens.next(token))
                values.push_back(token);
            if (values.empty())
                continue;
            std::size_t found = values.size();
            if (found == h.values)
                while (tokens.next(token))
                    ++found;
            // Fewer or more values than FIELDS x COUNT declare (a 3-value normal declared with COUNT
            // 1, say): the columns would be read shifted.
            if (found != h.values)
                fail_line(in, "expected " + std::to_string(h.values) + " values, found " + std::to_string(found));
            const auto coordinate = [&](const PcdField& f) {
                const std::string_view t = values[f.column];
                double v = 0;
                const Parsed parsed = parse_number(t, v);
                if (parsed == Parsed::not_a_number)
                    fail_line(in, quote_token(t) + " is not a number");
                if (parsed == Parsed::not_finite && !std::isnan(v))
                    v = std::numeric_limits<double>::infinity(); // out of range (v untouched): refused with the point
                return v; // NaN: no measurement; checked with the point
            };
            const Vec3 p{coordinate(fx), coordinate(fy), coordinate(fz)};
            Rgba color{};
            if (colors) {
                // PCL writes the packed colour as an unsigned integer even in a float field (opaque
                // colours are NaN as floats); older versions wrote the float, whose bits are the colour.
                const PcdField& f = h.fields[static_cast<std::size_t>(h.rgb)];
                std::uint64_t bits = 0;
                if (!parse_count(values[f.column], bits) || bits > 0xFFFFFFFFu) {
                    const float packed = static_cast<float>(coordinate(f));
                    std::uint32_t float_bits = 0xFFFFFFFFu; // a NaN colour is lost: white
                    if (std::isfinite(packed))
                        std::memcpy(&float_bits, &packed, sizeof float_bits);
                    bits = float_bits;
                }
                color = pcd_color(static_cast<std::uint32_t>(bits));
            }
            add_pcd_point(in, p, colors ? &color : nullptr, cloud, i);
            ++i;
        }
        // Lines after the declared points mean a POINTS (and WIDTH x HEIGHT) lower than the data (100
        // declared, 500 written): what was read is part of the cloud, refused rather than read as if it
        // were whole. Blank lines and comments are not data.
        while (in.next_line(line)) {
            Tokens tokens(line, kBlanks);
            if (tokens.next(token))
                fail_line(in, "data after the " + std::to_string(h.points) +
                                  " points the header declares: the header does not describe the data");
        }
        record_float32_spacing(cloud, in.name(), float32);
        return cloud;
    }
    const bool swap = !host_is_little_endian();
    const auto record_point = [&](const char* x, const char* y, const char* z, const char* rgb, std::uint64_t i) {
        const Vec3 p{decode(x, pcd_type(fx), swap), decode(y, pcd_type(fy), swap), decode(z, pcd_type(fz), swap)};
        Rgba color{};
        if (colors)
            color = pcd_color(load<std::uint32_t>(rgb, swap));
        add_pcd_point(in, p, colors ? &color : nullptr, cloud, i);
    };
    if (h.data == PcdData::binary) {
        const std::uint64_t bytes = saturating_mul(h.points, h.record_size);
        if (in.file_size() > 0 && bytes > in.file_size() - std::min(in.file_size(), in.offset()))
            throw IoError(in.name() + ": truncated: the header declares " + std::to_string(h.points) + " points of " +
                          std::to_string(h.record_size) + " bytes, more than the file holds");
        reserve_capped(cloud, h.points, kReserveCap, colors);
        for (std::uint64_t i = 0; i < h.points; ++i) {
            const char* r = in.take(h.record_size);
            if (!r)
                throw IoError(in.name() + ": truncated: " + std::to_string(i) + " of " + std::to_string(h.points) + " points");
            record_point(r + fx.offset, r + fy.offset, r + fz.offset,
                         colors ? r + h.fields[static_cast<std::size_t>(h.rgb)].offset : nullptr, i);
        }
        // Records after the declared points, as in ASCII; padding shorter than a record is not data.
        if (in.request(std::max<std::size_t>(h.record_size, 1)))
            throw InvalidInput(in.name() + ": " + std::to_string(bytes_left(in)) + " bytes after the " +
                               std::to_string(h.points) + " points the header declares: the header does not " +
                               "describe the data");
        record_float32_spacing(cloud, in.name(), float32);
        return cloud;
    }
    // binary_compressed: two 32-bit sizes, then the LZF data of every field's values in turn.
    const char* sizes = in.take(8);
    if (!sizes)
        throw IoError(in.name() + ": truncated: the compressed PCD data has no sizes");
    const std::uint32_t compressed = load<std::uint32_t>(sizes, swap), uncompressed = load<std::uint32_t>(sizes + 4, swap);
    if (uncompressed != saturating_mul(h.points, h.packed_size))
        throw InvalidInput(in.name() + ": the compressed PCD data unpacks to " + std::to_string(uncompressed) +
                           " bytes, not the " + std::to_string(h.points) + " x " + std::to_string(h.packed_size) +
                           " the header declares");
    // One LZF byte unpacks to at most about 88 (a 3-byte reference copies up to 264): anything more is
    // not LZF, and would otherwise size an allocation by a number the file made up.
    if (uncompressed > 100 * std::uint64_t{compressed} + 64)
        throw InvalidInput(in.name() + ": the compressed PCD data cannot unpack to " + std::to_string(uncompressed) + " bytes");
    std::vector<unsigned char> packed;
    for (std::uint64_t left = compressed; left > 0;) {
        const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(left, kBufferSize));
        const char* chunk = in.take(step);
        if (!chunk)
            throw IoError(in.name() + ": truncated: the compressed PCD data ends early");
        packed.insert(packed.end(), chunk, chunk + step);
        left -= step;
    }
    // Data after the compressed block, as after binary records (padding shorter than a point is not
    // data): a second cloud run together with this one, or a header that does not describe the file.
    // It was ignored without a word (QA round 29) though ASCII and binary data refuse it.
    if (in.request(std::max<std::size_t>(h.packed_size, 1)))
        throw InvalidInput(in.name() + ": " + std::to_string(bytes_left(in)) + " bytes after the compressed data of the " +
                           std::to_string(h.points) + " points the header declares: the header does not describe the data");
    std::vector<unsigned char> data(uncompressed);
    if (!lzf_decompress(packed, data))
        throw InvalidInput(in.name() + ": corrupt compressed PCD data (not LZF, or not " + std::to_string(uncompressed) + " bytes)");
    // Where each stored field's values start: fields follow one another, padding fields are not stored.
    std::vector<std::size_t> start(h.fields.size(), 0);
    std::size_t at = 0;
    for (std::size_t k = 0; k < h.fields.size(); ++k)
        if (h.fields[k].name != "_") {
            start[k] = at;
            at += static_cast<std::size_t>(h.points) * h.fields[k].size * h.fields[k].count;
        }
    const auto element = [&](int field, std::uint64_t i) {
        const PcdField& f = h.fields[static_cast<std::size_t>(field)];
        return reinterpret_cast<const char*>(data.data()) + start[static_cast<std::size_t>(field)] + i * f.size * f.count;
    };
    cloud.positions.reserve(static_cast<std::size_t>(h.points));
    for (std::uint64_t i = 0; i < h.points; ++i)
        record_point(element(h.x, i), element(h.y, i), element(h.z, i), colors ? element(h.rgb, i) : nullptr, i);
    record_float32_spacing(cloud, in.name(), float32);
    return cloud;
}

// ---------------------------------------------------------------------------------------------------
// Stanford scan lists (.conf): the raw range scans of one object and how each was aligned.

std::array<std::array<double, 3>, 3> placement_rotation(const ScanPlacement& placement)
{
    // The rotation of the conjugate quaternion (-x, -y, -z, w); see ScanPlacement.
    const double x = -placement.rotation[0], y = -placement.rotation[1], z = -placement.rotation[2];
    const double w = placement.rotation[3];
    return {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
             {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
             {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
}

// Appends the points of one more file to those read so far, refusing more than max_points together.
// `what` names the file or list at fault, `together` says whose points they are.
void append_within_limit(PointCloud& cloud, PointCloud part, const ReadOptions& options, const std::string& what,
                         const std::string& together)
{
    append(cloud, std::move(part));
    if (options.max_points > 0 && cloud.size() > options.max_points)
        throw InvalidInput(what + ": " + together + " hold " + std::to_string(cloud.size()) +
                           " points together so far, more than max_points " + std::to_string(options.max_points));
}

// ---------------------------------------------------------------------------------------------------
// The format by extension

enum class Format { ply, columns, pts, ptx, obj, off, las, pcd, conf };

Format format_of(const fs::path& path, const std::string& name)
{
    std::string ext = lower_extension(path);
    if (ext == ".gz")
        ext = lower_extension(path.stem());
    if (ext == ".ply")
        return Format::ply;
    if (ext == ".pts")
        return Format::pts;
    if (ext == ".las")
        return Format::las;
    if (ext == ".ptx")
        return Format::ptx;
    if (ext == ".pcd")
        return Format::pcd;
    if (ext == ".laz")
        throw InvalidInput(name + ": LAZ (compressed LAS) is not read; decompress first (laszip -i IN.laz -o "
                                  "OUT.las, or pdal translate)");
    if (ext == ".xyz" || ext == ".txt" || ext == ".csv")
        return Format::columns;
    if (ext == ".obj")
        return Format::obj;
    if (ext == ".off")
        return Format::off;
    if (ext == ".conf")
        return Format::conf;
    throw InvalidInput(name + ": unknown point file extension " + (ext.empty() ? "(none)" : quote_token(ext)) +
                       "; expected .ply, .las, .ptx, .pcd, .xyz, .pts, .txt, .csv, .obj, .off (optionally .gz) or a .conf "
                       "scan list");
}

// A file without an extension (a pipe such as <(zcat scan.ply.gz), which is /dev/fd/63, or a download
// saved without one) is read when it opens with a header that names its format: "ply", LAS's "LASF",
// PCD's "# .PCD" or "VERSION". Nothing is guessed for text columns: any text would pass for them.
std::optional<Format> format_by_header(Input& in)
{
    if (!in.request(1))
        return std::nullopt;
    in.request(8); // fewer at the end of a short input
    const std::string_view start(in.data(), in.available());
    const auto opens = [&](std::string_view magic) { return start.substr(0, magic.size()) == magic; };
    if (opens("ply\n") || opens("ply\r") || opens("ply "))
        return Format::ply;
    if (opens("LASF"))
        return Format::las;
    if (opens("# .PCD") || opens("VERSION"))
        return Format::pcd;
    return std::nullopt;
}

// `allow_empty`: a scan of a list may have seen nothing (read_conf leaves it out).
PointCloud read_format(Input& in, Format format, const std::string& name, const ReadOptions& options, bool allow_empty = false)
{
    PointCloud cloud;
    switch (format) {
    case Format::conf: break; // read by read_conf: a list of files, not points
    case Format::ply: cloud = read_ply(in, options); break;
    case Format::columns: cloud = read_columns(in, options, false); break;
    case Format::pts: cloud = read_columns(in, options, true); break;
    case Format::las: cloud = read_las(in, options); break;
    case Format::ptx: cloud = read_ptx(in, options); break;
    case Format::pcd: cloud = read_pcd(in, options); break;
    case Format::obj: cloud = read_obj(in, options); break;
    case Format::off: cloud = read_off(in, options); break;
    }
    if (allow_empty && cloud.empty())
        return cloud;
    validate(cloud, name);
    recenter(cloud);
    return cloud;
}

// The points of a Stanford scan list (.conf), each scan read by its format and placed (see above).
PointCloud read_conf(const fs::path& path, const std::string& name, const ReadOptions& options)
{
    PointCloud cloud;
    std::size_t read = 0;
    for (const ScanPlacement& scan : read_scan_list(path)) {
        if (scan.missing) {
            if (options.skip_missing_scans)
                continue;
            throw IoError(name + ": line " + std::to_string(scan.line) + ": " + scan.path.string() +
                          ": no such file (to read the scans that exist: --skip-missing-scans, or "
                          "ReadOptions::skip_missing_scans through the API)");
        }
        // A scan's error names the list and its line too: the list is what the user gave.
        const std::string where = name + ": line " + std::to_string(scan.line) + ": ";
        PointCloud part;
        try {
            // A scan that saw nothing adds nothing (QA round 77: a valid PLY of 0 vertices failed the
            // whole list, --skip-missing-scans or not); a list of nothing but such scans has no points.
            Input in(scan.path, scan.path.string(), options.pipe_wait_seconds);
            part = read_format(in, format_of(scan.path, scan.path.string()), scan.path.string(), options, true);
        } catch (const IoError& e) {
            throw IoError(where + e.what());
        } catch (const InvalidInput& e) {
            throw InvalidInput(where + e.what());
        }
        ++read;
        if (part.empty())
            continue;
        place_scan(part, scan);
        append_within_limit(cloud, std::move(part), options, name, "its scans");
    }
    if (read == 0)
        throw IoError(name + ": none of the scans it lists exists");
    // Each scan was checked alone; placed, they may lie farther apart than a mesh can span (a
    // translation of 1e300 passed every check and failed in the build, naming no file).
    validate(cloud, name);
    return cloud;
}

} // namespace

PointCloud read_points(const std::filesystem::path& path, const ReadOptions& options)
{
    const std::string name = path.string();
    if (lower_extension(path).empty()) {
        Input in(path, name, options.pipe_wait_seconds);
        if (const std::optional<Format> format = format_by_header(in))
            return read_format(in, *format, name, options);
        throw InvalidInput(name + ": no file extension, and its first bytes are no PLY, LAS or PCD header; name it by "
                                  "its format (.xyz .pts .txt .csv .obj .off .ptx, optionally .gz)");
    }
    const Format format = format_of(path, name);
    if (format == Format::conf) {
        PointCloud cloud = read_conf(path, name, options);
        recenter(cloud);
        return cloud;
    }
    Input in(path, name, options.pipe_wait_seconds);
    return read_format(in, format, name, options);
}

bool is_scan_list(const std::filesystem::path& path)
{
    try {
        return format_of(path, path.string()) == Format::conf;
    } catch (const InvalidInput&) {
        return false; // no point file either: read_points says so
    }
}

std::vector<ScanPlacement> read_scan_list(const std::filesystem::path& path)
{
    const std::string name = path.string();
    Input in(path, name);
    std::vector<ScanPlacement> scans;
    std::string_view line;
    while (in.next_line(line)) {
        Tokens tokens(line, kBlanks);
        std::string_view keyword;
        if (!tokens.next(keyword) || keyword == "camera")
            continue; // blank, comment, or the viewer's camera
        if (keyword != "bmesh" && keyword != "mesh")
            fail_line(in, quote_token(keyword) + " is not a scan list line (expected bmesh, mesh or camera)");
        ScanPlacement scan;
        scan.line = in.line_number();
        std::string_view file;
        if (!tokens.next(file))
            fail_line(in, "expected FILE tx ty tz qx qy qz qw after " + std::string(keyword));
        double values[7];
        for (int k = 0; k < 7; ++k) {
            std::string_view token;
            if (!tokens.next(token))
                fail_line(in, "expected 7 numbers after the file name (tx ty tz qx qy qz qw), found " + std::to_string(k));
            values[k] = number_on_line(in, token);
        }
        std::string_view extra;
        if (tokens.next(extra))
            fail_line(in, "unexpected " + quote_token(extra) + " after the quaternion");
        scan.path = path.parent_path() / fs::path(std::string(file));
        std::error_code directory_error;
        if (fs::is_directory(scan.path, directory_error))
            fail_line(in, scan.path.string() + " is a directory, not a scan");
        Format kind = Format::ply;
        try {
            kind = format_of(scan.path, scan.path.string());
        } catch (const InvalidInput& e) {
            fail_line(in, e.what());
        }
        if (kind == Format::conf)
            fail_line(in, "a scan list may not list another scan list");
        scan.translation = {values[0], values[1], values[2]};
        const double length = std::sqrt(values[3] * values[3] + values[4] * values[4] + values[5] * values[5] +
                                        values[6] * values[6]);
        // Six printed digits leave a length within 1e-5 of one, three (a list edited by hand) within
        // about 2e-3 (QA round 77: 1.001 was refused); 1% off is a typing error, not a rotation.
        if (!(std::abs(length - 1) <= 1e-2))
            fail_line(in, "the quaternion has length " + std::to_string(length) + ", not 1");
        for (int k = 0; k < 4; ++k)
            scan.rotation[k] = values[3 + k] / length;
        std::error_code ec;
        scan.missing = !fs::exists(scan.path, ec) && !ec; // an access error is reported by the read itself
        scans.push_back(std::move(scan));
    }
    if (scans.empty())
        throw InvalidInput(name + ": lists no scan (no bmesh or mesh line)");
    return scans;
}

void place_scan(PointCloud& cloud, const ScanPlacement& placement)
{
    const auto r = placement_rotation(placement);
    const auto rotate = [&r](const Vec3& p) {
        return Vec3{r[0][0] * p.x + r[0][1] * p.y + r[0][2] * p.z, r[1][0] * p.x + r[1][1] * p.y + r[1][2] * p.z,
                    r[2][0] * p.x + r[2][1] * p.y + r[2][2] * p.z};
    };
    // R (origin + p) + t = R p + (R origin + t): the whole part of the last term stays the origin.
    const Vec3 moved = rotate(cloud.origin) + placement.translation;
    const Vec3 origin{std::round(moved.x), std::round(moved.y), std::round(moved.z)};
    const Vec3 offset = moved - origin;
    for (Vec3& p : cloud.positions)
        p = rotate(p) + offset;
    if (cloud.viewpoint)
        *cloud.viewpoint = rotate(*cloud.viewpoint) + offset;
    cloud.origin = origin;
    if (placement.translation != Vec3{0, 0, 0} || placement.rotation != std::array<double, 4>{0, 0, 0, 1})
        cloud.crs.clear(); // moved: the file's coordinates, which its CRS describes, are gone
}

PointCloud read_points(const std::vector<std::filesystem::path>& paths, const ReadOptions& options)
{
    if (paths.empty())
        throw InvalidInput("read_points: no point file given");
    PointCloud cloud;
    // Files in two coordinate systems (lidar tiles of UTM zones 32 and 33) were merged as if in one,
    // their coordinate system dropped, and the cloud was wrong without a word (QA round 29). Systems
    // that certainly differ are refused (crs_differ: two EPSG codes, or an EPSG code and the WKT of
    // another system); spellings it cannot tell apart may name one system, and the merged cloud keeps
    // no coordinate system then, as before.
    std::string crs, crs_file; // the first coordinate system a file names, and that file
    for (const std::filesystem::path& path : paths) {
        PointCloud part = read_points(path, options);
        if (!part.crs.empty() && crs.empty()) {
            crs = part.crs;
            crs_file = path.string();
        } else if (!part.crs.empty() && part.crs != crs && crs_differ(part.crs, crs)) {
            throw InvalidInput(path.string() + ": its coordinate system " + crs_label(part.crs) + " is not that of " +
                               crs_file + " (" + crs_label(crs) + "): points in different coordinate systems cannot be "
                               "merged; reproject them to one first (pdal translate, las2las)");
        }
        append_within_limit(cloud, std::move(part), options, path.string(), "the files");
    }
    // Each file was checked alone; together they may span more than a mesh can (one tile at 9e29,
    // another at -9e29): refused here, naming the files, not by the build without a file name.
    if (paths.size() > 1)
        validate(cloud, paths.front().string() + " (and " + std::to_string(paths.size() - 1) + " more file" +
                            (paths.size() > 2 ? "s" : "") + ")");
    recenter(cloud);
    return cloud;
}

} // namespace mrt
