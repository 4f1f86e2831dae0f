// Beyond the paper (its §6 lists holes and non-manifold output; we also rule out self-intersections):
// the surface stage builds an oriented 2-manifold, but where the sample is thinner than a tile a gap
// face may cross a fan of the other side. This pass finds the intersecting pairs once with CGAL's box
// intersection (self_intersecting_faces; or takes them from the vertex fit, which has just tested the
// whole mesh) and then repairs them with local edits, each judged by exact triangle-triangle tests
// (faces_intersect) against the faces near it (a uniform grid over face boxes finds those). After each
// round only the faces an edit changed are tested again: every other pair is as it was.
#include "libmrtile/untangle.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/errors.h"
#include "libmrtile/mesh_stats.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace mrt {
namespace {

// Repairs tried per face over all rounds.
constexpr std::uint8_t kMaxTries = 2;
// The work bound's floor (UntangleOptions::tests_per_face), about a tenth of a second: a small
// mesh's crossings get the same chance as a large one's.
constexpr std::size_t kMinTests = 400000;

// A face an edge collapse removed (untangle keeps the handles until its garbage collection).
bool is_deleted(const Mesh& mesh, Mesh::FaceHandle f) { return mesh.has_face_status() && mesh.status(f).deleted(); }

struct Box
{
    OpenMesh::Vec3d min, max;
    bool overlaps(const Box& o) const
    {
        for (int k = 0; k < 3; ++k)
            if (max[k] < o.min[k] || o.max[k] < min[k])
                return false;
        return true;
    }
};

Box corners_box(const Mesh& mesh, const std::array<Mesh::VertexHandle, 3>& corners)
{
    Box b{OpenMesh::Vec3d(std::numeric_limits<double>::max()), OpenMesh::Vec3d(std::numeric_limits<double>::lowest())};
    for (const auto v : corners) {
        b.min.minimize(mesh.point(v));
        b.max.maximize(mesh.point(v));
    }
    return b;
}

Box face_box(const Mesh& mesh, Mesh::FaceHandle f) { return corners_box(mesh, face_vertices(mesh, f)); }

// Faces by the grid cells their boxes overlap. Faces are added again when an edit moves them; stale
// entries are harmless, since every candidate's current box is tested.
class FaceGrid
{
public:
    FaceGrid(const Mesh& mesh, double cell) : mesh_(mesh), grid_(cell), stamp_(mesh.n_faces(), 0)
    {
        for (const auto f : mesh.faces())
            insert(f);
    }

    void insert(Mesh::FaceHandle f) { grid_.insert(static_cast<std::uint32_t>(f.idx()), bounding(face_box(mesh_, f))); }

    // Faces whose current box overlaps `b`, each once, in increasing index order.
    std::vector<int> near(const Box& b)
    {
        ++round_;
        std::vector<int> out;
        const auto consider = [&](int f) {
            if (stamp_[static_cast<std::size_t>(f)] != round_ && !is_deleted(mesh_, Mesh::FaceHandle(f))) {
                stamp_[static_cast<std::size_t>(f)] = round_;
                if (face_box(mesh_, Mesh::FaceHandle(f)).overlaps(b))
                    out.push_back(f);
            }
        };
        const BoundingBox box = bounding(b);
        if (grid_.cell_count(box) > std::max(BoxGrid::kMaxCellsPerItem, static_cast<double>(mesh_.n_faces()))) {
            // A box over more cells than there are faces: every face is a candidate.
            for (const auto f : mesh_.faces())
                consider(f.idx());
        } else {
            grid_.for_each_candidate(box, [&](std::uint32_t f) { consider(static_cast<int>(f)); });
        }
        std::sort(out.begin(), out.end());
        return out;
    }

private:
    static BoundingBox bounding(const Box& b)
    {
        return {{b.min[0], b.min[1], b.min[2]}, {b.max[0], b.max[1], b.max[2]}};
    }

    const Mesh& mesh_;
    BoxGrid grid_;
    std::vector<unsigned> stamp_;
    unsigned round_ = 0;
};

class Untangler
{
public:
    Untangler(Mesh& mesh, const UntangleOptions& options)
        : mesh_(mesh), options_(options), min_cos_(std::cos(options.max_turn_degrees * M_PI / 180.0)),
          grid_(mesh, grid_cell(mesh))
    {
        mesh_.get_property_handle(tile_, kFaceTile);
        mesh_.get_property_handle(gap_, kFaceGap);
    }

