#pragma once
// Hierarchies with a known flat cut for the tile and surface tests, independent of the clustering
// stage: k-means (Lloyd, seeded centres) labels the points, one node per cluster. Only what tiles and
// surfaces read is filled in: point ranges in tree order, moments and PCA frames.
#include "libmrtile/hierarchy.h"
#include "libmrtile/mesh.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

namespace mrt::testing {

struct FlatCut
{
    Hierarchy hierarchy;
    std::vector<std::int32_t> cut; //!< every node: the nodes partition the points
};

//! Nodes from a labelling: points sorted by label (stable), one node per non-empty label.
inline FlatCut hierarchy_from_labels(const PointCloud& cloud, const std::vector<std::uint32_t>& label)
{
    FlatCut out;
    std::vector<std::uint32_t> order(cloud.size());
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return label[a] < label[b]; });
    Hierarchy& h = out.hierarchy;
    h.cloud.origin = cloud.origin;
    for (std::uint32_t i : order) {
        h.cloud.positions.push_back(cloud.positions[i]);
        h.input_index.push_back(i);
    }
    for (std::uint32_t begin = 0; begin < order.size();) {
        std::uint32_t end = begin;
        while (end < order.size() && label[order[end]] == label[order[begin]])
            ++end;
        Node n;
        n.begin = begin;
        n.end = end;
        n.moments = compute_moments(h.cloud.positions.data() + begin, end - begin);
        n.box = bounding_box(std::vector<Vec3>(h.cloud.positions.begin() + begin, h.cloud.positions.begin() + end));
        out.cut.push_back(static_cast<std::int32_t>(h.nodes.size()));
        h.nodes.push_back(n);
        begin = end;
    }
    update_derived(h);
    return out;
}

//! k-means labels: k seeded centres (every (n/k)-th point), `iterations` Lloyd steps.
inline std::vector<std::uint32_t> kmeans_labels(const PointCloud& cloud, std::size_t k, int iterations = 4)
{
    const std::size_t n = cloud.size();
    std::vector<Vec3> centres;
    for (std::size_t i = 0; i < k; ++i)
        centres.push_back(cloud.positions[(i * n) / k]);
    std::vector<std::uint32_t> label(n, 0);
    for (int it = 0; it <= iterations; ++it) {
        for (std::size_t p = 0; p < n; ++p) {
            double best = std::numeric_limits<double>::infinity();
            for (std::size_t c = 0; c < centres.size(); ++c) {
                const double d = squared_distance(cloud.positions[p], centres[c]);
                if (d < best) {
                    best = d;
                    label[p] = static_cast<std::uint32_t>(c);
                }
            }
        }
        std::vector<Vec3> sum(centres.size());
        std::vector<std::size_t> count(centres.size(), 0);
        for (std::size_t p = 0; p < n; ++p) {
            sum[label[p]] += cloud.positions[p];
            ++count[label[p]];
        }
        for (std::size_t c = 0; c < centres.size(); ++c)
            if (count[c])
                centres[c] = sum[c] / static_cast<double>(count[c]);
    }
    return label;
}

inline FlatCut kmeans_cut(const PointCloud& cloud, std::size_t k, int iterations = 4)
{
    return hierarchy_from_labels(cloud, kmeans_labels(cloud, k, iterations));
}

//! Non-manifold vertices counted directly on the half-edge structure: a vertex with a face whose
//! outgoing boundary half-edges number more than one (two fans touching), or an isolated vertex.
inline std::size_t count_nonmanifold_vertices(const Mesh& mesh)
{
    std::size_t bad = 0;
    for (auto v : mesh.vertices()) {
        std::size_t boundary_out = 0, out = 0;
        for (auto h : mesh.voh_range(v)) {
            ++out;
            if (mesh.is_boundary(h))
                ++boundary_out;
        }
        if (out == 0 || boundary_out > 1)
            ++bad;
    }
    return bad;
}

} // namespace mrt::testing
