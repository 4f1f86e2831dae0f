// Beyond the paper: its tiles meet at a sharp edge of the sampled surface through gap triangles
// between their rims (§4.3), and the vertex fit then moves those rims onto the points of both sides.
// Where a rim vertex ends up beyond the edge, a face turns back over its neighbour and stands out as a
// spike (QA round 72: 19 such folds on the shared fandisk, 25 on a box, 39 on the demo's plate, 21 on
// the bunny). The repair is the edge flip of mesh optimisation (Hoppe et al. 1993): it changes two
// faces and never the topology, so every guarantee of the surface stage holds after it. Where no flip
// helps, a spike's tip moves back towards its neighbours, bounded by the points (a vertex on a sampled
// corner stays). A change whose faces would cross another face is undone: the pass adds no crossing.
#include "libmrtile/remove_folds.h"

#include "libmrtile/errors.h"
#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh_stats.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace mrt {
namespace {

// A vertex whose faces' angles sum to less than this is a tip (a cube's corner: 3/2 pi; the spikes a
// fold leaves: about pi); only tips move, so that the corners and edges of the sample keep their place.
constexpr double kTipAngleSum = 1.25 * kPi;

Vec3 point(const Mesh& mesh, Mesh::VertexHandle vh) { return to_vec3(mesh.point(vh)); }

// The angle between the normals of triangles f and g, in radians (0: flat, pi: folded flat onto each
// other); pi for a triangle without area, whose normal is no direction.
double fold_between(const std::array<Vec3, 3>& f, const std::array<Vec3, 3>& g)
{
    if (!has_area(f[0], f[1], f[2]) || !has_area(g[0], g[1], g[2]))
        return kPi;
    return angle_between(normalized(cross(f[1] - f[0], f[2] - f[0])), normalized(cross(g[1] - g[0], g[2] - g[0])));
}

// The fold across half-edge h's edge (interior), as the mesh stands.
double fold_at(const Mesh& mesh, Mesh::HalfedgeHandle h)
{
    return fold_between(face_corners(mesh, mesh.face_handle(h)), face_corners(mesh, mesh.opposite_face_handle(h)));
}

// The fold across half-edge `out`'s edge if the face inside it, left of `out`, were `inside`: kept
// out of the comparison (-1) where `out`'s edge is a border.
double fold_with(const Mesh& mesh, Mesh::HalfedgeHandle out, const std::array<Vec3, 3>& inside)
{
    const Mesh::FaceHandle other = mesh.opposite_face_handle(out);
    return other.is_valid() ? fold_between(inside, face_corners(mesh, other)) : -1.0;
}

class FoldRemover
{
public:
    FoldRemover(Mesh& mesh, const FoldOptions& options, const std::vector<std::pair<int, int>>* keep_pairs, const Hierarchy* sample)
        : mesh_(mesh), options_(options), sample_(sample), fold_(radians(options.fold_angle_degrees)),
          max_face_angle_(radians(options.max_face_angle_degrees)), kept_(mesh.n_faces(), false)
    {
        has_tiles_ = mesh_.get_property_handle(tile_, kFaceTile) && mesh_.get_property_handle(gap_, kFaceGap);
        if (keep_pairs)
            for (const auto& [f, g] : *keep_pairs)
                for (const int x : {f, g})
                    if (x >= 0 && static_cast<std::size_t>(x) < kept_.size())
                        kept_[static_cast<std::size_t>(x)] = true;
    }

    FoldStats run()
    {
        FoldStats stats;
        stats.folds_before = count_folds();
        for (int pass = 0; pass < options_.passes; ++pass) {
            const std::size_t kept = flip_pass(stats) + move_pass(stats);
            if (kept == 0)
                break;
        }
        stats.folds_after = count_folds();
        mesh_.update_normals();
        return stats;
    }

private:
    struct Flip
    {
        Mesh::EdgeHandle edge;
        Mesh::VertexHandle c, d; // the far corners of f0 = (a, b, c) and f1 = (b, a, d)
        int tile0, tile1;
        bool gap0, gap1;
    };

