// Beyond the paper: small holes that the sample covers, capped from the points (see
// close_covered_holes.h). The paper's T2 leaves such holes wherever its Delaunay faces are pruned; our
// surface stage fills most of them with a patch of the loop's own corners, which cuts through a solid
// where the loop runs along a sharp edge. The points inside the hole, as vertices, let the cap bend there.

#include "libmrtile/close_covered_holes.h"

#include "libmrtile/box_grid.h"
#include "libmrtile/errors.h"
#include "libmrtile/gap_triangulation.h"
#include "libmrtile/median.h"
#include "libmrtile/mesh_stats.h"
#include "libmrtile/polygon2d.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace mrt {

namespace {

// Inner points of a cap are kept this many spacings off its outline (closer, they make slivers) and
// this many apart (about the sample's own spacing: the fit moves them anyway).
constexpr double kOutlineMargin = 0.5;
constexpr double kThinning = 1.0;
// Rings of faces around a hole taken out to find a cap that fits, before it is given up.
constexpr int kMaxWidenings = 4;
// A ring of more than this many faces per loop edge allowed is not taken out (a vertex of very high
// valence: no small hole's rim).
constexpr std::size_t kMaxRingFaces = 8;
// A cap with a spot this many times the cover distance from every point is over a hole of the sample.
constexpr double kSampleHoleReach = 2.0;
// is_sample_hole takes a loop wider than this many spacings (its corners' box diagonal) for a hole of
// the sample without looking (about half a million spots would be judged at this width).
constexpr double kMaxJudgedSpacings = 2000.0;

void check_options(const CoveredHoleOptions& o)
{
    if (!(o.cover_spacings > 0.0) || !std::isfinite(o.cover_spacings))
        throw InvalidInput("CoveredHoleOptions::cover_spacings must be positive and finite");
    if (!(o.max_turn_degrees > 0.0 && o.max_turn_degrees < 180.0))
        throw InvalidInput("CoveredHoleOptions::max_turn_degrees must lie in (0, 180)");
    if (o.vertical && !(norm(o.axis) > 0.0 && std::isfinite(norm(o.axis))))
        throw InvalidInput("CoveredHoleOptions::axis must be a finite, non-zero direction when vertical is set");
}

// The distance from q to the polygon's outline.
double distance_to_outline(const std::vector<Point2>& polygon, const Point2& q)
{
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < polygon.size(); ++i)
        best = std::min(best, segment_distance2(q, polygon[i], polygon[(i + 1) % polygon.size()]));
    return std::sqrt(best);
}

// Whether a spot inside the polygon (on a grid radius / 1.5 apart) lies farther than `radius` from
// every point of `points`.
bool has_empty_spot(const std::vector<Point2>& polygon, const std::vector<Point2>& points, double radius)
{
    Point2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    Point2 hi{-lo[0], -lo[1]};
    for (const Point2& p : polygon)
        for (int k = 0; k < 2; ++k) {
            lo[static_cast<std::size_t>(k)] = std::min(lo[static_cast<std::size_t>(k)], p[static_cast<std::size_t>(k)]);
            hi[static_cast<std::size_t>(k)] = std::max(hi[static_cast<std::size_t>(k)], p[static_cast<std::size_t>(k)]);
        }
    const auto cell_of = [&](const Point2& p) {
        return std::make_pair(static_cast<std::int64_t>(std::floor((p[0] - lo[0]) / radius)),
                              static_cast<std::int64_t>(std::floor((p[1] - lo[1]) / radius)));
    };
    std::map<std::pair<std::int64_t, std::int64_t>, std::vector<Point2>> cells;
    for (const Point2& p : points)
        cells[cell_of(p)].push_back(p);
    const double step = radius / 1.5;
    const auto columns = static_cast<std::int64_t>(std::ceil((hi[0] - lo[0]) / step)),
               rows = static_cast<std::int64_t>(std::ceil((hi[1] - lo[1]) / step));
    for (std::int64_t i = 0; i <= columns; ++i)
        for (std::int64_t j = 0; j <= rows; ++j) {
            const Point2 spot{lo[0] + static_cast<double>(i) * step, lo[1] + static_cast<double>(j) * step};
            if (!inside_polygon(polygon, spot))
                continue;
            const auto [cx, cy] = cell_of(spot);
            bool near = false;
            for (std::int64_t dx = -1; dx <= 1 && !near; ++dx)
                for (std::int64_t dy = -1; dy <= 1 && !near; ++dy) {
                    const auto it = cells.find({cx + dx, cy + dy});
                    if (it != cells.end())
                        for (const Point2& p : it->second)
                            near = near || (p[0] - spot[0]) * (p[0] - spot[0]) + (p[1] - spot[1]) * (p[1] - spot[1]) <= radius * radius;
                }
            if (!near)
                return true;
        }
    return false;
}

