#pragma once
//! \file face_sequence.h
//! \brief The connectivity that Mesh::add_face builds for a sequence of triangles, built on flat
//! arrays and written into the mesh at once.
//! \details Rebuilding a mesh face by face through OpenMesh's add_face costs about 2,800 instructions
//! per triangle (its handle checks, circulators and per-element property resizes are calls into the
//! library): a 1M-point model's stored levels and the tiles cut from them add 2.5M faces per export,
//! a third of its time. FaceSequence follows add_face's rules step by step (the same refusals, the same
//! edge and half-edge numbering, the same next/prev links and outgoing half-edges), so the mesh that
//! apply() writes is the one the add_face calls would have built, element for element.

#include "libmrtile/mesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mrt {

class FaceSequence
{
public:
    //! A sequence over `vertices` isolated vertices (more can be added).
    explicit FaceSequence(std::size_t vertices = 0) : outgoing_(vertices, -1) {}

    //! Room for `vertices` vertices and `faces` faces (edges guessed as for a closed surface).
    void reserve(std::size_t vertices, std::size_t faces);

    //! Adds an isolated vertex; returns its index.
    int add_vertex()
    {
        outgoing_.push_back(-1);
        return static_cast<int>(outgoing_.size() - 1);
    }

    std::size_t n_vertices() const { return outgoing_.size(); }
    std::size_t n_faces() const { return face_halfedge_.size(); }

    //! \brief Triangle (a, b, c), distinct existing vertices, as Mesh::add_face(a, b, c) would add it
    //! at this point of the sequence: the new face's index, or -1 where add_face refuses it (a corner
    //! inside the surface, an edge with a face on this side already, a patch it cannot relink); a
    //! refused face changes nothing.
    int add_face(int a, int b, int c);

    //! \brief Gives `mesh`, which holds no edges and no faces and at most n_vertices() vertices (the
    //! ones it holds keep their properties), the sequence's vertices, edges and faces.
    void apply(Mesh& mesh) const;

private:
    static int opposite(int h) { return h ^ 1; }
    struct Halfedge
    {
        int to = -1, next = -1, prev = -1, face = -1;
    };
    Halfedge& at(int h) { return halfedges_[static_cast<std::size_t>(h)]; }
    const Halfedge& at(int h) const { return halfedges_[static_cast<std::size_t>(h)]; }
    bool is_boundary_vertex(int v) const
    {
        const int h = outgoing_[static_cast<std::size_t>(v)];
        return h < 0 || at(h).face < 0;
    }
    int find_halfedge(int from, int to) const;
    int new_edge(int from, int to);
    void adjust_outgoing(int v);

    std::vector<int> outgoing_;                   // per vertex: its half-edge, -1 when isolated
    std::vector<Halfedge> halfedges_;             // half-edges 2e and 2e + 1 form edge e
    std::vector<int> face_halfedge_;              // per face
};

} // namespace mrt