    // Triangle pairs tested so far; repair stops trying once `budget` is spent.
    std::size_t tests() const { return tests_; }

    // The intersecting pairs now, from `pairs` (those before this round's edits): pairs of faces no
    // edit changed are still there, and any other pair has a changed face, whose current box the grid
    // knows. Costs the changed faces' neighbourhoods instead of a test of the whole mesh.
    std::vector<std::pair<int, int>> update_pairs(const std::vector<std::pair<int, int>>& pairs)
    {
        std::vector<char> changed(mesh_.n_faces(), 0);
        for (const auto f : changed_)
            changed[static_cast<std::size_t>(f.idx())] = 1;
        std::vector<std::pair<int, int>> out;
        for (const auto& p : pairs)
            if (!changed[static_cast<std::size_t>(p.first)] && !changed[static_cast<std::size_t>(p.second)])
                out.push_back(p);
        std::sort(changed_.begin(), changed_.end());
        changed_.erase(std::unique(changed_.begin(), changed_.end()), changed_.end());
        for (const auto c : changed_) {
            if (is_deleted(mesh_, c))
                continue; // collapsed away: its pairs went with it
            for (const int g : grid_.near(face_box(mesh_, c))) {
                if (g == c.idx() || (changed[static_cast<std::size_t>(g)] && g < c.idx()))
                    continue; // itself, or a pair of two changed faces seen from the other one
                if (faces_intersect(mesh_, c, Mesh::FaceHandle(g)))
                    out.push_back({std::min(c.idx(), g), std::max(c.idx(), g)});
            }
        }
        changed_.clear();
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
        return out;
    }

    // Tries the edits for face f, keeps the first that lowers its faces' intersections.
    void repair(Mesh::FaceHandle f, UntangleStats& stats, std::size_t budget)
    {
        // A face tried twice without success hinges on something no edit here changes: skip it.
        if (tests_ >= budget || is_deleted(mesh_, f) || tries_[static_cast<std::size_t>(f.idx())] >= kMaxTries || hits({f}) == 0)
            return; // out of budget, given up, or an earlier edit fixed it
        ++tries_[static_cast<std::size_t>(f.idx())];
        // The edges first: a flip tried and undone renumbers the face's half-edges under a circulator.
        std::vector<Mesh::EdgeHandle> edges;
        for (const auto he : mesh_.fh_range(f))
            edges.push_back(mesh_.edge_handle(he));
        for (const auto e : edges)
            if (tests_ < budget && try_flip(e)) {
                ++stats.flips;
                return;
            }
        // Moves toward the centre of the neighbours (smoothing pulls a crossing apart), then across the
        // surface either way (a fold held by its neighbours), corners first, then the ring around them:
        // at a thin tip the crossing can hinge on a vertex next to the faces.
        const auto corners = face_vertices(mesh_, f);
        std::vector<Mesh::VertexHandle> ring;
        for (const auto v : corners)
            for (const auto w : mesh_.vv_range(v))
                if (std::find(corners.begin(), corners.end(), w) == corners.end())
                    ring.push_back(w);
        std::sort(ring.begin(), ring.end());
        ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
        std::vector<Mesh::VertexHandle> own(corners.begin(), corners.end());
        // A crossing in the face's own plane (a fold in a flat part) is parted by a move across the
        // surface too, but as a tent standing out of the plane: only moves within it are tried there.
        const bool in_plane = crossings_in_plane(f);
        for (const std::vector<Mesh::VertexHandle>* vertices : {&own, &ring})
            for (const Move move : {Move{false, 0.25}, Move{true, 0.25}, Move{true, -0.25}, Move{false, 0.5}, Move{true, 0.5}, Move{true, -0.5}, Move{false, 1.0}})
                for (const auto v : *vertices)
                    if (tests_ < budget && !(in_plane && move.along_normal) && try_move(v, move)) {
                        ++stats.moves;
                        return;
                    }
        // Last, an edge of the face collapsed either way: a tip folded over itself around one vertex
        // (a gap face at a sharp rim, turned under its neighbours) has no position that unfolds it,
        // but without that vertex the fold is gone.
        std::vector<Mesh::HalfedgeHandle> halfedges;
        for (const auto he : mesh_.fh_range(f)) {
            halfedges.push_back(he);
            halfedges.push_back(mesh_.opposite_halfedge_handle(he));
        }
        for (const auto he : halfedges)
            if (tests_ < budget && try_collapse(he)) {
                ++stats.collapses;
                return;
            }
    }