BoundingBox grown(BoundingBox box, double margin)
{
    box.min = box.min - Vec3{margin, margin, margin};
    box.max = box.max + Vec3{margin, margin, margin};
    return box;
}

// The input points near a cap, bucketed in cubic cells of `reach`, to tell whether every spot of the
// cap has one within `reach`.
class PointCover
{
public:
    PointCover(const Hierarchy& h, const BoundingBox& box, double reach) : reach_(reach), origin_(grown(box, reach).min)
    {
        for (const std::uint32_t i : points_in_box(h, grown(box, reach))) {
            const Vec3& p = h.cloud.positions[i];
            cells_[key(cell(p))].push_back(p);
            points_.push_back(i);
        }
    }

    // Tree-order indices of the points gathered (ascending).
    const std::vector<std::uint32_t>& points() const { return points_; }

    // Whether every spot of triangle t (a barycentric grid at most reach / 1.5 apart) has a point
    // within reach.
    bool covers(const std::array<Vec3, 3>& t) const
    {
        const Vec3* last = nullptr;
        return all_triangle_spots(t[0], t[1], t[2], reach_ / 1.5, 200, [&](const Vec3& spot) { return near(spot, last); });
    }

    // The share of triangle t's area with no point within reach, estimated at the centres of steps²
    // equal sub-triangles (steps = the longest edge over a third of the reach, 1 to 200), each of which
    // stands for the same area.
    double share_uncovered(const std::array<Vec3, 3>& t) const
    {
        std::size_t off = 0;
        const Vec3* last = nullptr;
        const std::size_t spots =
            visit_subtriangle_centres(t[0], t[1], t[2], reach_ / 3.0, 200, [&](const Vec3& spot) { off += near(spot, last) ? 0 : 1; });
        return static_cast<double>(off) / static_cast<double>(spots);
    }

private:
    std::array<std::int64_t, 3> cell(const Vec3& p) const
    {
        // Clamped before the cast: a reach of 1e-300 made cell numbers past the int64 range (undefined;
        // QA round 51). Keys keep 21 bits of each anyway.
        const auto index = [&](double offset) {
            return static_cast<std::int64_t>(std::clamp(std::floor(offset / reach_), -0x1p52, 0x1p52));
        };
        return {index(p.x - origin_.x), index(p.y - origin_.y), index(p.z - origin_.z)};
    }
    static std::uint64_t key(const std::array<std::int64_t, 3>& c)
    {
        return (static_cast<std::uint64_t>(c[0]) & 0x1fffff) << 42 | (static_cast<std::uint64_t>(c[1]) & 0x1fffff) << 21 |
               (static_cast<std::uint64_t>(c[2]) & 0x1fffff);
    }
    // Whether a point lies within reach of `spot`. `last`: the point that answered the previous spot
    // (nullptr at first), tried first: spots come a third of the reach apart, so it mostly answers
    // this one too, and a dense sample's 27 cells hold thousands of points (the 1.5M-point bunny's
    // crack checks took a fifth of its meshing, QA round 66). Then the spot's own cell, then the rest.
    bool near(const Vec3& spot, const Vec3*& last) const
    {
        const double reach2 = reach_ * reach_;
        if (last && squared_distance(*last, spot) <= reach2)
            return true;
        const std::array<std::int64_t, 3> c = cell(spot);
        const auto in_cell = [&](std::int64_t dx, std::int64_t dy, std::int64_t dz) {
            const auto it = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
            if (it != cells_.end())
                for (const Vec3& p : it->second)
                    if (squared_distance(p, spot) <= reach2) {
                        last = &p;
                        return true;
                    }
            return false;
        };
        if (in_cell(0, 0, 0))
            return true;
        for (std::int64_t dx = -1; dx <= 1; ++dx)
            for (std::int64_t dy = -1; dy <= 1; ++dy)
                for (std::int64_t dz = -1; dz <= 1; ++dz)
                    if ((dx != 0 || dy != 0 || dz != 0) && in_cell(dx, dy, dz))
                        return true;
        return false;
    }

