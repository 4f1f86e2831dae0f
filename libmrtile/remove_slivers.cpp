// Beyond the paper: its reconstruction (§4.3) joins tiles with strips triangulated between their rims,
// and where two rims run side by side the strip is made of caps (faces with an angle near 180
// degrees). They are correct as geometry but their normals are noise, which every renderer shows.
// The fix is the classic one for almost-degenerate faces (as in mesh repair tools): flip a cap's long
// edge (by default the only change: no vertex moves), or collapse the short edge of a needle (opt-in).
// Both are local and keep the topology, so every guarantee of the surface stage holds after them.
#include "libmrtile/remove_slivers.h"

#include "libmrtile/errors.h"

#include <OpenMesh/Core/Utils/PropertyManager.hh>

#include <algorithm>
#include <array>
#include <cmath>

namespace mrt {
namespace {

Vec3 point(const Mesh& mesh, Mesh::VertexHandle vh) { return to_vec3(mesh.point(vh)); }

Vec3 triangle_normal(const Vec3& p, const Vec3& q, const Vec3& r) { return normalized(cross(q - p, r - p)); }

// Whether triangle (p, q, r) has an angle whose cosine is below cos_limit (< 0): the law of cosines at
// the corner opposite the longest edge, without trigonometry (this runs for every face of a mesh).
bool is_cap_triangle(const Vec3& p, const Vec3& q, const Vec3& r, double cos_limit)
{
    const double a = squared_distance(q, r), b = squared_distance(r, p), c = squared_distance(p, q);
    const double longest = std::max({a, b, c});
    const double others = a + b + c - longest;
    const double product = longest == a ? b * c : longest == b ? a * c : a * b;
    return others - longest < 2.0 * std::sqrt(product) * cos_limit;
}

class SliverRemover
{
public:
    SliverRemover(Mesh& mesh, const SliverOptions& options)
        : mesh_(mesh), options_(options), cap_cos_(std::cos(radians(options.cap_angle_degrees))),
          min_cos_(std::cos(radians(options.max_turn_degrees))), up_(normalized(options.axis))
    {
        has_tiles_ = mesh_.get_property_handle(tile_, kFaceTile) && mesh_.get_property_handle(gap_, kFaceGap);
    }

    SliverStats run()
    {
        SliverStats stats;
        count(stats.caps_before, stats.needles_before);
        if (options_.cap_angle_degrees < 180.0 || options_.needle_ratio > 0.0) {
            // The first pass looks at every face, later ones only at faces next to a change.
            std::vector<Mesh::FaceHandle> work(mesh_.faces_begin(), mesh_.faces_end());
            std::vector<char> queued(mesh_.n_faces(), 0);
            std::vector<Mesh::FaceHandle> next;
            const auto enqueue = [&](Mesh::FaceHandle g) {
                if (g.is_valid() && !mesh_.status(g).deleted() && !queued[static_cast<std::size_t>(g.idx())]) {
                    queued[static_cast<std::size_t>(g.idx())] = 1;
                    next.push_back(g);
                }
            };
            for (int pass = 0; pass < options_.passes && !work.empty(); ++pass) {
                mesh_.update_normals();
                next.clear();
                std::fill(queued.begin(), queued.end(), 0);
                for (const auto f : work) {
                    if (mesh_.status(f).deleted())
                        continue;
                    if (is_cap(f)) {
                        const auto e = flip_cap(f);
                        if (e.is_valid()) {
                            ++stats.flips;
                            for (int side = 0; side < 2; ++side) {
                                const auto g = mesh_.face_handle(mesh_.halfedge_handle(e, side));
                                enqueue(g);
                                for (const auto n : mesh_.ff_range(g))
                                    enqueue(n);
                            }
                        }
                    } else if (is_needle(f)) {
                        const auto kept = collapse_needle(f);
                        if (kept.is_valid()) {
                            ++stats.collapses;
                            for (const auto g : mesh_.vf_range(kept))
                                enqueue(g);
                        }
                    }
                }
                work.swap(next);
            }
        }
        mesh_.garbage_collection();
        mesh_.update_normals();
        count(stats.caps_after, stats.needles_after);
        return stats;
    }

private:
    bool is_cap(Mesh::FaceHandle f) const
    {
        if (options_.cap_angle_degrees >= 180.0)
            return false;
        const auto [p, q, r] = face_corners(mesh_, f);
        return is_cap_triangle(p, q, r, cap_cos_);
    }

