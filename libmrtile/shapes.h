#pragma once
// Generated, seeded point clouds: analytic shapes whose right answers can be derived (plane, sphere,
// torus, a genus-3 solid, height fields). Used by the demo, the tests and the benchmarks.
#include "libmrtile/point_cloud.h"

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace mrt::shapes {

//! n x n grid on the plane z = 0 over [0,1]^2 (exactly planar).
PointCloud plane_grid(int n);
//! Uniform samples on a sphere of the given radius centred at the origin.
PointCloud sphere(std::size_t count, double radius = 1.0, std::uint32_t seed = 1);
//! Uniform (by area) samples on a torus with major radius R and minor radius r, axis z.
PointCloud torus(std::size_t count, double R = 1.0, double r = 0.35, std::uint32_t seed = 2);
//! Uniform samples on the surface of a plate with three round through-holes (genus 3), 200 x 80 x
//! 20, like the paper's "3Holes" data set.
PointCloud three_holes(std::size_t count, std::uint32_t seed = 3);
//! Random samples of the height field z = 0.1 sin(2πx) cos(2πy) on [0,1]^2.
PointCloud smooth_height_field(std::size_t count, std::uint32_t seed = 4);
//! The paper's step function (Table 1, footnote 3): z = 1 for y >= x else 0, on [0,1]^2.
PointCloud step_function(std::size_t count, std::uint32_t seed = 5);
//! Two parallel planes z = 0 and z = gap over [0,1]^2, count points each (random).
PointCloud parallel_planes(std::size_t count, double gap, std::uint32_t seed = 6);
//! Two linked tori (major radius R, minor r), `count` samples each (torus(count, R, r, seed) and
//! seed + 1000): the first about the z axis, the second in the xz-plane through the first's hole, its
//! tube passing the first's inner side `gap` away (separate objects that come close; R > 2 r + gap).
PointCloud linked_tori(std::size_t count, double R, double r, double gap, std::uint32_t seed = 12);
//! Uniform samples on the surface of the box [0,size.x]×[0,size.y]×[0,size.z], `density` points per unit
//! area, except the face x = 0, which gets `dense_face_factor` times as many (a face a range scanner saw
//! head-on beside faces it saw at a grazing angle: the density jumps at sharp edges).
PointCloud box_surface(const Vec3& size, double density, double dense_face_factor = 1.0, std::uint32_t seed = 8);
//! `count` uniform samples of the flat plate z = 0 over [0,1]^2 where keep(x, y) holds (holes, windows,
//! notches: whatever keep leaves out is unsampled).
PointCloud flat_plate(std::size_t count, const std::function<bool(double, double)>& keep, std::uint32_t seed = 9);
//! Uniform (by area) samples on a closed cone: apex (0, 0, height), base disk of the given radius at
//! z = 0 (a sharp rim where the slope meets the base at a steep angle, and a point at the apex).
PointCloud cone(std::size_t count, double radius = 0.5, double height = 1.0, std::uint32_t seed = 10);
//! Uniform (by area) samples on the surface of a triangle mesh (corners into `vertices`): polyhedra
//! with edges of any angle, a solid with a hole, whatever a test needs whose right answer is its mesh.
PointCloud mesh_surface(const std::vector<Vec3>& vertices, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                        std::size_t count, std::uint32_t seed = 11);
//! Adds Gaussian noise of the given standard deviation along each axis.
void add_noise(PointCloud& cloud, double sigma, std::uint32_t seed = 7);
//! Translates every position by `offset` (to test far-from-origin precision), keeping origin at zero.
void translate(PointCloud& cloud, const Vec3& offset);

} // namespace mrt::shapes