    double reach_;
    Vec3 origin_;
    std::unordered_map<std::uint64_t, std::vector<Vec3>> cells_;
    std::vector<std::uint32_t> points_;
};

// A hole seen along `normal` (unit) from `centre`: its outline, and the points near it within a slab as
// thick as the hole is wide (`width`: its corners' box diagonal, or 4 spacings), in the plane's
// coordinates and in space.
struct HoleView
{
    Vec3 u, v;
    std::vector<Point2> outline;
    std::vector<Point2> seen;
    std::vector<Vec3> seen_3d;
};

HoleView view_hole(const Hierarchy& h, const std::vector<Vec3>& corners, const Vec3& centre, const Vec3& normal, double width,
                   const std::vector<std::uint32_t>& near_points)
{
    HoleView view;
    view.u = perpendicular_axis(normal);
    view.v = cross(normal, view.u);
    const auto project = [&](const Vec3& p) { return Point2{dot(p - centre, view.u), dot(p - centre, view.v)}; };
    for (const Vec3& c : corners)
        view.outline.push_back(project(c));
    for (const std::uint32_t i : near_points) {
        const Vec3& p = h.cloud.positions[i];
        if (std::abs(dot(p - centre, normal)) <= width) {
            view.seen.push_back(project(p));
            view.seen_3d.push_back(p);
        }
    }
    return view;
}

// The area-weighted mean normal of the faces, or zero.
Vec3 mean_normal(const Mesh& mesh, const std::vector<Mesh::FaceHandle>& faces)
{
    Vec3 normal{0, 0, 0};
    for (const auto f : faces) {
        const std::array<Vec3, 3> t = face_corners(mesh, f);
        normal += cross(t[1] - t[0], t[2] - t[0]);
    }
    return norm(normal) > 0.0 ? normalized(normal) : Vec3{0, 0, 0};
}

class HoleCloser
{
public:
    HoleCloser(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
               const CoveredHoleOptions& o)
        : mesh_(mesh), h_(h), spacing_of_(spacing_of), o_(o), min_turn_cos_(std::cos(o.max_turn_degrees * M_PI / 180.0)),
          grid_(mean_edge_length(mesh) * 2.0)
    {
        if (!mesh_.get_property_handle(cluster_, kVertexCluster) || !mesh_.get_property_handle(tile_, kFaceTile) ||
            !mesh_.get_property_handle(gap_, kFaceGap))
            throw InvalidInput("close_covered_holes: the mesh lacks the v:cluster / f:tile / f:gap properties (mesh.h)");
    }

    CoveredHoleStats run()
    {
        // The loops as they are now, each as its border half-edges in order; a cap changes only its own.
        std::vector<std::vector<Mesh::HalfedgeHandle>> loops;
        std::vector<char> seen(mesh_.n_halfedges(), 0);
        for (const auto start : mesh_.halfedges()) {
            if (!mesh_.is_boundary(start) || seen[static_cast<std::size_t>(start.idx())])
                continue;
            std::vector<Mesh::HalfedgeHandle> loop;
            Mesh::HalfedgeHandle hh = start;
            do {
                seen[static_cast<std::size_t>(hh.idx())] = 1;
                loop.push_back(hh);
                hh = mesh_.next_halfedge_handle(hh);
            } while (hh != start && !seen[static_cast<std::size_t>(hh.idx())] && loop.size() <= o_.max_edges);
            if (hh == start && loop.size() >= 3 && loop.size() <= o_.max_edges)
                loops.push_back(std::move(loop));
        }
        if (loops.empty())
            return stats_; // a closed mesh, or only long loops: no face grid needed
        for (const auto f : mesh_.faces())
            grid_.insert(static_cast<std::uint32_t>(f.idx()), triangle_box(face_corners(mesh_, f)));
        for (const auto& loop : loops)
            close(loop);
        if (removed_any_)
            mesh_.garbage_collection();
        return stats_;
    }

private:
    double spacing(Mesh::VertexHandle v) const
    {
        const auto it = spacing_of_.find(mesh_.property(cluster_, v));
        return it == spacing_of_.end() ? 0.0 : it->second;
    }

