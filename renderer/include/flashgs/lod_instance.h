// A rigid placement of a LOD set's leaf (an instanced set draws one chunk range at many places):
// the Gaussians' positions, orientations, scales and view-dependent colour moved together.
#pragma once

#include <array>

#include "flashgs/scene.h"

namespace flashgs {

struct LodBox;

// p' = scale * R(rotation) p + translation.
struct LodInstance {
  std::array<double, 4> rotation{1, 0, 0, 0};  // unit quaternion (w, x, y, z)
  std::array<double, 3> translation{0, 0, 0};
  double scale = 1;
};

// Moves every Gaussian of `scene` by `instance`: positions, rotation quaternions, scales, and
// the SH bands above degree 0 rotated with the scene (each band by its exact rotation matrix),
// so that a Gaussian looks from the moved camera as it did from the original one.
void transform_gaussians(Scene& scene, const LodInstance& instance);

// The axis-aligned bound of `box` moved by `instance` (of its eight corners).
LodBox transformed_bound(const LodBox& box, const LodInstance& instance);

// Why `instance` cannot be used, or "" when it can: a rotation that is not a unit quaternion of
// finite numbers (|q| off 1 by more than 1e-3), a translation beyond +-1e12 or not finite, a
// scale outside 1e-6..1e6.
const char* lod_instance_problem(const LodInstance& instance);

}  // namespace flashgs