    std::size_t count_folds() const
    {
        std::size_t n = 0;
        for (const auto e : mesh_.edges())
            if (!mesh_.is_boundary(e) && fold_at(mesh_, mesh_.halfedge_handle(e, 0)) > fold_)
                ++n;
        return n;
    }

    // Whether flipping e lowers the largest fold of its quad's five edges and leaves none of them above
    // the limit, without a face lacking area, a new cap or (vertical) a face turned from the axis.
    bool improves(Mesh::EdgeHandle e) const
    {
        const auto h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
        const auto n0 = mesh_.next_halfedge_handle(h0), p0 = mesh_.prev_halfedge_handle(h0); // b -> c, c -> a
        const auto n1 = mesh_.next_halfedge_handle(h1), p1 = mesh_.prev_halfedge_handle(h1); // a -> d, d -> b
        const Vec3 a = point(mesh_, mesh_.from_vertex_handle(h0)), b = point(mesh_, mesh_.to_vertex_handle(h0));
        const Vec3 c = point(mesh_, mesh_.to_vertex_handle(n0)), d = point(mesh_, mesh_.to_vertex_handle(n1));
        const std::array<Vec3, 3> old0{a, b, c}, old1{b, a, d}, new0{c, a, d}, new1{d, b, c};
        if (!has_area(c, a, d) || !has_area(d, b, c))
            return false;
        const double fold_now = fold_between(old0, old1);
        if (!(fold_now > fold_))
            return false;
        const double before = std::max({fold_now, fold_with(mesh_, mesh_.opposite_halfedge_handle(n0), old0),
                                        fold_with(mesh_, mesh_.opposite_halfedge_handle(p0), old0),
                                        fold_with(mesh_, mesh_.opposite_halfedge_handle(n1), old1),
                                        fold_with(mesh_, mesh_.opposite_halfedge_handle(p1), old1)});
        // After the flip: c -> a and a -> d bound (c, a, d); d -> b and b -> c bound (d, b, c).
        const double after = std::max({fold_between(new0, new1), fold_with(mesh_, mesh_.opposite_halfedge_handle(p0), new0),
                                       fold_with(mesh_, mesh_.opposite_halfedge_handle(n1), new0),
                                       fold_with(mesh_, mesh_.opposite_halfedge_handle(p1), new1),
                                       fold_with(mesh_, mesh_.opposite_halfedge_handle(n0), new1)});
        if (!(after < before) || after > fold_)
            return false;
        const double new_angle = std::max(largest_angle(c, a, d), largest_angle(d, b, c));
        if (new_angle > max_face_angle_ && new_angle > std::max(largest_angle(a, b, c), largest_angle(b, a, d)))
            return false;
        if (options_.vertical && (!(dot(cross(a - c, d - c), options_.axis) > 0.0) || !(dot(cross(b - d, c - d), options_.axis) > 0.0)))
            return false;
        return true;
    }