    bool requested_status() const { return requested_status_; }

private:
    static double grid_cell(const Mesh& mesh)
    {
        double sum = 0.0;
        std::size_t n = 0;
        for (const auto e : mesh.edges()) {
            sum += mesh.calc_edge_length(e);
            ++n;
        }
        return n > 0 && sum > 0 ? 2.0 * sum / static_cast<double>(n) : 1.0;
    }

    // Intersecting pairs with at least one face in `faces` (pairs inside `faces` counted once).
    std::size_t hits(const std::vector<Mesh::FaceHandle>& faces)
    {
        std::size_t count = 0;
        for (std::size_t i = 0; i < faces.size(); ++i)
            for (const int g : grid_.near(face_box(mesh_, faces[i]))) {
                const Mesh::FaceHandle gh(g);
                if (gh == faces[i])
                    continue;
                const auto earlier = std::find(faces.begin(), faces.begin() + static_cast<std::ptrdiff_t>(i), gh);
                if (earlier != faces.begin() + static_cast<std::ptrdiff_t>(i))
                    continue; // counted from the other face
                ++tests_;
                if (faces_intersect(mesh_, faces[i], gh))
                    ++count;
            }
        return count;
    }

    // Whether every face that f crosses lies in f's plane: parallel normals, corners within a
    // millionth of f's longest edge of it (rounding, on a plane that is not axis-aligned).
    bool crossings_in_plane(Mesh::FaceHandle f)
    {
        const auto c = face_vertices(mesh_, f);
        const OpenMesh::Vec3d a = mesh_.point(c[0]), b = mesh_.point(c[1]), d = mesh_.point(c[2]);
        const OpenMesh::Vec3d n = OpenMesh::cross(b - a, d - a).normalized();
        const double tolerance = 1e-6 * std::sqrt(std::max({(b - a).sqrnorm(), (d - b).sqrnorm(), (a - d).sqrnorm()}));
        for (const int g : grid_.near(face_box(mesh_, f))) {
            const Mesh::FaceHandle gh(g);
            if (gh == f)
                continue;
            ++tests_;
            if (!faces_intersect(mesh_, f, gh))
                continue;
            for (const auto v : mesh_.fv_range(gh))
                if (std::abs(OpenMesh::dot(mesh_.point(v) - a, n)) > tolerance)
                    return false;
        }
        return true;
    }

    // Area above a millionth of the longest edge squared: an edit never makes a needle or a cap that
    // is nearly a segment (mesh_stats counts such faces as degenerate; their normals are noise). Far
    // stricter than vec3.h's has_area, which only tells area from rounding noise.
    bool has_area(Mesh::FaceHandle f) const { return has_area(face_vertices(mesh_, f)); }
    bool has_area(const std::array<Mesh::VertexHandle, 3>& c) const
    {
        const OpenMesh::Vec3d a = mesh_.point(c[0]), b = mesh_.point(c[1]), d = mesh_.point(c[2]);
        const double longest = std::max({(b - a).sqrnorm(), (d - b).sqrnorm(), (a - d).sqrnorm()});
        return OpenMesh::cross(b - a, d - a).norm() > 2e-6 * longest;
    }

    bool faces_up(const OpenMesh::Vec3d& n) const { return !options_.vertical || OpenMesh::dot(n, to_point(options_.axis)) > 0.0; }

