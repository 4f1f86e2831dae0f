// The persistence half of the hierarchy (paper §4.1 builds it; this keeps it): a versioned,
// checksummed binary file, explicit little-endian, validated before anything is allocated from it.
#include "libmrtile/model_file.h"

#include "libmrtile/coverage_gap.h"

#include "libmrtile/atomic_file.h"
#include "libmrtile/cut.h"
#include "libmrtile/errors.h"
#include "libmrtile/face_sequence.h"
#include "libmrtile/parallel.h"
#include "libmrtile/tiles.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>

namespace mrt {
namespace {

constexpr char kMagic[8] = {'M', 'R', 'T', 'I', 'L', 'E', '\r', '\n'};
constexpr char kEndMagic[4] = {'M', 'E', 'N', 'D'};
constexpr std::uint32_t kEndianMarker = 0x01020304u;
constexpr std::size_t kHeaderSize = 104;
constexpr std::size_t kNodeSize = 176;
constexpr std::size_t kNodeSizeV1 = 168; // version 1: no coverage gap
constexpr std::size_t kTrailerSize = 8;
constexpr std::uint32_t kFlagColors = 1, kFlagBuildTime = 2, kFlagViewpoint = 4, kFlagCrs = 8, kFlagLevels = 16;
constexpr std::uint32_t kFlagDenoised = 32; // BuildInfo::denoised: no section of its own
// Hierarchy::denoise_moves (a denoised model's noise floors); files from before it have flag 32
// alone and load with no such floor, as they were cut then.
constexpr std::uint32_t kFlagDenoiseMove = 64;
constexpr std::uint32_t kKnownFlags =
    kFlagColors | kFlagBuildTime | kFlagViewpoint | kFlagCrs | kFlagLevels | kFlagDenoised | kFlagDenoiseMove;
// Stored levels: a LOD set has at most LodSetOptions::max_levels (16) levels; a recipe is a line of options.
constexpr std::uint32_t kMaxStoredLevels = 64;
constexpr std::uint32_t kMaxRecipeBytes = 1u << 16;
constexpr std::size_t kStoredVertexBytes = 48 + 4; // position, normal, cluster (+ 4 with colours)
constexpr std::size_t kStoredFaceBytes = 12 + 4 + 1;
// A WKT CRS is a few kilobytes; anything near this is not one.
constexpr std::uint32_t kMaxCrsBytes = 1u << 20;

// The farthest the denoising can have moved a point: across the cloud (its quadric passes through its
// neighbours). Saving and loading hold Hierarchy::denoise_moves to it.
double move_reach(const std::vector<Vec3>& positions) { return bounding_box(positions).diagonal(); }
bool plausible_move(float move, double reach) { return move >= 0.0f && static_cast<double>(move) <= reach; }

// What is wrong with a hierarchy's build record, or "" (saving and loading hold it to this; QA round
// 34: a model with a tolerance of NaN, a build time of -1 or a min cluster of 0 loaded, and `info`
// printed them). The build time counts only where it was recorded (`timed`).
std::string bad_build_info(const BuildInfo& info, bool timed)
{
    if (!(std::isfinite(info.criterion_value) && info.criterion_value >= 0.0))
        return "a stop criterion of " + std::to_string(info.criterion_value) + " (must be finite and >= 0)";
    if (info.min_cluster == 0)
        return "a min cluster of 0 (must be at least 1)";
    if (timed && !(std::isfinite(info.build_seconds) && info.build_seconds >= 0.0))
        return "a build time of " + std::to_string(info.build_seconds) + " s";
    return {};
}

// A viewpoint the stages can measure from: its squared distances stay finite (1e300 was loaded).
bool plausible_viewpoint(const Vec3& v) { return is_finite(v) && std::isfinite(dot(v, v)); }

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
    //! Overwrites the u64 written at `at` (a size known only once what follows it is written).
    void patch_u64(std::size_t at, std::uint64_t v)
    {
        std::string bytes;
        Writer(bytes).u64(v);
        out_.replace(at, 8, bytes);
    }
    void f64(double v)
    {
        std::uint64_t bits;
        std::memcpy(&bits, &v, 8);
        u64(bits);
    }
    void f32(float v)
    {
        std::uint32_t bits;
        std::memcpy(&bits, &v, 4);
        u32(bits);
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
    // The bytes combined by shifts, written out: compilers turn this into one load on a
    // little-endian host (a loop over the bytes they did not, and a model's levels are 100 MB of it).
    std::uint32_t u32()
    {
        need(4);
        const auto* b = reinterpret_cast<const unsigned char*>(in_.data() + pos_);
        pos_ += 4;
        return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 | std::uint32_t{b[3]} << 24;
    }
    std::uint64_t u64()
    {
        need(8);
        const auto* b = reinterpret_cast<const unsigned char*>(in_.data() + pos_);
        pos_ += 8;
        return std::uint64_t{b[0]} | std::uint64_t{b[1]} << 8 | std::uint64_t{b[2]} << 16 | std::uint64_t{b[3]} << 24 |
               std::uint64_t{b[4]} << 32 | std::uint64_t{b[5]} << 40 | std::uint64_t{b[6]} << 48 | std::uint64_t{b[7]} << 56;
    }
    std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
    double f64()
    {
        const std::uint64_t bits = u64();
        double v;
        std::memcpy(&v, &bits, 8);
        return v;
    }
    float f32()
    {
        const std::uint32_t bits = u32();
        float v;
        std::memcpy(&v, &bits, 4);
        return v;
    }
    void bytes(void* p, std::size_t n)
    {
        need(n);
        std::memcpy(p, in_.data() + pos_, n);
        pos_ += n;
    }
    std::size_t position() const { return pos_; }
    void skip(std::size_t n)
    {
        need(n);
        pos_ += n;
    }
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

// The stored statistics of every node, bounded by its points: a box that is exactly its points' (a leaf)
// or its children's (else), and moments and errors that are finite and fit in that box. Cuts and
// meshes size their work from these numbers; a forged file with NaN or huge ones would make them
// allocate without bound. Runs after the point ranges are known to be valid; O(points + nodes).
void check_node_statistics(const Hierarchy& h, const Reader& r)
{
    const std::vector<Vec3>& positions = h.cloud.positions;
    for (std::size_t k = h.nodes.size(); k-- > 0;) { // children before parents
        const Node& node = h.nodes[k];
        const std::string which = "node " + std::to_string(k) + ": ";
        BoundingBox box;
        if (node.is_leaf()) {
            box.min = box.max = positions[node.begin];
            for (std::size_t i = node.begin; i < node.end; ++i) {
                box.min = min(box.min, positions[i]);
                box.max = max(box.max, positions[i]);
            }
        } else {
            const BoundingBox& a = h.nodes[static_cast<std::size_t>(node.left)].box;
            const BoundingBox& b = h.nodes[static_cast<std::size_t>(node.right)].box;
            box.min = min(a.min, b.min);
            box.max = max(a.max, b.max);
        }
        if (!(box.min == node.box.min) || !(box.max == node.box.max))
            r.fail(which + "its box is not its points' box");
        const Moments& m = node.moments;
        const double diagonal = box.diagonal();
        const double count = static_cast<double>(m.count);
        // Rounding allowance: the mean may sit a hair outside a flat box; sums of squares carry rounding.
        const double slack = 1e-9 * (diagonal + norm(box.max) + norm(box.min)) + 1e-300;
        const Vec3 pad{slack, slack, slack};
        if (!is_finite(m.mean) || !BoundingBox{box.min - pad, box.max + pad}.contains(m.mean))
            r.fail(which + "its mean lies outside its points' box");
        const double largest_square = count * (diagonal * diagonal + slack);
        for (const double v : m.m2)
            if (!std::isfinite(v) || std::abs(v) > largest_square * (1 + 1e-9))
                r.fail(which + "second moments do not fit its points' box");
        if (m.m2[0] < 0 || m.m2[3] < 0 || m.m2[5] < 0)
            r.fail(which + "negative second moments");
        // Paper eq. 1 sums distances to the centre (each at most the diagonal); it is kept up to date
        // incrementally while points move between clusters, hence the factor 2 of room.
        if (!(node.internal_error >= 0 && node.internal_error <= 2 * count * (diagonal + slack)) ||
            !(node.max_plane_distance >= 0 && node.max_plane_distance <= 2 * diagonal + slack) ||
            !(node.coverage_gap >= 0 && node.coverage_gap <= 2 * diagonal + slack))
            r.fail(which + "errors do not fit its points' box");
    }
}

void check_structure(const Hierarchy& h, const Reader& r)
{
    // What a build would have refused (validate): a non-finite origin or point, an extent no mesh can
    // have. Such a model was not written by save_model; meshing it would give non-finite vertices.
    try {
        validate(h.cloud, "the point cloud");
    } catch (const InvalidInput& e) {
        r.fail(e.what());
    }
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
        // Every node but the root is the child of an earlier node (parents come first in the file),
        // so that the tree has no orphans: a node no parent names could carry any parent index, which
        // the derived statistics would then follow out of the array.
        if (k > 0) {
            const std::int32_t p = node.parent;
            const Node* parent = p >= 0 && static_cast<std::size_t>(p) < k ? &h.nodes[static_cast<std::size_t>(p)] : nullptr;
            if (!parent || (parent->left != static_cast<std::int32_t>(k) && parent->right != static_cast<std::int32_t>(k)))
                r.fail("node " + std::to_string(k) + " is not a child of its parent");
        }
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
    check_node_statistics(h, r);
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
}


// The stored levels (SaveOptions::levels). A mesh is written vertex by vertex and face by face in
// index order with the corners as OpenMesh walks them, so that reading it back with add_face gives
// the same indices, the same corner order and therefore byte-identical tiles.
void write_levels(Writer& w, std::string& out, const StoredLevels& stored)
{
    if (stored.recipe.size() > kMaxRecipeBytes || stored.levels.size() > kMaxStoredLevels)
        throw InvalidInput("save_model: too many stored levels or too long a recipe");
    const std::size_t size_at = out.size();
    w.u64(0); // section size, patched below
    w.u32(static_cast<std::uint32_t>(stored.recipe.size()));
    w.bytes(stored.recipe.data(), stored.recipe.size());
    w.u32(static_cast<std::uint32_t>(stored.levels.size()));
    for (const LodLevel& level : stored.levels) {
        w.f64(level.tolerance);
        w.f64(level.geometric_error);
        w.f64(level.max_plane_distance);
        w.u64(level.cut.size());
        for (std::int32_t id : level.cut)
            w.i32(id);
        const Mesh& m = level.mesh;
        OpenMesh::FPropHandleT<int> tile;
        OpenMesh::FPropHandleT<bool> gap;
        OpenMesh::VPropHandleT<int> cluster;
        if (!m.get_property_handle(tile, kFaceTile) || !m.get_property_handle(gap, kFaceGap) ||
            !m.get_property_handle(cluster, kVertexCluster) || !m.has_vertex_normals())
            throw InvalidInput("save_model: a level mesh lacks its tile, gap, cluster or normal properties");
        for (const auto v : m.all_vertices())
            if (m.status(v).deleted())
                throw InvalidInput("save_model: a level mesh holds deleted elements (collect its garbage first)");
        for (const auto f : m.all_faces())
            if (m.status(f).deleted())
                throw InvalidInput("save_model: a level mesh holds deleted elements (collect its garbage first)");
        const bool colored = m.has_vertex_colors();
        w.u64(m.n_vertices());
        w.u64(m.n_faces());
        w.u32(colored ? 1u : 0u);
        for (const auto v : m.vertices()) {
            for (int a = 0; a < 3; ++a)
                w.f64(m.point(v)[a]);
            for (int a = 0; a < 3; ++a)
                w.f64(m.normal(v)[a]);
            w.i32(m.property(cluster, v));
            if (colored)
                w.bytes(m.color(v).data(), 4);
        }
        for (const auto f : m.faces()) {
            int k = 0;
            for (const auto v : m.fv_range(f)) {
                w.u32(static_cast<std::uint32_t>(v.idx()));
                ++k;
            }
            if (k != 3)
                throw InvalidInput("save_model: a level mesh has a face that is not a triangle");
            w.i32(m.property(tile, f));
            const char g = m.property(gap, f) ? 1 : 0;
            w.bytes(&g, 1);
        }
    }
    w.patch_u64(size_at, out.size() - size_at - 8);
}

// The bytes of a level's mesh, once its declared counts are known to fit the `left` bytes. Counts below
// 2^31 keep the byte count below 2^38: it cannot overflow.
std::size_t level_mesh_bytes(const Reader& r, std::size_t left, const std::string& which, std::uint64_t vertices,
                             std::uint64_t faces, std::uint32_t colored)
{
    const std::size_t vertex_bytes = kStoredVertexBytes + (colored ? 4 : 0);
    if (colored > 1 || vertices > std::numeric_limits<std::int32_t>::max() ||
        faces > std::numeric_limits<std::int32_t>::max() || vertices * vertex_bytes + faces * kStoredFaceBytes > left)
        r.fail(which + "declared " + std::to_string(vertices) + " vertices and " + std::to_string(faces) +
               " faces do not fit the file");
    return static_cast<std::size_t>(vertices * vertex_bytes + faces * kStoredFaceBytes);
}

// The bytes from the reader's position to `end`, the end of the levels section.
std::size_t bytes_left(const Reader& r, std::size_t end, const std::string& which)
{
    if (r.position() > end)
        r.fail(which + "runs past the end of the stored levels");
    return end - r.position();
}

// A level's cut size, once known to fit the bytes left before `end`.
std::size_t level_cut_size(Reader& r, std::size_t end, const std::string& which)
{
    const std::uint64_t cut_size = r.u64();
    if (cut_size == 0 || cut_size > bytes_left(r, end, which) / 4)
        r.fail(which + "cut of " + std::to_string(cut_size) + " nodes does not fit");
    return static_cast<std::size_t>(cut_size);
}

// Level l of the section, from its first byte: header, cut, mesh.
void read_level(Reader& r, std::size_t end, const Hierarchy& h, std::uint32_t l, LodLevel& level)
{
    const std::size_t node_count = h.nodes.size();
    const std::string which = "stored level " + std::to_string(l) + ": ";
    level.tolerance = r.f64();
    level.geometric_error = r.f64();
    level.max_plane_distance = r.f64();
    if (!std::isfinite(level.tolerance) || !std::isfinite(level.geometric_error) || !std::isfinite(level.max_plane_distance))
        r.fail(which + "non-finite error");
    level.cut.resize(level_cut_size(r, end, which));
    for (std::int32_t& id : level.cut) {
        id = r.i32();
        if (id < 0 || static_cast<std::size_t>(id) >= node_count)
            r.fail(which + "cut names node " + std::to_string(id) + " of " + std::to_string(node_count));
    }
    if (!is_partition(h, level.cut))
        r.fail(which + "the cut is not a partition of the points");
    const std::uint64_t vertices = r.u64();
    const std::uint64_t faces = r.u64();
    const std::uint32_t colored = r.u32();
    level_mesh_bytes(r, bytes_left(r, end, which), which, vertices, faces, colored);
    Mesh& m = level.mesh;
    m.reserve(vertices, 3 * faces / 2 + 3, faces);
    if (colored)
        m.request_vertex_colors();
    auto cluster = OpenMesh::getOrMakeProperty<OpenMesh::VertexHandle, int>(m, kVertexCluster);
    auto tile = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, int>(m, kFaceTile);
    auto gap = OpenMesh::getOrMakeProperty<OpenMesh::FaceHandle, bool>(m, kFaceGap);
    auto valid_id = [&](std::int32_t id) { return id >= -1 && id < static_cast<std::int64_t>(node_count); };
    for (std::uint64_t i = 0; i < vertices; ++i) {
        OpenMesh::Vec3d p, n;
        for (int a = 0; a < 3; ++a)
            p[a] = r.f64();
        for (int a = 0; a < 3; ++a)
            n[a] = r.f64();
        if (!is_finite(to_vec3(p)) || !is_finite(to_vec3(n)))
            r.fail(which + "non-finite vertex " + std::to_string(i));
        const auto v = m.add_vertex(p);
        m.set_normal(v, n);
        const std::int32_t id = r.i32();
        if (!valid_id(id))
            r.fail(which + "vertex " + std::to_string(i) + " names node " + std::to_string(id));
        cluster[v] = id;
        if (colored) {
            Mesh::Color c;
            r.bytes(c.data(), 4);
            m.set_color(v, c);
        }
    }
    // The faces go through FaceSequence, which builds what add_face would, at a tenth of its cost
    // (face_sequence.h); their properties are set once the mesh has them.
    FaceSequence sequence(static_cast<std::size_t>(vertices));
    sequence.reserve(static_cast<std::size_t>(vertices), static_cast<std::size_t>(faces));
    std::vector<std::int32_t> tiles(static_cast<std::size_t>(faces));
    std::vector<char> gaps(static_cast<std::size_t>(faces));
    for (std::uint64_t i = 0; i < faces; ++i) {
        std::array<int, 3> corner;
        for (int& c : corner) {
            const std::uint32_t index = r.u32();
            if (index >= vertices)
                r.fail(which + "face " + std::to_string(i) + " names vertex " + std::to_string(index));
            c = static_cast<int>(index);
        }
        if (corner[0] == corner[1] || corner[1] == corner[2] || corner[0] == corner[2]) // OpenMesh would loop an edge
            r.fail(which + "face " + std::to_string(i) + " repeats a corner");
        if (sequence.add_face(corner[0], corner[1], corner[2]) < 0)
            r.fail(which + "face " + std::to_string(i) + " does not fit a manifold mesh");
        const std::int32_t id = r.i32();
        char g = 0;
        r.bytes(&g, 1);
        if (!valid_id(id) || (g != 0 && g != 1))
            r.fail(which + "face " + std::to_string(i) + " has an invalid tile or gap flag");
        tiles[static_cast<std::size_t>(i)] = id;
        gaps[static_cast<std::size_t>(i)] = g;
    }
    sequence.apply(m);
    for (const auto f : m.faces()) {
        tile[f] = tiles[static_cast<std::size_t>(f.idx())];
        gap[f] = gaps[static_cast<std::size_t>(f.idx())] != 0;
    }
    m.update_face_normals();
}

// Steps over level l, checking only that its counts fit: where the next level starts.
void skip_level(Reader& r, std::size_t end, std::uint32_t l)
{
    const std::string which = "stored level " + std::to_string(l) + ": ";
    r.skip(24); // tolerance, geometric error, largest plane distance
    r.skip(level_cut_size(r, end, which) * 4);
    const std::uint64_t vertices = r.u64();
    const std::uint64_t faces = r.u64();
    const std::uint32_t colored = r.u32();
    r.skip(level_mesh_bytes(r, bytes_left(r, end, which), which, vertices, faces, colored));
}

// Reads the section write_levels wrote, checking every count against the bytes left before anything
// is allocated from it, every id against the hierarchy, and every face as OpenMesh adds it.
StoredLevels read_levels(Reader& r, std::size_t end, const Hierarchy& h)
{
    StoredLevels stored;
    auto left = [&] { return bytes_left(r, end, "stored levels: "); };
    const std::uint32_t recipe = r.u32();
    if (recipe > kMaxRecipeBytes || recipe > left())
        r.fail("stored levels: recipe of " + std::to_string(recipe) + " bytes does not fit");
    stored.recipe.resize(recipe);
    r.bytes(stored.recipe.data(), recipe);
    const std::uint32_t count = r.u32();
    if (count == 0 || count > kMaxStoredLevels)
        r.fail("stored levels: " + std::to_string(count) + " levels (expected 1 to " + std::to_string(kMaxStoredLevels) + ")");
    // Where each level starts, from the counts alone; then the levels are read each on its own, in
    // parallel (adding a 1M-point set's faces to OpenMesh is most of a load). A damaged file is
    // reported for its first damaged level, whatever the thread count.
    std::vector<Reader> starts;
    for (std::uint32_t l = 0; l < count; ++l) {
        starts.push_back(r);
        skip_level(r, end, l);
    }
    // Each level is read into its place: an OpenMesh mesh has no move constructor, so moving a level
    // into the vector (or the vector growing) would copy its mesh.
    stored.levels.resize(count);
    std::vector<std::exception_ptr> failures(count);
    run_parallel(count, 0, [&](std::size_t l) {
        try {
            read_level(starts[l], end, h, static_cast<std::uint32_t>(l), stored.levels[l]);
        } catch (...) {
            failures[l] = std::current_exception();
        }
    });
    for (const std::exception_ptr& failure : failures)
        if (failure)
            std::rethrow_exception(failure);
    return stored;
}

// Node hulls (version 3): the number of entries, each node's hull size, then every hull's point
// indices. A hierarchy without them (just built) has them computed here.
void write_hulls(Writer& w, const Hierarchy& h)
{
    std::vector<std::size_t> computed_start;
    std::vector<std::uint32_t> computed_points;
    const bool stored = h.hull_start.size() == h.nodes.size() + 1;
    if (!stored)
        compute_node_hulls(h, computed_start, computed_points);
    const std::vector<std::size_t>& start = stored ? h.hull_start : computed_start;
    const std::vector<std::uint32_t>& points = stored ? h.hull_points : computed_points;
    w.u64(points.size());
    for (std::size_t k = 0; k < h.nodes.size(); ++k)
        w.u32(static_cast<std::uint32_t>(start[k + 1] - start[k]));
    for (std::uint32_t i : points)
        w.u32(i);
}

// Reads what write_hulls wrote into `h` (checked by check_hulls once the nodes are).
void read_hulls(Reader& r, Hierarchy& h, std::size_t end)
{
    const std::uint64_t total = r.u64();
    const std::size_t count = h.nodes.size();
    if (total > (end - r.position()) / 4 || 4 * total + 4 * count > end - r.position())
        r.fail("node hulls of " + std::to_string(total) + " points do not fit");
    h.hull_start.assign(count + 1, 0);
    for (std::size_t k = 0; k < count; ++k)
        h.hull_start[k + 1] = h.hull_start[k] + r.u32();
    if (h.hull_start[count] != total)
        r.fail("node hulls' sizes do not add up to their " + std::to_string(total) + " points");
    h.hull_points.resize(static_cast<std::size_t>(total));
    for (std::uint32_t& i : h.hull_points)
        i = r.u32();
}

// Every hull point is one of its node's points, ascending.
void check_hulls(const Hierarchy& h, const Reader& r)
{
    for (std::size_t k = 0; k < h.nodes.size(); ++k)
        for (std::size_t j = h.hull_start[k]; j < h.hull_start[k + 1]; ++j) {
            const std::uint32_t i = h.hull_points[j];
            if (i < h.nodes[k].begin || i >= h.nodes[k].end || (j > h.hull_start[k] && i <= h.hull_points[j - 1]))
                r.fail("node " + std::to_string(k) + "'s hull names points not of the node, or not in order");
        }
}

} // namespace

std::string serialize_model(const Hierarchy& h, const SaveOptions& options)
{
    const std::size_t n = h.cloud.positions.size();
    // What load_model refuses must not be written: a default-constructed Hierarchy made a file that
    // saved without complaint and could not be loaded ("declared sizes ... do not fit the file").
    if (n == 0 || h.nodes.empty())
        throw InvalidInput("save_model: the hierarchy has no points or no nodes; build it with build_hierarchy or "
                           "load it with load_model before saving");
    if (h.input_index.size() != n || (h.cloud.has_colors() && h.cloud.colors.size() != n))
        throw InvalidInput("save_model: the hierarchy's input_index (" + std::to_string(h.input_index.size()) +
                           ") and colours (" + std::to_string(h.cloud.colors.size()) + ") must have one entry per point (" +
                           std::to_string(n) + "; colours may be empty)");
    if (!h.denoise_moves.empty()) {
        // What load_model checks (parse_model), so that a model saved loads.
        const double reach = move_reach(h.cloud.positions);
        const bool valid = h.info.denoised && h.denoise_moves.size() == n &&
                           std::all_of(h.denoise_moves.begin(), h.denoise_moves.end(),
                                       [&](float m) { return plausible_move(m, reach); });
        if (!valid)
            throw InvalidInput("save_model: the hierarchy's denoise_moves must be of a denoised hierarchy (info.denoised), "
                               "one per point (" + std::to_string(n) + ", got " + std::to_string(h.denoise_moves.size()) +
                               "), each finite, >= 0 and within the cloud's diagonal");
    }
    const bool record_time = options.record_build_time && std::isfinite(h.info.build_seconds);
    if (const std::string bad = bad_build_info(h.info, record_time); !bad.empty())
        throw InvalidInput("save_model: the hierarchy's build info has " + bad);
    if (h.cloud.viewpoint && !plausible_viewpoint(*h.cloud.viewpoint))
        throw InvalidInput("save_model: the cloud's viewpoint is not finite or too far out to measure from");
    // And what load_model checks of the tree, the node statistics and input_index (O(points + nodes)): a
    // hierarchy changed in memory was written over a good file, which then did not load (QA round 51).
    const std::string none, who = "save_model: the hierarchy";
    try {
        check_structure(h, Reader(none, who));
    } catch (const IoError& e) {
        throw InvalidInput(std::string(e.what()) + " (it would not load)");
    }
    std::string out;
    out.reserve(kHeaderSize + n * (24 + 4 + (h.cloud.has_colors() ? 4 : 0)) + h.nodes.size() * kNodeSize + kTrailerSize);
    Writer w(out);
    w.bytes(kMagic, 8);
    w.u32(kModelFormatVersion);
    w.u32(kEndianMarker);
    w.u32(static_cast<std::uint32_t>(kHeaderSize));
    const bool levels = options.levels != nullptr && !options.levels->levels.empty();
    const bool denoise_move = !h.denoise_moves.empty();
    w.u32((h.cloud.has_colors() ? kFlagColors : 0u) | (record_time ? kFlagBuildTime : 0u) |
          (h.cloud.viewpoint ? kFlagViewpoint : 0u) | (h.cloud.crs.empty() ? 0u : kFlagCrs) | (levels ? kFlagLevels : 0u) |
          (h.info.denoised ? kFlagDenoised : 0u) | (denoise_move ? kFlagDenoiseMove : 0u));
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
    write_hulls(w, h);
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
        w.f64(node.coverage_gap);
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
    if (denoise_move)
        for (const float m : h.denoise_moves)
            w.f32(m);
    if (levels) {
        const std::size_t levels_at = out.size();
        write_levels(w, out, *options.levels);
        // Read back as load_model_with_levels reads them: levels of another hierarchy, a cut naming no
        // node or a non-finite error were stored and refused only on the next load (QA round 51).
        Reader back(out, who);
        back.skip(levels_at + 8); // past the section's size
        try {
            read_levels(back, out.size(), h);
        } catch (const IoError& e) {
            throw InvalidInput(std::string(e.what()) + " (they would not load)");
        }
    }
    const std::uint64_t payload = out.size() - kHeaderSize;
    w.patch_u64(payload_size_at, payload);
    w.u32(crc(out, out.size()));
    w.bytes(kEndMagic, 4);
    return out;
}

namespace {

Model parse_model(const std::string& bytes, const std::string& name, bool with_levels)
{
    Reader r(bytes, name);
    if (bytes.empty())
        r.fail("empty file (0 bytes)");
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
        r.fail("wrong magic (not an .mrt file, or damaged by a text-mode transfer)");
    if (bytes.size() < kHeaderSize + kTrailerSize)
        r.fail("truncated (shorter than the header)");
    char magic[8];
    r.bytes(magic, 8);
    const std::uint32_t version = r.u32();
    if (version < 1 || version > kModelFormatVersion)
        r.fail("format version " + std::to_string(version) + " is not supported (this build reads versions 1 to " +
               std::to_string(kModelFormatVersion) + ")");
    const std::size_t node_size = version == 1 ? kNodeSizeV1 : kNodeSize;
    if (r.u32() != kEndianMarker)
        r.fail("bad byte-order marker");
    if (r.u32() != kHeaderSize)
        r.fail("unexpected header size");
    const std::uint32_t flags = r.u32();
    if ((flags & ~kKnownFlags) != 0)
        r.fail("unknown flags " + std::to_string(flags & ~kKnownFlags) + " (written by a newer version?)");
    const std::uint64_t n = r.u64();
    const std::uint64_t node_count = r.u64();
    // Check declared sizes against the file before allocating anything from them.
    const std::uint64_t per_point = 24 + 4 + ((flags & kFlagColors) ? 4 : 0);
    if (n == 0 || n > std::numeric_limits<std::uint32_t>::max() || node_count == 0 || node_count > 2 * n ||
        kHeaderSize + n * per_point + node_count * node_size + ((flags & kFlagViewpoint) ? 24 : 0) + ((flags & kFlagCrs) ? 4 : 0) +
                ((flags & kFlagDenoiseMove) ? 4 * n : 0) + ((flags & kFlagLevels) ? 8 : 0) +
                (version >= 3 ? 8 + 4 * node_count : 0) + kTrailerSize >
            bytes.size())
        r.fail("declared sizes (" + std::to_string(n) + " points, " + std::to_string(node_count) +
               " nodes) do not fit the file (" + std::to_string(bytes.size()) + " bytes): truncated or corrupted");
    const std::size_t end = bytes.size() - kTrailerSize;
    if (std::memcmp(bytes.data() + end + 4, kEndMagic, 4) != 0)
        r.fail("truncated (end marker missing)");
    const std::string stored_crc = bytes.substr(end, 4);
    if (Reader(stored_crc, name).u32() != crc(bytes, end))
        r.fail("checksum mismatch (corrupted)");

    Model model;
    Hierarchy& h = model.hierarchy;
    h.cloud.origin.x = r.f64();
    h.cloud.origin.y = r.f64();
    h.cloud.origin.z = r.f64();
    const std::uint32_t criterion = r.u32();
    if (criterion > 1)
        r.fail("unknown stop criterion " + std::to_string(criterion));
    h.info.criterion = static_cast<Criterion>(criterion);
    h.info.pca_limit = r.u32();
    h.info.min_cluster = r.u32();
    const std::uint32_t reclassify = r.u32();
    if (reclassify > 1)
        r.fail("bad reclassify flag " + std::to_string(reclassify));
    h.info.reclassify = reclassify != 0;
    h.info.denoised = (flags & kFlagDenoised) != 0;
    h.info.criterion_value = r.f64();
    const double seconds = r.f64();
    h.info.build_seconds = (flags & kFlagBuildTime) ? seconds : std::numeric_limits<double>::quiet_NaN();
    if (const std::string bad = bad_build_info(h.info, (flags & kFlagBuildTime) != 0); !bad.empty())
        r.fail("build info with " + bad);
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
    if (version >= 3)
        read_hulls(r, h, end);
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
        if (version >= 2)
            node.coverage_gap = r.f64();
    }
    if (flags & kFlagViewpoint) {
        Vec3 v;
        v.x = r.f64();
        v.y = r.f64();
        v.z = r.f64();
        if (!plausible_viewpoint(v)) {
            char text[96];
            std::snprintf(text, sizeof text, "viewpoint not finite or too far out (%.6g, %.6g, %.6g)", v.x, v.y, v.z);
            r.fail(text);
        }
        h.cloud.viewpoint = v;
    }
    if (flags & kFlagCrs) {
        const std::uint32_t length = r.u32();
        if (length == 0 || length > kMaxCrsBytes || length > end - r.position())
            r.fail("CRS of " + std::to_string(length) + " bytes does not fit");
        h.cloud.crs.resize(length);
        r.bytes(h.cloud.crs.data(), length);
    }
    if (flags & kFlagDenoiseMove) {
        if (!(flags & kFlagDenoised))
            r.fail("bad denoising section (moves in a model not denoised)");
        const double reach = move_reach(h.cloud.positions);
        h.denoise_moves.resize(n);
        for (float& m : h.denoise_moves) {
            m = r.f32();
            if (!plausible_move(m, reach))
                r.fail("bad denoising section (a move of " + std::to_string(m) + ", the cloud being " + std::to_string(reach) + " across)");
        }
    }
    std::size_t levels_at = 0;
    if (flags & kFlagLevels) {
        const std::uint64_t size = r.u64();
        if (size > end - r.position())
            r.fail("stored levels of " + std::to_string(size) + " bytes do not fit");
        levels_at = r.position();
        r.skip(static_cast<std::size_t>(size));
    }
    if (r.position() != end)
        r.fail("unexpected extra sections (written by a newer version?)");
    check_structure(h, r);
    update_derived(h);
    if (version == 1)
        set_coverage_gaps(h); // not stored before version 2
    if (version >= 3)
        check_hulls(h, r);
    else
        set_node_hulls(h); // not stored before version 3
    if (levels_at > 0 && with_levels) {
        Reader levels(bytes, name);
        levels.skip(levels_at);
        model.levels = read_levels(levels, end, h);
        if (levels.position() != end)
            levels.fail("stored levels end before their section does");
    }
    return model;
}

} // namespace

Hierarchy deserialize_model(const std::string& bytes, const std::string& name)
{
    return std::move(parse_model(bytes, name, false).hierarchy);
}

Model deserialize_model_with_levels(const std::string& bytes, const std::string& name)
{
    return parse_model(bytes, name, true);
}

void save_model(const Hierarchy& h, const std::filesystem::path& path, const SaveOptions& options)
{
    write_file_atomically(path, serialize_model(h, options));
}

namespace {

std::string read_model_bytes(const std::filesystem::path& path)
{
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
        throw IoError(path.string() + ": no such file");
    if (std::filesystem::is_directory(path, ec))
        throw IoError(path.string() + ": is a directory, not a model file");
    // A device or a pipe has no size to check the file against: "/dev/null: cannot read size
    // (Operation not supported)" said what failed, not what was wrong (QA round 29).
    if (!std::filesystem::is_regular_file(path, ec))
        throw IoError(path.string() + ": is not a regular file (a device, pipe or socket); a model is read from a file");
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
    return bytes;
}

} // namespace

Hierarchy load_model(const std::filesystem::path& path)
{
    return deserialize_model(read_model_bytes(path), path.string());
}

Model load_model_with_levels(const std::filesystem::path& path)
{
    return deserialize_model_with_levels(read_model_bytes(path), path.string());
}

} // namespace mrt
