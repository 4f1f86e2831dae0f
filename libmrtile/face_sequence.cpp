// Mesh assembly for the export path (stored levels loaded, tiles cut from them): OpenMesh's add_face
// rules replayed on flat arrays, so that a mesh of a million faces is rebuilt without a million calls
// into the library, and yet exactly as add_face would have built it (see face_sequence.h).
#include "libmrtile/face_sequence.h"

#include <array>

namespace mrt {

void FaceSequence::reserve(std::size_t vertices, std::size_t faces)
{
    outgoing_.reserve(vertices);
    halfedges_.reserve(3 * faces + 6); // a closed triangle surface: 3/2 edges per face
    face_halfedge_.reserve(faces);
}

// The half-edge from `from` to `to`, or -1: searched among the half-edges around `from` in the order
// OpenMesh's outgoing-half-edge circulator visits them (the next of each one's opposite).
int FaceSequence::find_halfedge(int from, int to) const
{
    const int start = outgoing_[static_cast<std::size_t>(from)];
    int h = start;
    while (h >= 0) {
        if (at(h).to == to)
            return h;
        h = at(opposite(h)).next;
        if (h == start)
            break;
    }
    return -1;
}

int FaceSequence::new_edge(int from, int to)
{
    const int h = static_cast<int>(halfedges_.size());
    halfedges_.push_back({to, -1, -1, -1});
    halfedges_.push_back({from, -1, -1, -1});
    return h;
}

// A vertex on the border keeps a border half-edge as its own (the first one around it), as
// add_face leaves it; an inner vertex keeps the one it has.
void FaceSequence::adjust_outgoing(int v)
{
    const int start = outgoing_[static_cast<std::size_t>(v)];
    int h = start;
    while (h >= 0) {
        if (at(h).face < 0) {
            outgoing_[static_cast<std::size_t>(v)] = h;
            return;
        }
        h = at(opposite(h)).next;
        if (h == start)
            return;
    }
}

int FaceSequence::add_face(int a, int b, int c)
{
    const std::array<int, 3> v{a, b, c};
    std::array<int, 3> he{};        // he[i]: v[i] -> v[i + 1]
    std::array<bool, 3> fresh{};    // he[i] did not exist before this face
    // The checks come first, so that a refused face leaves everything as it was.
    for (std::size_t i = 0; i < 3; ++i) {
        if (!is_boundary_vertex(v[i]))
            return -1; // a corner with no gap around it
        he[i] = find_halfedge(v[i], v[(i + 1) % 3]);
        fresh[i] = he[i] < 0;
        if (!fresh[i] && at(he[i]).face >= 0)
            return -1; // that side of the edge has its face already
    }
    // Links are recorded and set at the end, as add_face does: every rule below reads the links as
    // they were before this face.
    std::array<int, 18> link_from, link_to; // at most 6 links per corner; not zeroed, only the first link_count are read
    std::size_t link_count = 0;
    const auto link = [&](int from, int to) {
        link_from[link_count] = from;
        link_to[link_count++] = to;
    };
    auto next = [&](int h) { return at(h).next; };
    auto prev = [&](int h) { return at(h).prev; };
    for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t j = (i + 1) % 3;
        if (fresh[i] || fresh[j])
            continue;
        const int in_prev = he[i], in_next = he[j];
        if (next(in_prev) == in_next)
            continue;
        // Two existing border edges meet at v[j] but are not consecutive along the border: the
        // faces between them (a patch) move to another gap around v[j], if there is one.
        int gap_prev = opposite(in_next);
        do
            gap_prev = opposite(next(gap_prev));
        while (at(gap_prev).face >= 0);
        if (gap_prev == in_prev)
            return -1; // no other gap
        const int gap_next = next(gap_prev);
        link(gap_prev, next(in_prev));
        link(prev(in_next), gap_next);
        link(in_prev, in_next);
    }
    for (std::size_t i = 0; i < 3; ++i)
        if (fresh[i])
            he[i] = new_edge(v[i], v[(i + 1) % 3]);
    const int f = static_cast<int>(face_halfedge_.size());
    face_halfedge_.push_back(he[2]);
    std::array<bool, 3> adjust{};
    for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t j = (i + 1) % 3;
        const auto corner = static_cast<std::size_t>(v[j]);
        const int in_prev = he[i], in_next = he[j];
        if (fresh[i] || fresh[j]) {
            const int out_prev = opposite(in_next), out_next = opposite(in_prev);
            if (fresh[i] && !fresh[j]) {
                link(prev(in_next), out_next);
                outgoing_[corner] = out_next;
            } else if (!fresh[i] && fresh[j]) {
                const int border_next = next(in_prev);
                link(out_prev, border_next);
                outgoing_[corner] = border_next;
            } else if (outgoing_[corner] < 0) { // both new, the corner was isolated
                outgoing_[corner] = out_next;
                link(out_prev, out_next);
            } else { // both new, at a corner already on the border: into its gap
                const int border_next = outgoing_[corner];
                link(prev(border_next), out_next);
                link(out_prev, border_next);
            }
            link(in_prev, in_next);
        } else {
            adjust[j] = outgoing_[corner] == in_next;
        }
        at(in_prev).face = f;
    }
    for (std::size_t k = 0; k < link_count; ++k) {
        at(link_from[k]).next = link_to[k];
        at(link_to[k]).prev = link_from[k];
    }
    for (std::size_t i = 0; i < 3; ++i)
        if (adjust[i])
            adjust_outgoing(v[i]);
    return f;
}

void FaceSequence::apply(Mesh& mesh) const
{
    const std::size_t halfedges = halfedges_.size();
    mesh.resize(outgoing_.size(), halfedges / 2, face_halfedge_.size());
    for (std::size_t v = 0; v < outgoing_.size(); ++v)
        mesh.set_halfedge_handle(Mesh::VertexHandle(static_cast<int>(v)), Mesh::HalfedgeHandle(outgoing_[v]));
    for (std::size_t h = 0; h < halfedges; ++h) {
        const Mesh::HalfedgeHandle handle(static_cast<int>(h));
        const Halfedge& e = halfedges_[h];
        mesh.set_vertex_handle(handle, Mesh::VertexHandle(e.to));
        mesh.set_face_handle(handle, Mesh::FaceHandle(e.face));
        if (e.next >= 0)
            mesh.set_next_halfedge_handle(handle, Mesh::HalfedgeHandle(e.next));
    }
    // set_next_halfedge_handle also set the prev links, each to the last half-edge naming it as next;
    // they are set again as add_face left them (the same, unless a stale link pointed there too).
    for (std::size_t h = 0; h < halfedges; ++h)
        if (halfedges_[h].prev >= 0)
            mesh.set_prev_halfedge_handle(Mesh::HalfedgeHandle(static_cast<int>(h)), Mesh::HalfedgeHandle(halfedges_[h].prev));
    for (std::size_t f = 0; f < face_halfedge_.size(); ++f)
        mesh.set_halfedge_handle(Mesh::FaceHandle(static_cast<int>(f)), Mesh::HalfedgeHandle(face_halfedge_[f]));
}

} // namespace mrt