    Vec3 point(Mesh::VertexHandle v) const { return to_vec3(mesh_.point(v)); }

    // What a try at a cap found: a cap, a hole of the sample (the points leave much of it uncovered:
    // a wider hole would be no better), or a cap that does not fit as the rim stands.
    enum class Outcome { Closed, SampleHole, Refused };

    // A hole and the faces around it that its cap replaces: the border half-edges of the hole as it
    // is once `removed` (sorted) is taken out, in order. Each names its corner (from-vertex) and, on
    // its other side, the face the cap joins there.
    struct Hole
    {
        std::vector<Mesh::HalfedgeHandle> loop;
        std::vector<Mesh::FaceHandle> removed;
        std::vector<Mesh::HalfedgeHandle> origin; //!< the hole's loop before any widening
    };

    bool is_removed(const Hole& hole, Mesh::FaceHandle f) const
    {
        return f.is_valid() && std::binary_search(hole.removed.begin(), hole.removed.end(), f);
    }

    // The faces kept: valid, and not taken out.
    bool kept(const Hole& hole, Mesh::FaceHandle f) const { return f.is_valid() && !is_removed(hole, f); }

    void close(const std::vector<Mesh::HalfedgeHandle>& loop)
    {
        // A loop that an earlier cap changed (cannot happen: widening stops at other holes) is left.
        for (const auto hh : loop)
            if (mesh_.status(mesh_.edge_handle(hh)).deleted() || !mesh_.is_boundary(hh))
                return;
        Hole hole{loop, {}, loop};
        Outcome outcome = attempt(hole);
        // Where no cap fits, the hole's rim is often what is wrong: faces folded where tiles straddle a
        // sharp edge, a slit running back on itself. The faces at the loop's corners are taken out
        // (on paper: the mesh changes only once a cap fits) and the wider hole capped from the points,
        // up to kMaxWidenings rings. A hole of the sample is not widened.
        for (int widening = 0; outcome == Outcome::Refused && widening < kMaxWidenings; ++widening) {
            if (!widen(hole))
                break;
            outcome = attempt(hole);
        }
        ++(outcome == Outcome::Closed ? stats_.closed : outcome == Outcome::SampleHole ? stats_.uncovered : stats_.refused);
    }

    // Takes the faces at the hole's corners out too (on paper) and traces the wider hole; false when
    // it is no single disc of at most max_edges edges (it reaches another hole, or pinches).
    bool widen(Hole& hole) const
    {
        std::vector<Mesh::FaceHandle> removed = hole.removed;
        const std::size_t before = removed.size();
        for (const auto hh : hole.loop)
            for (const auto f : mesh_.vf_range(mesh_.from_vertex_handle(hh)))
                removed.push_back(f);
        std::sort(removed.begin(), removed.end());
        removed.erase(std::unique(removed.begin(), removed.end()), removed.end());
        if (removed.size() == before || removed.size() > kMaxRingFaces * o_.max_edges)
            return false;
        Hole wider{{}, std::move(removed), hole.origin};
        // A corner of a removed face on another hole's border: the wider hole would merge with it.
        for (const auto f : wider.removed)
            for (const auto c : mesh_.fv_range(f))
                for (const auto hh : mesh_.voh_range(c))
                    if (!mesh_.face_handle(hh).is_valid() && std::find(hole.origin.begin(), hole.origin.end(), hh) == hole.origin.end())
                        return false;
        // The border: half-edges of removed faces, or of the hole, whose other side is kept.
        std::vector<Mesh::HalfedgeHandle> border;
        for (const auto hh : hole.origin)
            if (kept(wider, mesh_.face_handle(mesh_.opposite_halfedge_handle(hh))))
                border.push_back(hh);
        for (const auto f : wider.removed)
            for (const auto hh : mesh_.fh_range(f))
                if (kept(wider, mesh_.face_handle(mesh_.opposite_halfedge_handle(hh))))
                    border.push_back(hh);
        if (border.size() < 3 || border.size() > o_.max_edges)
            return false;
        std::unordered_map<int, Mesh::HalfedgeHandle> leaving; // corner -> its border half-edge
        for (const auto hh : border)
            if (!leaving.emplace(mesh_.from_vertex_handle(hh).idx(), hh).second)
                return false; // the wider hole pinches at a corner
        // In order, from the border half-edge of the lowest corner (deterministic), once around.
        Mesh::HalfedgeHandle start = border[0];
        for (const auto hh : border)
            if (mesh_.from_vertex_handle(hh).idx() < mesh_.from_vertex_handle(start).idx())
                start = hh;
        Mesh::HalfedgeHandle hh = start;
        do {
            wider.loop.push_back(hh);
            const auto next = leaving.find(mesh_.to_vertex_handle(hh).idx());
            if (next == leaving.end())
                return false;
            hh = next->second;
        } while (hh != start && wider.loop.size() <= border.size());
        if (hh != start || wider.loop.size() != border.size())
            return false; // more than one loop
        hole = std::move(wider);
        return true;
    }