    bool is_needle(Mesh::FaceHandle f) const
    {
        if (!(options_.needle_ratio > 0.0))
            return false;
        const auto [p, q, r] = face_corners(mesh_, f);
        const double a = squared_distance(p, q), b = squared_distance(q, r), c = squared_distance(r, p);
        return std::min({a, b, c}) < options_.needle_ratio * options_.needle_ratio * std::max({a, b, c});
    }

    void count(std::size_t& caps, std::size_t& needles) const
    {
        caps = needles = 0;
        for (const auto f : mesh_.faces()) {
            if (is_cap(f))
                ++caps;
            else if (is_needle(f))
                ++needles;
        }
    }

    // Whether a changed face with this normal keeps a height field a graph.
    bool faces_up(const Vec3& normal) const { return !options_.vertical || dot(normal, up_) > 0.0; }

    // The halfedge of f's longest (largest_first) or shortest edge.
    Mesh::HalfedgeHandle extreme_edge(Mesh::FaceHandle f, bool largest_first) const
    {
        Mesh::HalfedgeHandle best;
        double best_length = 0.0;
        for (const auto h : mesh_.fh_range(f)) {
            const double length =
                squared_distance(point(mesh_, mesh_.from_vertex_handle(h)), point(mesh_, mesh_.to_vertex_handle(h)));
            if (!best.is_valid() || (largest_first ? length > best_length : length < best_length)) {
                best = h;
                best_length = length;
            }
        }
        return best;
    }

