// The README's API example, built against the *installed* package by the install_consumer test:
// load a model, refine it around a point, write the OpenMesh mesh.
#include "formats/write_mesh.h"
#include "libmrtile/cluster_tree.h"
#include "libmrtile/cut.h"
#include "libmrtile/model_file.h"
#include "libmrtile/reconstruct.h"
#include "libmrtile/refine_mesh.h"
#include "libmrtile/shapes.h"

#include <cstdio>

int main(int argc, char** argv)
{
    // A model to load: the one named on the command line, else a generated torus saved first.
    const std::string model = argc > 1 ? argv[1] : "torus.mrt";
    if (argc <= 1)
        mrt::save_model(mrt::build_hierarchy(mrt::shapes::torus(50000)), model);

    const mrt::Hierarchy h = mrt::load_model(model);

    // Coarse everywhere (1% of the model size), fine (0.02%) within 0.3 units of a point of interest.
    mrt::FocusRegion focus;
    focus.centre = mrt::Vec3{1.35, 0.0, 0.0} - h.cloud.origin;
    focus.radius = 0.3;
    focus.tolerance = 0.0002;
    const mrt::Cut cut = mrt::cut_by_regions(h, 0.01, {focus});

    const mrt::MeshResult result = mrt::mesh_cut(h, cut); // OpenMesh TriMesh with f:tile, v:cluster
    mrt::write_mesh(result.mesh, h.cloud.origin, "focus.ply");
    std::printf("%zu tiles, %zu faces, %zu refused\n", result.tiles, static_cast<std::size_t>(result.mesh.n_faces()),
                result.surface.refused_faces);

    // The focus reached incrementally: a mesh patched in place where the cut got finer (a step of a few
    // levels: one of 16 or more new tiles per tile is meshed afresh, LocalRefineOptions::max_step_ratio).
    mrt::MeshResult coarse = mrt::mesh_cut(h, mrt::cut_by_tolerance(h, 0.002));
    const mrt::LocalRefineStats patched = mrt::refine_mesh(h, coarse, mrt::refine_cut(h, coarse.cut, 0.002, {focus}));
    std::printf("refined %zu tiles in place (%zu kept, remeshed %d), %zu faces\n", patched.refined, patched.kept,
                static_cast<int>(patched.remeshed), static_cast<std::size_t>(coarse.mesh.n_faces()));
    const mrt::LocalRefineStats merged = mrt::coarsen_mesh(h, coarse, mrt::coarsen_cut(h, coarse.cut, focus, 0.002));
    std::printf("coarsened %zu groups back (%zu kept), %zu faces\n", merged.coarsened, merged.kept,
                static_cast<std::size_t>(coarse.mesh.n_faces()));
    // Any new cut (a camera that moved): coarsened where it is coarser, then refined where it is finer.
    mrt::Camera camera; // fov 60 degrees, 1080 px, 16 px error
    camera.position = mrt::Vec3{3, 0, 1} - h.cloud.origin;
    camera.direction = mrt::Vec3{-3, 0, -1};
    const mrt::LocalRefineStats moved = mrt::update_mesh(h, coarse, mrt::cut_for_camera(h, camera));
    std::printf("camera: %zu refined, %zu coarsened (%zu kept, remeshed %d), %zu faces\n", moved.refined, moved.coarsened,
                moved.kept, static_cast<int>(moved.remeshed), static_cast<std::size_t>(coarse.mesh.n_faces()));
    return result.surface.refused_faces == 0 && result.mesh.n_faces() > 0 && patched.refined > 0 && patched.refused == 0 &&
                   merged.refused == 0 && moved.refused == 0 && !moved.remeshed
               ? 0
               : 1;
}