    bool try_flip(Mesh::EdgeHandle e)
    {
        if (mesh_.is_boundary(e) || !mesh_.is_flip_ok(e))
            return false;
        const auto h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
        const auto f0 = mesh_.face_handle(h0), f1 = mesh_.face_handle(h1);
        const std::vector<Mesh::FaceHandle> pair{f0, f1};
        const std::size_t before = hits(pair);
        if (before == 0)
            return false;
        const OpenMesh::Vec3d old_normal = (mesh_.calc_face_normal(f0) + mesh_.calc_face_normal(f1)).normalized();
        auto corners0 = face_vertices(mesh_, f0);
        std::sort(corners0.begin(), corners0.end());
        mesh_.flip(e);
        const OpenMesh::Vec3d n0 = mesh_.calc_face_normal(f0), n1 = mesh_.calc_face_normal(f1);
        if (OpenMesh::dot(n0, old_normal) > min_cos_ && OpenMesh::dot(n1, old_normal) > min_cos_ && faces_up(n0) &&
            faces_up(n1) && has_area(f0) && has_area(f1) && hits(pair) < before) {
            if (tile_.is_valid() && mesh_.property(tile_, f0) != mesh_.property(tile_, f1)) {
                mesh_.property(tile_, f0) = mesh_.property(tile_, f1) = -1;
                if (gap_.is_valid())
                    mesh_.property(gap_, f0) = mesh_.property(gap_, f1) = true;
            }
            grid_.insert(f0);
            grid_.insert(f1);
            changed_.push_back(f0);
            changed_.push_back(f1);
            return true;
        }
        // The other diagonal again: the same two triangles, but OpenMesh may hand them back to the
        // two face handles the other way round. Then their ids go with them, and both are filed anew
        // in the grid (each now has the other's box).
        mesh_.flip(e);
        auto sorted_corners = [&](Mesh::FaceHandle f) {
            auto c = face_vertices(mesh_, f);
            std::sort(c.begin(), c.end());
            return c;
        };
        if (sorted_corners(f0) != corners0) {
            if (tile_.is_valid())
                std::swap(mesh_.property(tile_, f0), mesh_.property(tile_, f1));
            if (gap_.is_valid()) {
                const bool g0 = mesh_.property(gap_, f0);
                mesh_.property(gap_, f0) = mesh_.property(gap_, f1);
                mesh_.property(gap_, f1) = g0;
            }
            grid_.insert(f0);
            grid_.insert(f1);
            changed_.push_back(f0); // the same two triangles, under each other's handle
            changed_.push_back(f1);
        }
        return false;
    }

    // A candidate move: toward the neighbours' centre by `amount` of the way, or along the vertex
    // normal by `amount` of the shortest edge.
    struct Move
    {
        bool along_normal;
        double amount;
    };

    bool try_move(Mesh::VertexHandle v, Move move)
    {
        if (mesh_.is_boundary(v))
            return false; // a border vertex has no centre to move to
        OpenMesh::Vec3d centre(0, 0, 0);
        double shortest = std::numeric_limits<double>::max();
        int neighbours = 0;
        for (const auto w : mesh_.vv_range(v)) {
            centre += mesh_.point(w);
            shortest = std::min(shortest, (mesh_.point(w) - mesh_.point(v)).norm());
            ++neighbours;
        }
        if (neighbours == 0)
            return false;
        centre /= static_cast<double>(neighbours);
        const OpenMesh::Vec3d start = mesh_.point(v);
        OpenMesh::Vec3d step = (centre - start) * move.amount;
        if (move.along_normal) {
            OpenMesh::Vec3d normal(0, 0, 0);
            for (const auto f : mesh_.vf_range(v))
                normal += mesh_.calc_face_normal(f);
            if (normal.norm() == 0.0)
                return false;
            step = normal.normalized() * (move.amount * shortest);
        }
        const double limit = options_.max_move * shortest;
        if (step.norm() > limit)
            step *= limit / step.norm();
        if (step.norm() == 0.0)
            return false;
        std::vector<Mesh::FaceHandle> faces;
        for (const auto f : mesh_.vf_range(v))
            faces.push_back(f);
        std::sort(faces.begin(), faces.end());
        std::vector<OpenMesh::Vec3d> normals;
        for (const auto f : faces)
            normals.push_back(mesh_.calc_face_normal(f));
        const std::size_t before = hits(faces);
        if (before == 0)
            return false;
        mesh_.point(v) = start + step;
        bool ok = true;
        for (std::size_t i = 0; i < faces.size() && ok; ++i)
            ok = OpenMesh::dot(mesh_.calc_face_normal(faces[i]), normals[i]) > min_cos_ && faces_up(mesh_.calc_face_normal(faces[i])) &&
                 has_area(faces[i]);
        if (ok) {
            for (const auto f : faces)
                grid_.insert(f);
            if (hits(faces) < before) {
                changed_.insert(changed_.end(), faces.begin(), faces.end());
                return true;
            }
        }
        mesh_.point(v) = start;
        return false;
    }

