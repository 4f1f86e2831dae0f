// The persistence half of the hierarchy (paper §4.1 builds it; this keeps it): a versioned,
// checksummed binary file, explicit little-endian, validated before anything is allocated from it.
#include "libmrtile/model_file.h"

#include "libmrtile/atomic_file.h"
#include "libmrtile/errors.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

namespace mrt {
namespace {

constexpr char kMagic[8] = {'M', 'R', 'T', 'I', 'L', 'E', '\r', '\n'};
constexpr char kEndMagic[4] = {'M', 'E', 'N', 'D'};
constexpr std::uint32_t kEndianMarker = 0x01020304u;
constexpr std::size_t kHeaderSize = 104;
constexpr std::size_t kNodeSize = 168;
constexpr std::size_t kTrailerSize = 8;
constexpr std::uint32_t kFlagColors = 1, kFlagBuildTime = 2, kFlagViewpoint = 4, kFlagCrs = 8;
constexpr std::uint32_t kKnownFlags = kFlagColors | kFlagBuildTime | kFlagViewpoint | kFlagCrs;
// A WKT CRS is a few kilobytes; anything near this is not one.
constexpr std::uint32_t kMaxCrsBytes = 1u << 20;

// Little-endian writer over a string (byte by byte through shifts: correct on any host).
class Writer
{
public:
    explicit Writer(std::string& out) : out_(out) {}
    void bytes(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
    void u32(std::uint32_t v)
    {
        char b[4];
        for (int i = 0; i < 4; ++i)
            b[i] = static_cast<char>((v >> (8 * i)) & 0xffu);
        bytes(b, 4);
    }
    void u64(std::uint64_t v)
    {
        char b[8];
        for (int i = 0; i < 8; ++i)
            b[i] = static_cast<char>((v >> (8 * i)) & 0xffu);
        bytes(b, 8);
    }
    void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
    void f64(double v)
    {
        std::uint64_t bits;
        std::memcpy(&bits, &v, 8);
        u64(bits);
    }

private:
    std::string& out_;
};

class Reader
{
public:
    Reader(const std::string& in, const std::string& name) : in_(in), name_(name) {}
    void need(std::size_t n) const
    {
        if (pos_ + n > in_.size())
            fail("truncated (ends inside the data)");
    }
    std::uint32_t u32()
    {
        need(4);
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i)
            v |= static_cast<std::uint32_t>(static_cast<unsigned char>(in_[pos_ + static_cast<std::size_t>(i)])) << (8 * i);
        pos_ += 4;
        return v;
    }
    std::uint64_t u64()
    {
        const std::uint64_t lo = u32();
        const std::uint64_t hi = u32();
        return lo | (hi << 32);
    }
    std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
    double f64()
    {
        const std::uint64_t bits = u64();
        double v;
        std::memcpy(&v, &bits, 8);
        return v;
    }
    void bytes(void* p, std::size_t n)
    {
        need(n);
        std::memcpy(p, in_.data() + pos_, n);
        pos_ += n;
    }
    std::size_t position() const { return pos_; }
    [[noreturn]] void fail(const std::string& why) const { throw IoError(name_ + ": not a valid .mrt model: " + why); }

private:
    const std::string& in_;
    const std::string& name_;
    std::size_t pos_ = 0;
};

std::uint32_t crc(const std::string& bytes, std::size_t length)
{
    uLong value = crc32(0L, Z_NULL, 0);
    std::size_t done = 0;
    while (done < length) { // zlib takes 32-bit lengths
        const auto chunk = static_cast<uInt>(std::min<std::size_t>(length - done, 1u << 30));
        value = crc32(value, reinterpret_cast<const Bytef*>(bytes.data() + done), chunk);
        done += chunk;
    }
    return static_cast<std::uint32_t>(value);
}

void check_structure(const Hierarchy& h, const Reader& r)
{
    const std::size_t n = h.cloud.positions.size();
    const std::size_t count = h.nodes.size();
    if (count == 0)
        r.fail("no nodes");
    if (h.nodes[0].begin != 0 || h.nodes[0].end != n || h.nodes[0].parent != -1 || h.nodes[0].depth != 0)
        r.fail("root does not span all points");
    for (std::size_t k = 0; k < count; ++k) {
        const Node& node = h.nodes[k];
        if (node.begin >= node.end || node.end > n || node.moments.count != node.count())
            r.fail("node " + std::to_string(k) + " has an invalid point range");
        if ((node.left < 0) != (node.right < 0))
            r.fail("node " + std::to_string(k) + " has one child");
        if (node.is_leaf())
            continue;
        const auto self = static_cast<std::int64_t>(k);
        if (node.left <= self || node.right <= self || static_cast<std::size_t>(node.left) >= count ||
            static_cast<std::size_t>(node.right) >= count)
            r.fail("node " + std::to_string(k) + " has invalid children");
        const Node& l = h.nodes[static_cast<std::size_t>(node.left)];
        const Node& rt = h.nodes[static_cast<std::size_t>(node.right)];
        if (l.parent != self || rt.parent != self || l.begin != node.begin || l.end != rt.begin ||
            rt.end != node.end || l.depth != node.depth + 1 || rt.depth != node.depth + 1)
            r.fail("node " + std::to_string(k) + " does not match its children");
    }
    // Distinct input indices: a permutation of 0..n-1, or (merged duplicates) of a subset of a larger
    // range. The common case is checked with a bitmap, the other by sorting a copy.
    std::vector<bool> seen(n, false);
    bool beyond = false;
    for (std::uint32_t index : h.input_index) {
        if (index >= n) {
            beyond = true;
            break;
        }
        if (seen[index])
            r.fail("input indices repeat");
        seen[index] = true;
    }
    if (beyond) {
        std::vector<std::uint32_t> sorted = h.input_index;
        std::sort(sorted.begin(), sorted.end());
        if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
            r.fail("input indices repeat");
    }
    for (const Vec3& p : h.cloud.positions)
        if (!is_finite(p))
            r.fail("non-finite coordinate");
}

} // namespace

std::string serialize_model(const Hierarchy& h, const SaveOptions& options)
{
    const std::size_t n = h.cloud.positions.size();
    std::string out;
    out.reserve(kHeaderSize + n * (24 + 4 + (h.cloud.has_colors() ? 4 : 0)) + h.nodes.size() * kNodeSize + kTrailerSize);
    Writer w(out);
    w.bytes(kMagic, 8);
    w.u32(kModelFormatVersion);
    w.u32(kEndianMarker);
    w.u32(static_cast<std::uint32_t>(kHeaderSize));
    const bool record_time = options.record_build_time && std::isfinite(h.info.build_seconds);
    w.u32((h.cloud.has_colors() ? kFlagColors : 0u) | (record_time ? kFlagBuildTime : 0u) |
          (h.cloud.viewpoint ? kFlagViewpoint : 0u) | (h.cloud.crs.empty() ? 0u : kFlagCrs));
    w.u64(n);
    w.u64(h.nodes.size());
    w.f64(h.cloud.origin.x);
    w.f64(h.cloud.origin.y);
    w.f64(h.cloud.origin.z);
    w.u32(static_cast<std::uint32_t>(h.info.criterion));
    w.u32(h.info.pca_limit);
    w.u32(h.info.min_cluster);
    w.u32(h.info.reclassify ? 1u : 0u);
    w.f64(h.info.criterion_value);
    w.f64(record_time ? h.info.build_seconds : 0.0);
    const std::size_t payload_size_at = out.size();
    w.u64(0); // payload size, patched below
    for (const Vec3& p : h.cloud.positions) {
        w.f64(p.x);
        w.f64(p.y);
        w.f64(p.z);
    }
    if (h.cloud.has_colors())
        for (const auto& c : h.cloud.colors)
            w.bytes(c.data(), 4);
    for (std::uint32_t i : h.input_index)
        w.u32(i);
    for (const Node& node : h.nodes) {
        w.u32(node.begin);
        w.u32(node.end);
        w.i32(node.parent);
        w.i32(node.left);
        w.i32(node.right);
        w.u32(node.depth);
        w.u64(node.moments.count);
        w.f64(node.moments.mean.x);
        w.f64(node.moments.mean.y);
        w.f64(node.moments.mean.z);
        for (double v : node.moments.m2)
            w.f64(v);
        w.f64(node.internal_error);
        w.f64(node.max_plane_distance);
        for (const Vec3* v : {&node.box.min, &node.box.max}) {
            w.f64(v->x);
            w.f64(v->y);
            w.f64(v->z);
        }
    }
    if (h.cloud.viewpoint) {
        w.f64(h.cloud.viewpoint->x);
        w.f64(h.cloud.viewpoint->y);
        w.f64(h.cloud.viewpoint->z);
    }
    if (!h.cloud.crs.empty()) {
        if (h.cloud.crs.size() > kMaxCrsBytes)
            throw InvalidInput("save_model: the CRS text is longer than " + std::to_string(kMaxCrsBytes) + " bytes");
        w.u32(static_cast<std::uint32_t>(h.cloud.crs.size()));
        w.bytes(h.cloud.crs.data(), h.cloud.crs.size());
    }
    const std::uint64_t payload = out.size() - kHeaderSize;
    std::string patch;
    Writer(patch).u64(payload);
    out.replace(payload_size_at, 8, patch);
    w.u32(crc(out, out.size()));
    w.bytes(kEndMagic, 4);
    return out;
}

Hierarchy deserialize_model(const std::string& bytes, const std::string& name)
{
    Reader r(bytes, name);
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
        r.fail("wrong magic (not an .mrt file, or damaged by a text-mode transfer)");
    if (bytes.size() < kHeaderSize + kTrailerSize)
        r.fail("truncated (shorter than the header)");
    char magic[8];
    r.bytes(magic, 8);
    const std::uint32_t version = r.u32();
    if (version != kModelFormatVersion)
        r.fail("format version " + std::to_string(version) + " is not supported (this build reads version " +
               std::to_string(kModelFormatVersion) + ")");
    if (r.u32() != kEndianMarker)
        r.fail("bad byte-order marker");
    if (r.u32() != kHeaderSize)
        r.fail("unexpected header size");
    const std::uint32_t flags = r.u32();
    if ((flags & ~kKnownFlags) != 0)
        r.fail("unknown flags " + std::to_string(flags) + " (written by a newer version?)");
    const std::uint64_t n = r.u64();
    const std::uint64_t node_count = r.u64();
    // Check declared sizes against the file before allocating anything from them.
    const std::uint64_t per_point = 24 + 4 + ((flags & kFlagColors) ? 4 : 0);
    if (n == 0 || n > std::numeric_limits<std::uint32_t>::max() || node_count == 0 || node_count > 2 * n ||
        kHeaderSize + n * per_point + node_count * kNodeSize + ((flags & kFlagViewpoint) ? 24 : 0) + ((flags & kFlagCrs) ? 4 : 0) + kTrailerSize >
            bytes.size())
        r.fail("declared sizes (" + std::to_string(n) + " points, " + std::to_string(node_count) +
               " nodes) do not fit the file (" + std::to_string(bytes.size()) + " bytes): truncated or corrupted");
    const std::size_t end = bytes.size() - kTrailerSize;
    if (std::memcmp(bytes.data() + end + 4, kEndMagic, 4) != 0)
        r.fail("truncated (end marker missing)");
    const std::string stored_crc = bytes.substr(end, 4);
    if (Reader(stored_crc, name).u32() != crc(bytes, end))
        r.fail("checksum mismatch (corrupted)");

    Hierarchy h;
    h.cloud.origin.x = r.f64();
    h.cloud.origin.y = r.f64();
    h.cloud.origin.z = r.f64();
    const std::uint32_t criterion = r.u32();
    if (criterion > 1)
        r.fail("unknown stop criterion " + std::to_string(criterion));
    h.info.criterion = static_cast<Criterion>(criterion);
    h.info.pca_limit = r.u32();
    h.info.min_cluster = r.u32();
    h.info.reclassify = r.u32() != 0;
    h.info.criterion_value = r.f64();
    const double seconds = r.f64();
    h.info.build_seconds = (flags & kFlagBuildTime) ? seconds : std::numeric_limits<double>::quiet_NaN();
    const std::uint64_t payload = r.u64();
    if (kHeaderSize + payload != end)
        r.fail("payload size does not match the file size");

    h.cloud.positions.resize(n);
    for (Vec3& p : h.cloud.positions) {
        p.x = r.f64();
        p.y = r.f64();
        p.z = r.f64();
    }
    if (flags & kFlagColors) {
        h.cloud.colors.resize(n);
        for (auto& c : h.cloud.colors)
            r.bytes(c.data(), 4);
    }
    h.input_index.resize(n);
    for (std::uint32_t& i : h.input_index)
        i = r.u32();
    h.nodes.resize(node_count);
    for (Node& node : h.nodes) {
        node.begin = r.u32();
        node.end = r.u32();
        node.parent = r.i32();
        node.left = r.i32();
        node.right = r.i32();
        node.depth = r.u32();
        node.moments.count = r.u64();
        node.moments.mean.x = r.f64();
        node.moments.mean.y = r.f64();
        node.moments.mean.z = r.f64();
        for (double& v : node.moments.m2)
            v = r.f64();
        node.internal_error = r.f64();
        node.max_plane_distance = r.f64();
        for (Vec3* v : {&node.box.min, &node.box.max}) {
            v->x = r.f64();
            v->y = r.f64();
            v->z = r.f64();
        }
    }
    if (flags & kFlagViewpoint) {
        Vec3 v;
        v.x = r.f64();
        v.y = r.f64();
        v.z = r.f64();
        if (!is_finite(v))
            r.fail("non-finite viewpoint");
        h.cloud.viewpoint = v;
    }
    if (flags & kFlagCrs) {
        const std::uint32_t length = r.u32();
        if (length == 0 || length > kMaxCrsBytes || length > end - r.position())
            r.fail("CRS of " + std::to_string(length) + " bytes does not fit");
        h.cloud.crs.resize(length);
        r.bytes(h.cloud.crs.data(), length);
    }
    if (r.position() != end)
        r.fail("unexpected extra sections (written by a newer version?)");
    check_structure(h, r);
    update_derived(h);
    return h;
}

void save_model(const Hierarchy& h, const std::filesystem::path& path, const SaveOptions& options)
{
    write_file_atomically(path, serialize_model(h, options));
}

Hierarchy load_model(const std::filesystem::path& path)
{
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw IoError(path.string() + ": no such file");
    if (std::filesystem::is_directory(path, ec))
        throw IoError(path.string() + ": is a directory, not a model file");
    std::ifstream in(path, std::ios::binary);
    if (!in)
        throw IoError(path.string() + ": cannot open for reading");
    const auto size = std::filesystem::file_size(path, ec);
    if (ec)
        throw IoError(path.string() + ": cannot read size (" + ec.message() + ")");
    std::string bytes(static_cast<std::size_t>(size), '\0');
    in.read(bytes.data(), static_cast<std::streamsize>(size));
    if (static_cast<std::uintmax_t>(in.gcount()) != size)
        throw IoError(path.string() + ": read failed");
    return deserialize_model(bytes, path.string());
}

} // namespace mrt