    // One pass: the folded edges in edge order, each face flipped at most once, then the flips whose
    // new faces cross another face undone. Returns the flips kept.
    std::size_t flip_pass(FoldStats& stats)
    {
        std::vector<bool> touched(mesh_.n_faces(), false);
        std::vector<Flip> flips;
        std::vector<std::vector<int>> faces_of; // of each flip
        for (const auto e : mesh_.edges()) {
            if (mesh_.is_boundary(e) || !mesh_.is_flip_ok(e))
                continue;
            const auto h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
            const auto f0 = mesh_.face_handle(h0), f1 = mesh_.face_handle(h1);
            const auto i0 = static_cast<std::size_t>(f0.idx()), i1 = static_cast<std::size_t>(f1.idx());
            if (touched[i0] || touched[i1] || kept_[i0] || kept_[i1] || !improves(e))
                continue;
            Flip flip{e, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h0)), mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h1)),
                      has_tiles_ ? mesh_.property(tile_, f0) : -1, has_tiles_ ? mesh_.property(tile_, f1) : -1,
                      has_tiles_ && mesh_.property(gap_, f0), has_tiles_ && mesh_.property(gap_, f1)};
            mesh_.flip(e);
            if (has_tiles_ && flip.tile0 != flip.tile1) {
                mesh_.property(tile_, f0) = mesh_.property(tile_, f1) = -1;
                mesh_.property(gap_, f0) = mesh_.property(gap_, f1) = true;
            }
            touched[i0] = touched[i1] = true;
            faces_of.push_back({f0.idx(), f1.idx()});
            flips.push_back(flip);
        }
        if (flips.empty())
            return 0;
        // A flip across a thin part can put a new face through the other side: undo it (its faces go
        // back to what they were).
        const std::vector<bool> undo = crossing_changes(faces_of, std::vector<bool>(flips.size(), false), [&](std::size_t k) {
            const Flip& flip = flips[k];
            mesh_.flip(flip.edge); // the quad's other diagonal again: a -> b
            if (has_tiles_)
                for (const int fi : faces_of[k]) {
                    const Mesh::FaceHandle f(fi);
                    bool has_c = false;
                    for (const auto v : mesh_.fv_range(f))
                        has_c = has_c || v == flip.c;
                    mesh_.property(tile_, f) = has_c ? flip.tile0 : flip.tile1;
                    mesh_.property(gap_, f) = has_c ? flip.gap0 : flip.gap1;
                }
        });
        const std::size_t kept = flips.size() - static_cast<std::size_t>(std::count(undo.begin(), undo.end(), true));
        stats.undone += flips.size() - kept;
        stats.flips += kept;
        return kept;
    }

    // The largest fold among the edges of the faces around v (its spokes and its link), as the mesh stands.
    double star_fold(Mesh::VertexHandle v) const
    {
        double worst = 0.0;
        for (const auto f : mesh_.vf_range(v))
            for (const auto h : mesh_.fh_range(f))
                if (!mesh_.is_boundary(mesh_.edge_handle(h)))
                    worst = std::max(worst, fold_at(mesh_, h));
        return worst;
    }

    // Whether the faces around v, as v stands now, all have area, make no cap beyond the largest angle
    // they had before (`old_angle`) and (vertical) face along the axis.
    bool star_shape_ok(Mesh::VertexHandle v, double old_angle) const
    {
        for (const auto f : mesh_.vf_range(v)) {
            const std::array<Vec3, 3> p = face_corners(mesh_, f);
            if (!has_area(p[0], p[1], p[2]))
                return false;
            const double angle = largest_angle(p[0], p[1], p[2]);
            if (angle > max_face_angle_ && angle > old_angle)
                return false;
            if (options_.vertical && !(dot(cross(p[1] - p[0], p[2] - p[0]), options_.axis) > 0.0))
                return false;
        }
        return true;
    }

    // Undoes changes (each given by the faces it changed) whose faces cross another face, and those
    // marked in `undo` from the start, by calling undo_change(k); repeated, since a face put back can
    // cross a change kept beside it, which was tested against the face as changed. Returns the
    // changes undone.
    template <typename Undo>
    std::vector<bool> crossing_changes(const std::vector<std::vector<int>>& faces_of, std::vector<bool> undo, const Undo& undo_change)
    {
        std::vector<int> owner(mesh_.n_faces(), -1); // the change of a face
        std::vector<int> faces;
        for (std::size_t k = 0; k < faces_of.size(); ++k)
            for (const int f : faces_of[k]) {
                owner[static_cast<std::size_t>(f)] = static_cast<int>(k);
                faces.push_back(f);
            }
        for (std::size_t k = 0; k < undo.size(); ++k)
            if (undo[k])
                undo_change(k);
        // Until no kept change crosses: first every change whose faces cross, then the kept ones that a
        // face put back crosses (a pair of two faces put back, or of one and an untouched face, was
        // there before the pass).
        for (bool more = true; more;) {
            more = false;
            for (const auto& [f, g] : intersecting_pairs_with(mesh_, faces))
                for (const int x : {f, g}) {
                    const int k = owner[static_cast<std::size_t>(x)];
                    if (k >= 0 && !undo[static_cast<std::size_t>(k)]) {
                        undo[static_cast<std::size_t>(k)] = true;
                        undo_change(static_cast<std::size_t>(k));
                        more = true;
                    }
                }
        }
        return undo;
    }

    // The sum of the angles of the faces at v (2 pi where the surface is flat around it).
    double angle_sum(Mesh::VertexHandle v) const
    {
        double sum = 0.0;
        const Vec3 p = point(mesh_, v);
        for (const auto h : mesh_.voh_range(v)) {
            if (mesh_.is_boundary(h))
                continue;
            const Vec3 q = point(mesh_, mesh_.to_vertex_handle(h)), r = point(mesh_, mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h)));
            sum += angle_between(q - p, r - p);
        }
        return sum;
    }

    // Where a flip cannot help (a spike's tip: every diagonal around it folds), a corner of a folded
    // edge moves to the middle of its neighbours when that lowers the largest fold around it below the
    // limit; border vertices stay (the border is the sample's). Each face changes at most once per
    // pass; moves whose faces then cross another face are undone. Returns the moves kept.
    std::size_t move_pass(FoldStats& stats)
    {
        std::vector<bool> candidate(mesh_.n_vertices(), false);
        for (const auto e : mesh_.edges()) {
            if (mesh_.is_boundary(e))
                continue;
            const auto h0 = mesh_.halfedge_handle(e, 0), h1 = mesh_.halfedge_handle(e, 1);
            if (!(fold_at(mesh_, h0) > fold_))
                continue;
            for (const auto v : {mesh_.from_vertex_handle(h0), mesh_.to_vertex_handle(h0), mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h0)),
                                 mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h1))})
                candidate[static_cast<std::size_t>(v.idx())] = true;
        }
        // How far each candidate stands from the sample (squared): as far as it may move (a vertex on a
        // point of a real corner stays; a spike's tip, off the points, may come back that far).
        std::vector<double> reach_sq(mesh_.n_vertices(), std::numeric_limits<double>::infinity());
        if (sample_) {
            std::vector<Vec3> queries;
            std::vector<std::size_t> which;
            for (std::size_t i = 0; i < candidate.size(); ++i)
                if (candidate[i]) {
                    queries.push_back(point(mesh_, Mesh::VertexHandle(static_cast<int>(i))));
                    which.push_back(i);
                }
            const std::vector<double> d = squared_nearest_point_distances(*sample_, sample_->cloud.positions, queries, 1);
            for (std::size_t k = 0; k < which.size(); ++k)
                reach_sq[which[k]] = d[k];
        }
        std::vector<bool> touched(mesh_.n_faces(), false);
        std::vector<std::pair<Mesh::VertexHandle, Mesh::Point>> moves; // vertex, where it was
        for (std::size_t i = 0; i < candidate.size(); ++i) {
            if (!candidate[i])
                continue;
            const Mesh::VertexHandle v(static_cast<int>(i));
            if (mesh_.status(v).deleted() || mesh_.is_boundary(v) || !(angle_sum(v) < kTipAngleSum))
                continue;
            bool free = true, protect = false;
            double old_angle = 0.0;
            for (const auto f : mesh_.vf_range(v)) {
                const auto k = static_cast<std::size_t>(f.idx());
                free = free && !touched[k];
                protect = protect || kept_[k];
                const std::array<Vec3, 3> p = face_corners(mesh_, f);
                old_angle = std::max(old_angle, largest_angle(p[0], p[1], p[2]));
            }
            if (!free || protect)
                continue;
            Mesh::Point middle(0.0, 0.0, 0.0);
            int n = 0;
            for (const auto w : mesh_.vv_range(v)) {
                middle += mesh_.point(w);
                ++n;
            }
            if (n < 3)
                continue;
            middle /= static_cast<double>(n);
            const Mesh::Point was = mesh_.point(v);
            const double before = star_fold(v);
            // The shortest move that does it: a tip that stands for a real edge keeps most of its place.
            bool moved = false;
            for (const double t : {0.125, 0.25, 0.5, 1.0}) {
                if (t * (middle - was).norm() > std::sqrt(reach_sq[i]))
                    break;
                mesh_.set_point(v, was + t * (middle - was));
                const double after = star_fold(v);
                if (after < before && !(after > fold_) && star_shape_ok(v, old_angle)) {
                    moved = true;
                    break;
                }
            }
            if (!moved) {
                mesh_.set_point(v, was);
                continue;
            }
            for (const auto f : mesh_.vf_range(v))
                touched[static_cast<std::size_t>(f.idx())] = true;
            moves.emplace_back(v, was);
        }
        if (moves.empty())
            return 0;
        // A tip that stands for the sample (a vertex on a point of a real corner) keeps its place: a
        // move that takes it farther from the nearest sample point is undone, as is one whose faces
        // then cross another face.
        std::vector<bool> farther(moves.size(), false);
        if (sample_) {
            std::vector<Vec3> queries;
            for (const auto& [v, was] : moves)
                queries.push_back(point(mesh_, v));
            const std::vector<double> d = squared_nearest_point_distances(*sample_, sample_->cloud.positions, queries, 1);
            for (std::size_t k = 0; k < moves.size(); ++k)
                farther[k] = d[k] > reach_sq[static_cast<std::size_t>(moves[k].first.idx())];
        }
        std::vector<std::vector<int>> faces_of(moves.size());
        for (std::size_t k = 0; k < moves.size(); ++k)
            for (const auto f : mesh_.vf_range(moves[k].first))
                faces_of[k].push_back(f.idx());
        const std::vector<bool> undo =
            crossing_changes(faces_of, farther, [&](std::size_t k) { mesh_.set_point(moves[k].first, moves[k].second); });
        const std::size_t kept = moves.size() - static_cast<std::size_t>(std::count(undo.begin(), undo.end(), true));
        stats.undone += moves.size() - kept;
        stats.moves += kept;
        return kept;
    }

    Mesh& mesh_;
    const FoldOptions& options_;
    const Hierarchy* sample_;
    double fold_, max_face_angle_;
    std::vector<bool> kept_; // faces of keep_pairs
    bool has_tiles_ = false;
    OpenMesh::FPropHandleT<int> tile_;
    OpenMesh::FPropHandleT<bool> gap_;
};

} // namespace

void check_fold_options(const FoldOptions& options)
{
    const auto angle_ok = [](double a) { return a > 0.0 && a <= 180.0; };
    if (!angle_ok(options.fold_angle_degrees) || !angle_ok(options.max_face_angle_degrees) || options.passes < 0 || options.passes > 64 ||
        (options.vertical && !(squared_norm(options.axis) > 0.0)) || !std::isfinite(options.axis.x) || !std::isfinite(options.axis.y) ||
        !std::isfinite(options.axis.z))
        throw InvalidInput("remove_folds: fold_angle_degrees and max_face_angle_degrees must be in (0, 180], passes in [0, 64], "
                           "and a vertical pass needs a finite, non-zero axis");
}

FoldStats remove_folds(Mesh& mesh, const FoldOptions& options, const std::vector<std::pair<int, int>>* keep_pairs,
                       const Hierarchy* sample)
{
    check_fold_options(options);
    if (mesh.n_faces() == 0 || options.fold_angle_degrees >= 180.0)
        return {};
    return FoldRemover(mesh, options, keep_pairs, sample).run();
}

} // namespace mrt