    // Flips the long edge of cap f if the other diagonal of its quad is better and the quad nearly flat.
    Mesh::EdgeHandle flip_cap(Mesh::FaceHandle f)
    {
        const auto h0 = extreme_edge(f, true);
        const auto e = mesh_.edge_handle(h0);
        if (mesh_.is_boundary(e) || !mesh_.is_flip_ok(e))
            return Mesh::EdgeHandle();
        // h0 = a -> b in f0 = (a, b, c); h1 = b -> a in f1 = (b, a, d); flipped: (c, a, d) and (d, b, c).
        const auto h1 = mesh_.opposite_halfedge_handle(h0);
        const auto va = mesh_.from_vertex_handle(h0), vb = mesh_.to_vertex_handle(h0);
        const auto vc = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h0));
        const auto vd = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(h1));
        const Vec3 a = point(mesh_, va), b = point(mesh_, vb), c = point(mesh_, vc), d = point(mesh_, vd);
        if (!has_area(c, a, d) || !has_area(d, b, c))
            return Mesh::EdgeHandle();
        const Vec3 across = cross(a - b, d - b); // plane of the face across the long edge
        if (std::abs(dot(c - b, normalized(across))) > options_.max_flip_height * distance(a, b))
            return Mesh::EdgeHandle();
        const double before = std::max(largest_angle(a, b, c), largest_angle(b, a, d));
        const double after = std::max(largest_angle(c, a, d), largest_angle(d, b, c));
        if (!(after < before - 1e-6))
            return Mesh::EdgeHandle();
        Vec3 reference{0, 0, 0};
        for (const auto v : {va, vb, vc, vd})
            reference += to_vec3(mesh_.normal(v));
        reference = normalized(reference);
        const Vec3 n0 = triangle_normal(c, a, d), n1 = triangle_normal(d, b, c);
        if (!(dot(n0, reference) >= min_cos_) || !(dot(n1, reference) >= min_cos_) || !faces_up(n0) || !faces_up(n1))
            return Mesh::EdgeHandle();
        const auto f0 = mesh_.face_handle(h0), f1 = mesh_.face_handle(h1);
        const bool same_tile = !has_tiles_ || mesh_.property(tile_, f0) == mesh_.property(tile_, f1);
        mesh_.flip(e);
        if (!same_tile) {
            mesh_.property(tile_, f0) = mesh_.property(tile_, f1) = -1;
            mesh_.property(gap_, f0) = mesh_.property(gap_, f1) = true;
        }
        return e;
    }

    // Collapses the short edge of needle f into one of its ends (the other end's position is kept, so
    // a mesh that interpolates its points still does), if that turns no face around it too far.
    // Returns the vertex kept (invalid if nothing was collapsed).
    Mesh::VertexHandle collapse_needle(Mesh::FaceHandle f)
    {
        const auto h = extreme_edge(f, false);
        if (try_collapse(h))
            return mesh_.to_vertex_handle(h);
        const auto o = mesh_.opposite_halfedge_handle(h);
        if (try_collapse(o))
            return mesh_.to_vertex_handle(o);
        return Mesh::VertexHandle();
    }

    // collapse(h) removes h's from-vertex u and keeps its to-vertex v where it is.
    bool try_collapse(Mesh::HalfedgeHandle h)
    {
        const auto vu = mesh_.from_vertex_handle(h), vv = mesh_.to_vertex_handle(h);
        if (mesh_.is_boundary(vu) || mesh_.is_boundary(vv) || !mesh_.is_collapse_ok(h))
            return false;
        const Vec3 kept = point(mesh_, vv);
        const auto gone0 = mesh_.face_handle(h), gone1 = mesh_.face_handle(mesh_.opposite_halfedge_handle(h));
        for (const auto g : mesh_.vf_range(vu)) {
            if (g == gone0 || g == gone1)
                continue;
            const std::array<Vec3, 3> before = face_corners(mesh_, g);
            std::array<Vec3, 3> after = before;
            int k = 0;
            for (const auto w : mesh_.fv_range(g)) {
                if (w == vu)
                    after[static_cast<std::size_t>(k)] = kept;
                ++k;
            }
            if (!has_area(after[0], after[1], after[2]))
                return false;
            const Vec3 n = triangle_normal(after[0], after[1], after[2]);
            if (!(dot(triangle_normal(before[0], before[1], before[2]), n) >= min_cos_) || !faces_up(n))
                return false;
        }
        mesh_.collapse(h);
        return true;
    }

    Mesh& mesh_;
    const SliverOptions& options_;
    double cap_cos_;
    double min_cos_;
    Vec3 up_;
    bool has_tiles_ = false;
    OpenMesh::FPropHandleT<int> tile_;
    OpenMesh::FPropHandleT<bool> gap_;
};

} // namespace

std::size_t count_caps(const Mesh& mesh, double cap_angle_degrees)
{
    const double cos_limit = std::cos(radians(cap_angle_degrees));
    std::size_t caps = 0;
    for (const auto f : mesh.faces()) {
        const auto [p, q, r] = face_corners(mesh, f);
        caps += is_cap_triangle(p, q, r, cos_limit);
    }
    return caps;
}

void check_sliver_options(const SliverOptions& options)
{
    if (!(options.cap_angle_degrees > 90.0 && options.cap_angle_degrees <= 180.0) ||
        !(options.needle_ratio >= 0.0 && options.needle_ratio < 1.0) ||
        !(options.max_turn_degrees >= 0.0 && options.max_turn_degrees <= 90.0) || options.passes < 0 ||
        !(options.max_flip_height >= 0.0) || !std::isfinite(options.max_flip_height) || (options.vertical && !(squared_norm(options.axis) > 0.0)))
        throw InvalidInput("remove_slivers: cap_angle_degrees must be in (90, 180], needle_ratio in [0, 1), "
                           "max_turn_degrees in [0, 90], max_flip_height >= 0 (finite), passes >= 0, and a vertical cleanup needs a "
                           "non-zero axis");
}

SliverStats remove_slivers(Mesh& mesh, const SliverOptions& options)
{
    check_sliver_options(options);
    return SliverRemover(mesh, options).run();
}

} // namespace mrt