    Outcome attempt(const Hole& hole)
    {
        const std::vector<Mesh::HalfedgeHandle>& loop = hole.loop;
        const std::size_t n = loop.size();
        std::vector<Mesh::VertexHandle> corners;
        std::vector<double> spacings;
        Vec3 centre{0, 0, 0};
        for (const auto hh : loop) {
            const Mesh::VertexHandle v = mesh_.from_vertex_handle(hh);
            corners.push_back(v);
            if (spacing(v) > 0.0)
                spacings.push_back(spacing(v));
            centre += point(v);
        }
        centre = centre / static_cast<double>(n);
        // The point spacing around: the median of the corners' tiles (not the largest: a tile whose hull
        // reaches over the hole has few points for its area, and QA round 45's 1M-point bunny had a base
        // hole capped 31 spacings from the points by such a tile's spacing).
        const double s = upper_median_in_place(spacings);
        // A loop through a vertex twice bounds two holes that touch there: not a disc to cap.
        std::vector<Mesh::VertexHandle> sorted = corners;
        std::sort(sorted.begin(), sorted.end());
        if (!(s > 0.0) || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
            return Outcome::Refused;
        // A piece of a face or two (the loop runs around all of it) is no hole in a surface.
        std::vector<Mesh::FaceHandle> beside;
        for (const auto hh : loop)
            beside.push_back(mesh_.face_handle(mesh_.opposite_halfedge_handle(hh)));
        std::sort(beside.begin(), beside.end());
        beside.erase(std::unique(beside.begin(), beside.end()), beside.end());
        if (beside.size() < 3)
            return Outcome::SampleHole;
        const double reach = o_.cover_spacings * s;
        std::vector<Vec3> corner_points;
        for (const auto c : corners)
            corner_points.push_back(point(c));
        const BoundingBox box = bounding_box(corner_points);
        const PointCover cover(h_, grown(box, kSampleHoleReach * reach), reach); // as far as an empty disc is judged
        // The plane the hole is seen in: the mean of the faces kept at its corners (across a sharp edge
        // of 90 degrees, 45 degrees from each side, so both sides project without folding). Its outline
        // must be simple (checked by the triangulation) and counter-clockwise from that side: the cap's
        // faces run along the loop's half-edges. (Other directions were tried where this one folds: the
        // best-fit plane of the corners, the rim faces' normals. They closed none more of 60 loops on 83
        // sampled solids: those loops run back and forth in space, not only in projection.)
        std::vector<Mesh::FaceHandle> around;
        for (const auto c : corners)
            for (const auto f : mesh_.vf_range(c))
                if (kept(hole, f))
                    around.push_back(f);
        std::sort(around.begin(), around.end());
        around.erase(std::unique(around.begin(), around.end()), around.end());
        const Vec3 normal = mean_normal(mesh_, around);
        if (!(norm(normal) > 0.0))
            return Outcome::Refused;
        const HoleView view = view_hole(h_, corner_points, centre, normal, std::max(box.diagonal(), 4.0 * s), cover.points());
        const std::vector<Point2>& polygon = view.outline;
        const std::vector<Point2>& seen = view.seen;
        const std::vector<Vec3>& seen_3d = view.seen_3d;
        if (!(signed_area(polygon) > 0.0))
            return Outcome::Refused;
        // Where the points seen along the normal leave an empty disc inside the outline, the hole is the
        // sample's own.
        if (has_empty_spot(polygon, seen, kSampleHoleReach * reach))
            return Outcome::SampleHole;
        // The cap's inner vertices: the points inside the outline, thinned to about one per spacing and
        // kept half a spacing off it; on the sample (a sharp edge's points among them).
        std::vector<Point2> inside;
        std::vector<Vec3> inside_3d;
        for (std::size_t i = 0; i < seen.size(); ++i) {
            const Point2& q = seen[i];
            if (!inside_polygon(polygon, q) || distance_to_outline(polygon, q) < kOutlineMargin * s)
                continue;
            bool crowded = false;
            for (const Point2& k : inside)
                crowded = crowded || (k[0] - q[0]) * (k[0] - q[0]) + (k[1] - q[1]) * (k[1] - q[1]) < kThinning * kThinning * s * s;
            if (crowded)
                continue;
            inside.push_back(q);
            inside_3d.push_back(seen_3d[i]);
        }
        const std::vector<std::array<std::uint32_t, 3>> triangles = polygon_triangles(polygon, inside);
        if (triangles.empty())
            return Outcome::Refused;
        const auto position = [&](std::uint32_t k) { return k < n ? point(corners[k]) : inside_3d[k - n]; };
        std::vector<std::array<Vec3, 3>> cap;
        for (const auto& t : triangles)
            cap.push_back({position(t[0]), position(t[1]), position(t[2])});
        // A face that cuts a corner, or joins a rim vertex far from the points, misses them.
        if (!std::all_of(cap.begin(), cap.end(), [&](const std::array<Vec3, 3>& t) { return cover.covers(t); }))
            return Outcome::Refused;
        if (!well_turned(loop, triangles, cap, normal) || joins_outside(hole, corners, triangles))
            return Outcome::Refused;
        // Added tentatively, so that the crossing test sees the cap's corners as the mesh's own.
        std::vector<Mesh::VertexHandle> handle(corners);
        std::vector<bool> used(inside.size(), false);
        for (const auto& t : triangles)
            for (const std::uint32_t k : t)
                if (k >= n)
                    used[k - n] = true;
        for (std::size_t k = 0; k < inside.size(); ++k) {
            Mesh::VertexHandle added;
            if (used[k]) {
                added = mesh_.add_vertex(to_point(inside_3d[k]));
                mesh_.property(cluster_, added) = mesh_.property(cluster_, nearest_corner(corners, inside_3d[k]));
            }
            handle.push_back(added);
        }
        const auto drop_new_vertices = [&] {
            for (std::size_t k = n; k < handle.size(); ++k)
                if (handle[k].is_valid())
                    remove_vertex(handle[k]);
        };
        std::vector<std::array<Mesh::VertexHandle, 3>> faces;
        for (const auto& t : triangles)
            faces.push_back({handle[t[0]], handle[t[1]], handle[t[2]]});
        if (crosses(hole, faces)) {
            drop_new_vertices();
            return Outcome::Refused;
        }
        // The rim taken out, then the cap put in; the vertices left without faces go.
        std::vector<Removed> taken;
        for (const auto f : hole.removed) {
            taken.push_back({face_vertices(mesh_, f), mesh_.property(tile_, f), mesh_.property(gap_, f)});
            mesh_.delete_face(f, false);
            removed_any_ = true;
        }
        std::vector<Mesh::FaceHandle> added;
        for (const auto& f : faces) {
            const Mesh::FaceHandle fh = mesh_.add_face(f[0], f[1], f[2]);
            if (!fh.is_valid())
                break; // refused (a complex edge): undone below
            added.push_back(fh);
        }
        if (added.size() < faces.size()) {
            for (const auto fh : added)
                mesh_.delete_face(fh, false);
            drop_new_vertices();
            restore(taken);
            return Outcome::Refused;
        }
        for (const auto fh : added) {
            mesh_.property(tile_, fh) = -1;
            mesh_.property(gap_, fh) = true;
            grid_.insert(static_cast<std::uint32_t>(fh.idx()), triangle_box(face_corners(mesh_, fh)));
        }
        for (const Removed& r : taken)
            for (const auto c : r.corners)
                if (!mesh_.status(c).deleted() && mesh_.is_isolated(c))
                    remove_vertex(c);
        stats_.faces += added.size();
        stats_.removed += taken.size();
        return Outcome::Closed;
    }

    // A face taken out, as it was.
    struct Removed
    {
        std::array<Mesh::VertexHandle, 3> corners;
        int tile;
        bool gap;
    };

    // Puts faces taken out back (their places are free again, so each fits).
    void restore(const std::vector<Removed>& taken)
    {
        for (auto it = taken.rbegin(); it != taken.rend(); ++it) {
            const Mesh::FaceHandle f = mesh_.add_face(it->corners[0], it->corners[1], it->corners[2]);
            assert(f.is_valid());
            if (!f.is_valid())
                continue; // cannot happen: the face's place is free (the hole would stay wider)
            mesh_.property(tile_, f) = it->tile;
            mesh_.property(gap_, f) = it->gap;
            grid_.insert(static_cast<std::uint32_t>(f.idx()), triangle_box(face_corners(mesh_, f)));
        }
    }

    // Whether every cap face faces the hole's side (its normal within 90 degrees of the plane's; in a
    // height field, up the axis) and each face on the loop turns at most max_turn from the face beside
    // it across the loop. Inner vertices lie off the plane, so a face's turn is not the projection's.
    bool well_turned(const std::vector<Mesh::HalfedgeHandle>& loop, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                     const std::vector<std::array<Vec3, 3>>& cap, const Vec3& normal) const
    {
        const std::size_t n = loop.size();
        for (std::size_t k = 0; k < cap.size(); ++k) {
            const auto& t = cap[k];
            const Vec3 c = cross(t[1] - t[0], t[2] - t[0]);
            if (!(norm(c) > 0.0) || !(dot(c, normal) > 0.0) || (o_.vertical && !(dot(c, o_.axis) > 0.0)))
                return false;
            const Vec3 face_normal = normalized(c);
            for (std::size_t e = 0; e < 3; ++e) {
                const std::uint32_t i = triangles[k][e], j = triangles[k][(e + 1) % 3];
                if (i >= n || j != (i + 1) % n)
                    continue; // not a loop edge in the loop's direction
                const Mesh::FaceHandle f = mesh_.face_handle(mesh_.opposite_halfedge_handle(loop[i]));
                if (!f.is_valid() || dot(to_vec3(mesh_.calc_face_normal(f)), face_normal) < min_turn_cos_)
                    return false;
            }
        }
        return true;
    }

    // Whether a cap face would join two corners that an edge outside the loop already joins (where the
    // loop turns back on itself across a narrow neck): that edge would get a third face.
    bool joins_outside(const Hole& hole, const std::vector<Mesh::VertexHandle>& corners,
                       const std::vector<std::array<std::uint32_t, 3>>& triangles) const
    {
        const std::size_t n = corners.size();
        for (const auto& t : triangles)
            for (std::size_t e = 0; e < 3; ++e) {
                const std::uint32_t i = t[e], j = t[(e + 1) % 3];
                if (i >= n || j >= n || (i + 1) % n == j || (j + 1) % n == i)
                    continue;
                const Mesh::HalfedgeHandle hh = mesh_.find_halfedge(corners[i], corners[j]);
                if (hh.is_valid() && (kept(hole, mesh_.face_handle(hh)) || kept(hole, mesh_.opposite_face_handle(hh))))
                    return true; // an edge that stays (one of its faces is kept)
            }
        return false;
    }

    Mesh::VertexHandle nearest_corner(const std::vector<Mesh::VertexHandle>& corners, const Vec3& p) const
    {
        std::size_t best = 0;
        for (std::size_t i = 1; i < corners.size(); ++i)
            if (squared_distance(point(corners[i]), p) < squared_distance(point(corners[best]), p))
                best = i;
        return corners[best];
    }

    // Whether a cap face meets a face of the mesh, or another cap face, other than in the corners and
    // edges they share.
    bool crosses(const Hole& hole, const std::vector<std::array<Mesh::VertexHandle, 3>>& faces) const
    {
        for (std::size_t i = 0; i < faces.size(); ++i) {
            std::array<Vec3, 3> t;
            for (std::size_t k = 0; k < 3; ++k)
                t[k] = point(faces[i][k]);
            const bool meets = grid_.any_candidate(triangle_box(t), [&](std::uint32_t id) {
                const Mesh::FaceHandle f(static_cast<int>(id));
                return !mesh_.status(f).deleted() && !is_removed(hole, f) && corners_intersect(mesh_, faces[i], face_vertices(mesh_, f));
            });
            if (meets)
                return true;
            for (std::size_t j = i + 1; j < faces.size(); ++j)
                if (corners_intersect(mesh_, faces[i], faces[j]))
                    return true;
        }
        return false;
    }

    void remove_vertex(Mesh::VertexHandle v)
    {
        mesh_.delete_vertex(v, false);
        removed_any_ = true;
    }

    Mesh& mesh_;
    const Hierarchy& h_;
    const std::unordered_map<std::int32_t, double>& spacing_of_;
    const CoveredHoleOptions& o_;
    double min_turn_cos_;
    BoxGrid grid_;
    CoveredHoleStats stats_;
    bool removed_any_ = false;
    OpenMesh::VPropHandleT<int> cluster_;
    OpenMesh::FPropHandleT<int> tile_;
    OpenMesh::FPropHandleT<bool> gap_;
};

} // namespace

