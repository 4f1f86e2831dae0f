// The README's local-refinement examples (under "Library"), built against the *installed* package by the
// install_consumer test: load a model, refine it around a point, write the OpenMesh mesh, then change
// the mesh in place for other cuts. The text between each pair of README markers is the README's,
// verbatim; the readme_example_in_sync test checks that it is.
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

    // README focus begin
const mrt::Hierarchy h = mrt::load_model(model);
mrt::FocusRegion focus;                                  // a sphere (or Shape::Box) of interest
focus.centre = mrt::Vec3{1.35, 0.0, 0.0} - h.cloud.origin;
focus.radius = 0.3;
focus.tolerance = 0.0002;                                // fine inside ...
const mrt::Cut cut = mrt::cut_by_regions(h, 0.01, {focus}); // ... coarse (1%) elsewhere
const mrt::MeshResult result = mrt::mesh_cut(h, cut);   // OpenMesh TriMesh with f:tile, f:gap, v:cluster
mrt::write_mesh(result.mesh, h.cloud.origin, "focus.ply");
    // README focus end
    std::printf("%zu tiles, %zu faces, %zu refused\n", result.tiles, static_cast<std::size_t>(result.mesh.n_faces()),
                result.surface.refused_faces);

    // README incremental begin
mrt::MeshResult r = mrt::mesh_cut(h, mrt::cut_by_tolerance(h, 0.002));     // the mesh a viewer shows
const mrt::Cut finer = mrt::refine_cut(h, r.cut, 0.002, {focus});           // the user zooms in (a few levels)
const mrt::LocalRefineStats s = mrt::refine_mesh(h, r, finer);              // r.mesh, r.cut updated in place
// s.refined tiles re-triangulated, s.kept left as they were (r.cut keeps those); untouched tiles bit for bit
// (a step of many levels at once, such as 0.01 -> 0.0002, is meshed afresh instead: s.remeshed)
const mrt::LocalRefineStats m = mrt::coarsen_mesh(h, r, mrt::coarsen_cut(h, r.cut, focus, 0.002)); // tiles inside focus merged
const mrt::LocalRefineStats b = mrt::update_mesh(h, r, mrt::cut_by_tolerance(h, 0.002)); // back to the base cut (coarsen_cut is no undo)
mrt::Camera camera;                                                       // fov 60°, 1080 px, 16 px error
camera.position = mrt::Vec3{3, 0, 1} - h.cloud.origin;                   // model coordinates, like regions
camera.direction = mrt::Vec3{-3, 0, -1};                                  // looking at the torus's centre
const mrt::LocalRefineStats c = mrt::update_mesh(h, r, mrt::cut_for_camera(h, camera)); // any new cut: coarsen, then refine
    // README incremental end
    std::printf("refined %zu tiles in place (%zu kept, remeshed %d); coarsened %zu groups (%zu kept); back to the base "
                "cut: %zu coarsened; camera: %zu refined, %zu coarsened (%zu kept, remeshed %d), %zu faces\n",
                s.refined, s.kept, static_cast<int>(s.remeshed), m.coarsened, m.kept, b.coarsened, c.refined, c.coarsened,
                c.kept, static_cast<int>(c.remeshed), static_cast<std::size_t>(r.mesh.n_faces()));
    const bool refused = s.refused != 0 || m.refused != 0 || b.refused != 0 || c.refused != 0;
    return result.surface.refused_faces == 0 && result.mesh.n_faces() > 0 && s.refined > 0 && !s.remeshed && m.coarsened > 0 &&
                   !refused && !c.remeshed
               ? 0
               : 1;
}