    // Collapses the half-edge's start into its end (OpenMesh's collapse, where is_collapse_ok allows
    // it: the topology stays) when the faces around the start, with the end in its place, cross fewer
    // faces than they did, within the turn and area limits of the other edits. Judged on the corners
    // before the collapse, which cannot be undone. Border vertices stay.
    bool try_collapse(Mesh::HalfedgeHandle he)
    {
        const auto from = mesh_.from_vertex_handle(he), to = mesh_.to_vertex_handle(he);
        if (mesh_.is_boundary(from) || mesh_.is_boundary(mesh_.edge_handle(he)))
            return false;
        if (!requested_status_) { // statuses mark what a collapse removes (OpenMesh counts requests)
            mesh_.request_vertex_status();
            mesh_.request_edge_status();
            mesh_.request_halfedge_status();
            mesh_.request_face_status();
            requested_status_ = true;
        }
        if (!mesh_.is_collapse_ok(he))
            return false;
        const auto gone0 = mesh_.face_handle(he), gone1 = mesh_.face_handle(mesh_.opposite_halfedge_handle(he));
        std::vector<Mesh::FaceHandle> around;
        for (const auto f : mesh_.vf_range(from))
            around.push_back(f);
        std::sort(around.begin(), around.end());
        std::vector<Mesh::FaceHandle> kept;
        std::vector<std::array<Mesh::VertexHandle, 3>> corners;
        for (const auto f : around) {
            if (f == gone0 || f == gone1)
                continue;
            auto c = face_vertices(mesh_, f);
            for (auto& v : c)
                if (v == from)
                    v = to;
            if (!has_area(c))
                return false;
            const OpenMesh::Vec3d n = OpenMesh::cross(mesh_.point(c[1]) - mesh_.point(c[0]), mesh_.point(c[2]) - mesh_.point(c[0])).normalized();
            if (OpenMesh::dot(n, mesh_.calc_face_normal(f)) <= min_cos_ || !faces_up(n))
                return false;
            kept.push_back(f);
            corners.push_back(c);
        }
        const std::size_t before = hits(around);
        if (before == 0)
            return false;
        std::size_t after = 0;
        for (std::size_t i = 0; i < corners.size() && after < before; ++i) {
            for (const int g : grid_.near(corners_box(mesh_, corners[i]))) {
                if (std::binary_search(around.begin(), around.end(), Mesh::FaceHandle(g)))
                    continue; // replaced by `corners`, or removed
                ++tests_;
                if (corners_intersect(mesh_, corners[i], face_vertices(mesh_, Mesh::FaceHandle(g))))
                    ++after;
            }
            for (std::size_t j = 0; j < i; ++j) {
                ++tests_;
                if (corners_intersect(mesh_, corners[i], corners[j]))
                    ++after;
            }
        }
        if (after >= before)
            return false;
        OpenMesh::VPropHandleT<int> cluster;
        const bool clusters = mesh_.get_property_handle(cluster, kVertexCluster);
        mesh_.collapse(he);
        for (const auto f : kept) {
            // A fan face that now has a corner of another tile is a gap face, as after a flip.
            if (clusters && tile_.is_valid() && mesh_.property(tile_, f) >= 0 && mesh_.property(cluster, to) != mesh_.property(tile_, f)) {
                mesh_.property(tile_, f) = -1;
                if (gap_.is_valid())
                    mesh_.property(gap_, f) = true;
            }
            grid_.insert(f);
            changed_.push_back(f);
        }
        changed_.push_back(gone0);
        changed_.push_back(gone1);
        return true;
    }

    Mesh& mesh_;
    const UntangleOptions& options_;
    double min_cos_;
    FaceGrid grid_;
    OpenMesh::FPropHandleT<int> tile_;
    OpenMesh::FPropHandleT<bool> gap_;
    std::size_t tests_ = 0;
    bool requested_status_ = false; // by try_collapse: released again at the end
    std::vector<Mesh::FaceHandle> changed_; // faces an edit changed since the last update_pairs
    std::vector<std::uint8_t> tries_ = std::vector<std::uint8_t>(mesh_.n_faces(), 0);
};

// Removes, from each pair left, a gap face with exactly one border edge whose third corner is not on
// the border (so the mesh stays a manifold), and drops the pairs it was in. Returns the faces removed.
std::size_t remove_border_folds(Mesh& mesh, std::vector<std::pair<int, int>>& pairs)
{
    OpenMesh::FPropHandleT<bool> gap;
    if (!mesh.get_property_handle(gap, kFaceGap))
        return 0;
    auto removable = [&](Mesh::FaceHandle f) {
        if (!mesh.property(gap, f))
            return false;
        int border_edges = 0;
        Mesh::VertexHandle third;
        for (const Mesh::HalfedgeHandle h : mesh.fh_range(f))
            if (mesh.is_boundary(mesh.opposite_halfedge_handle(h))) {
                ++border_edges;
                third = mesh.to_vertex_handle(mesh.next_halfedge_handle(h));
            }
        return border_edges == 1 && !mesh.is_boundary(third);
    };
    // Faces are deleted one by one (a deletion changes its neighbours' borders), so statuses are needed
    // from the first; a face already deleted is in `removed`.
    std::vector<int> removed;
    for (const auto& [a, b] : pairs) {
        if (std::binary_search(removed.begin(), removed.end(), a) || std::binary_search(removed.begin(), removed.end(), b))
            continue;
        for (const int f : {a, b})
            if (removable(Mesh::FaceHandle(f))) {
                if (removed.empty()) {
                    mesh.request_vertex_status();
                    mesh.request_edge_status();
                    mesh.request_halfedge_status();
                    mesh.request_face_status();
                }
                mesh.delete_face(Mesh::FaceHandle(f), false);
                removed.insert(std::lower_bound(removed.begin(), removed.end(), f), f);
                break;
            }
    }
    if (removed.empty())
        return 0;
    // The pairs left only count now (garbage collection renumbers the faces).
    pairs.erase(std::remove_if(pairs.begin(), pairs.end(), [&](const std::pair<int, int>& p) {
                    return std::binary_search(removed.begin(), removed.end(), p.first) ||
                           std::binary_search(removed.begin(), removed.end(), p.second);
                }),
                pairs.end());
    mesh.garbage_collection();
    return removed.size();
}

} // namespace

