// Scene guides as line segments: the ground grid and world axes, the training cameras' frustums, the Gaussians' centres, their projection into the view, and picking a frustum by a click (no GL).
#pragma once

#include <array>
#include <vector>

#include <glm/glm.hpp>

#include "flashgs/camera.h"
#include "flashgs/scene_parts.h"

namespace flashgs::viewer {

struct WorldSegment {
  glm::vec3 a, b;
  std::array<float, 4> rgba;
};

// In render-image pixels (x right, y down), as the frame the lines are drawn over.
struct ScreenSegment {
  float x0, y0, x1, y1;
  std::array<float, 4> rgba;
};

// A grid in the plane through the world origin perpendicular to `up`, centred under the
// scene's centre and about four extents wide at a round spacing, plus the world axes from
// the origin (x red, y green, z blue, one extent long).
std::vector<WorldSegment> grid_and_axes(const glm::vec3& centre, float extent, const glm::vec3& up);

// Each camera as a pyramid from its centre to its image's corners at depth `depth`, with a
// tick on the image's top edge; camera `highlighted` (or none: -1) in another colour.
std::vector<WorldSegment> camera_frustums(const std::vector<Camera>& cameras, float depth, int highlighted);

// The segments seen by `view`, clipped to the space in front of it (view depth > `near`).
std::vector<ScreenSegment> project_segments(const std::vector<WorldSegment>& segments, const Camera& view,
                                            float near_depth);

// The centres of the drawn Gaussians (the parts one after another: a streamed cut, or a scene
// as one part) seen by `view` as short dashes (2 pixels) in their base colour (the SH DC term),
// for the "centres" debug view: at most `max_marks` of them, every k-th where there are more (a
// dash per Gaussian of a 3.5M scene would cost more than the frame).
std::vector<ScreenSegment> centre_marks(const std::vector<ScenePart>& parts, const Camera& view, std::size_t max_marks);

// The camera whose frustum, as camera_frustums draws it at `depth`, is under (x, y) in
// `view`'s image: inside its projected body or within `radius` pixels of an edge or its
// centre. The nearest to the click wins; among bodies the click is inside, the one nearest the
// viewer. -1 when none is.
int pick_camera(const std::vector<Camera>& cameras, const Camera& view, float x, float y, float radius, float depth);

}  // namespace flashgs::viewer