CoveredHoleStats close_covered_holes(Mesh& mesh, const Hierarchy& h, const std::unordered_map<std::int32_t, double>& spacing_of,
                                     const CoveredHoleOptions& options)
{
    CoveredHoleOptions o = options;
    check_options(o);
    if (o.vertical)
        o.axis = normalized(o.axis);
    if (mesh.n_faces() == 0 || o.max_edges < 3)
        return {};
    HoleCloser closer(mesh, h, spacing_of, o);
    const CoveredHoleStats stats = closer.run();
    if (stats.closed > 0) {
        mesh.update_face_normals();
        mesh.update_vertex_normals();
    }
    return stats;
}

bool is_sample_hole(const Mesh& mesh, const Hierarchy& h, const std::vector<Mesh::HalfedgeHandle>& loop, double spacing)
{
    if (loop.size() < 3 || !(spacing > 0.0) || !std::isfinite(spacing))
        return false;
    std::vector<Vec3> corners;
    std::vector<Mesh::FaceHandle> around;
    Vec3 centre{0, 0, 0};
    for (const auto hh : loop) {
        const Mesh::VertexHandle v = mesh.from_vertex_handle(hh);
        corners.push_back(to_vec3(mesh.point(v)));
        centre += corners.back();
        for (const auto f : mesh.vf_range(v))
            around.push_back(f);
    }
    centre = centre / static_cast<double>(corners.size());
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    const Vec3 normal = mean_normal(mesh, around);
    if (!(norm(normal) > 0.0))
        return false;
    const BoundingBox box = bounding_box(corners);
    // A loop this wide is no crack between tiles (and judging it spot by spot would take long: a lake
    // in a 10M-point terrain).
    if (box.diagonal() > kMaxJudgedSpacings * spacing)
        return true;
    const double radius = kSampleHoleReach * CoveredHoleOptions{}.cover_spacings * spacing;
    const HoleView view = view_hole(h, corners, centre, normal, std::max(box.diagonal(), 4.0 * spacing),
                                    points_in_box(h, grown(box, radius)));
    return has_empty_spot(view.outline, view.seen, radius);
}

