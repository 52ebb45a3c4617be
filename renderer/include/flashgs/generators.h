// Procedural scenes and camera paths: the bundled demo scene, orbit cameras, scene tiling.
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/scene.h"

namespace flashgs {

// The demo scene shipped in assets/: a torus knot of anisotropic, view-dependent (SH degree 1)
// Gaussians above a checkered floor; about `count` Gaussians, deterministic for a seed.
Scene make_demo_scene(std::size_t count = 30000, std::uint32_t seed = 7);

// A camera at `eye` looking at `target` with `up` pointing up in the image (OpenCV axes),
// horizontal field of view `fov_degrees`. Throws flashgs::Error when eye and target coincide.
Camera look_at_camera(const float eye[3], const float target[3], const float up[3], int width, int height,
                      float fov_degrees);

// `count` cameras on a circle of `radius` around `target` at `height` above it along `up`,
// looking at the target (OpenCV axes), horizontal field of view `fov_degrees`.
std::vector<Camera> make_orbit_cameras(const float target[3], const float up[3], float radius,
                                       float height, int count, int width, int height_px,
                                       float fov_degrees);

// `copies` copies of `scene` on a square grid in the x-z plane, spaced by the scene's extent,
// for large-scene benchmarks (e.g. 7 copies of pc_playbot = 3.5M Gaussians).
Scene tile_scene(const Scene& scene, int copies);

// Axis-aligned bounds of the Gaussian centres.
void scene_bounds(const Scene& scene, float lo[3], float hi[3]);

}  // namespace flashgs