void check_untangle_options(const UntangleOptions& options)
{
    // A NaN, negative or huge tests_per_face was converted to the work bound's integer (undefined
    // behaviour), and NaN moves or turns refused or allowed every edit without a word.
    if (options.max_rounds < 0 || !(options.max_move >= 0.0) || !std::isfinite(options.max_move) ||
        !(options.max_turn_degrees >= 0.0 && options.max_turn_degrees <= 180.0) || !(options.tests_per_face >= 0.0) ||
        !(options.tests_per_face <= 1e9) || (options.vertical && !(squared_norm(options.axis) > 0.0)))
        throw InvalidInput("untangle: max_rounds must be >= 0 (0 = off), max_move >= 0 (finite), max_turn_degrees in [0, 180], "
                           "tests_per_face in [0, 1e9], and a vertical untangling needs a non-zero axis");
}

UntangleStats untangle(Mesh& mesh, const UntangleOptions& options)
{
    return untangle(mesh, options, self_intersecting_faces(mesh));
}

UntangleStats untangle(Mesh& mesh, const UntangleOptions& options, std::vector<std::pair<int, int>> pairs)
{
    check_untangle_options(options);
    const auto faces = static_cast<int>(mesh.n_faces());
    for (const auto& [a, b] : pairs)
        if (a < 0 || b < 0 || a >= faces || b >= faces || a == b)
            throw InvalidInput("untangle: a given pair (" + std::to_string(a) + ", " + std::to_string(b) +
                               ") does not name two faces of the mesh");
    UntangleStats stats;
    stats.pairs_before = pairs.size();
    if (pairs.empty())
        return stats;
    Untangler untangler(mesh, options);
    // A crumpled surface (a noisy sample meshed below its noise floor) can cross itself everywhere; the
    // edits are for the few crossings of a clean one, so their work is bounded by the mesh's size.
    const auto budget = std::max(kMinTests, static_cast<std::size_t>(options.tests_per_face * static_cast<double>(mesh.n_faces())));
    for (int round = 0; round < options.max_rounds && !pairs.empty(); ++round) {
        std::vector<int> faces;
        for (const auto& [a, b] : pairs) {
            faces.push_back(a);
            faces.push_back(b);
        }
        std::sort(faces.begin(), faces.end());
        faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
        const std::size_t edits = stats.flips + stats.moves + stats.collapses;
        for (const int f : faces)
            untangler.repair(Mesh::FaceHandle(f), stats, budget);
        pairs = untangler.update_pairs(pairs);
        if (stats.flips + stats.moves + stats.collapses == edits || untangler.tests() >= budget)
            break; // nothing more this way, or out of budget
    }
    stats.tests = untangler.tests();
    // Face indices stay as they are up to here (remove_border_folds works on them), then the collapsed
    // faces and vertices go.
    if (options.remove_border_folds && !pairs.empty())
        stats.removed_faces = remove_border_folds(mesh, pairs);
    if (stats.collapses > 0)
        mesh.garbage_collection();
    if (untangler.requested_status()) { // the mesh leaves with the status bits it came with
        mesh.release_vertex_status();
        mesh.release_edge_status();
        mesh.release_halfedge_status();
        mesh.release_face_status();
    }
    stats.pairs_after = pairs.size();
    if (stats.flips + stats.moves + stats.collapses + stats.removed_faces > 0)
        mesh.update_normals();
    return stats;
}

} // namespace mrt
