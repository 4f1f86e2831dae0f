#pragma once
//! \file lod_tileset.h
//! \brief Writes a LodSet (libmrtile/lod_set.h) as a 3D Tiles 1.1 tileset.
//! \details Empty regions become tiles without content; with Draco, every tile is quantized on one
//! grid (the root box's cube), so border vertices shared by neighbouring tiles decode identically.

#include "formats/write_3d_tiles.h"
#include "libmrtile/georef.h"
#include "libmrtile/lod_set.h"

#include <filesystem>

namespace mrt {

//! The tile tree in the writer's terms (pointers into `set`'s meshes; `set` must outlive the result).
std::vector<TilesetTile> tileset_tiles(const LodSet& set);

//! The one Draco grid of a tileset: the cube over every tile's vertices (skirts included), padded by a
//! millionth of its side. Not the root's box: that holds every point, and a stray point the mesh
//! leaves out far away would stretch the grid and coarsen every position as much. The root's box
//! when no tile has vertices.
QuantizationGrid tileset_grid(const LodSet& set);

//! \brief The Draco position bits a tileset on `grid` needs (at least `least`, at most
//! kMaxPositionBits): a quantized vertex moves up to √3/2 of a step, and that stays under half the
//! finest level's accuracy, the mean RMS plane distance of its tiles (over their points; model units
//! × `unit_scale`, the grid's units per model unit: a CRS's unit_to_metre after georeference). One
//! grid spans the whole tileset, so a survey 20 km wide got 1.4 m steps from 14 bits, and its finest
//! tiles, 3 cm from the points on average, were 0.3-0.6 m off (QA round 38); object scans keep 14 bits.
//! `least` when that accuracy is 0 (points exactly on their planes).
int tileset_position_bits(const Hierarchy& h, const LodSet& set, const QuantizationGrid& grid, double unit_scale = 1.0,
                          int least = 14);

//! Where georeference() put a LOD set on the globe.
struct GeoPlacement
{
    Geodetic anchor;                        //!< the local frame's origin: below the model's box centre
    std::array<double, 16> root_transform;  //!< ENU at the anchor → ECEF (TilesetOptions::root_transform)
};

//! \brief Places a LOD set of input in projected coordinates (UTM and other Transverse Mercator
//! grids) on the globe: every tile vertex (origin + position, a point of `crs`, heights taken as
//! ellipsoidal) is mapped exactly to local east-north-up metres at the anchor, the geodetic point under
//! the centre of `model_box` (relative to origin) at its mid height; normals turn with the grid's
//! convergence; boxes are recomputed (each still contains its content and its children's) and
//! geometric errors converted to metres (a CRS in feet). Pass the
//! returned root transform to write_lod_tileset with origin 0. Why not just a root transform: a
//! projected grid is not a rigid frame (it is rotated from true north by up to a few degrees, scaled by
//! up to 1.0004 and flat where the Earth curves, 8 m over 10 km), so an ENU frame at one point puts
//! the far side of a large survey visibly off; the exact per-vertex map puts every vertex where the
//! CRS says it is (to the datum, see georef.h). Costs two map evaluations per vertex.
//! `height_offset` (metres) is added to every height: the geoid's height above the ellipsoid for input
//! with orthometric heights.
GeoPlacement georeference(LodSet& set, const Vec3& origin, const BoundingBox& model_box, const ProjectedCrs& crs,
                          double height_offset = 0.0);

//! With Draco and no grid in `options`, tiles are quantized on tileset_grid(set).
//! \throw IoError naming the path that cannot be written; InvalidInput for an empty set.
void write_lod_tileset(const LodSet& set, const Vec3& origin, const std::filesystem::path& dir,
                       TilesetOptions options = {});

} // namespace mrt