double area_off_the_sample(const Mesh& mesh, const Hierarchy& h, const std::vector<Mesh::FaceHandle>& faces, double reach)
{
    for (const Mesh::FaceHandle f : faces)
        if (!f.is_valid() || f.idx() >= static_cast<int>(mesh.n_faces()) || (mesh.has_face_status() && mesh.status(f).deleted()))
            throw InvalidInput("area_off_the_sample: face handle " + std::to_string(f.idx()) + " is no face of the mesh");
    if (!(reach > 0.0) || !std::isfinite(reach) || faces.empty())
        return 0.0;
    std::vector<std::array<Vec3, 3>> triangles;
    std::vector<Vec3> corners;
    for (const Mesh::FaceHandle f : faces) {
        triangles.push_back(face_corners(mesh, f));
        corners.insert(corners.end(), triangles.back().begin(), triangles.back().end());
    }
    const PointCover cover(h, bounding_box(corners), reach);
    double off = 0.0;
    for (const std::array<Vec3, 3>& t : triangles)
        off += 0.5 * norm(cross(t[1] - t[0], t[2] - t[0])) * cover.share_uncovered(t);
    return off;
}

double area_off_the_sample(const Mesh& mesh, const Hierarchy& h, const BoundingBox& box, double reach)
{
    std::vector<Mesh::FaceHandle> meeting;
    for (const Mesh::FaceHandle f : mesh.faces())
        if (triangle_box(face_corners(mesh, f)).meets(box))
            meeting.push_back(f);
    return area_off_the_sample(mesh, h, meeting, reach);
}

} // namespace mrt
