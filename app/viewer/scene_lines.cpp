// Grid, axes, frustum and centre geometry, near-plane clipping and projection with the view camera.
#include "scene_lines.h"

#include <algorithm>
#include <cmath>

#include "flashgs/model_constants.h"

namespace flashgs::viewer {
namespace {

glm::vec3 to_view(const Camera& c, const glm::vec3& p) {
  const glm::vec3 d = p - glm::vec3(c.position[0], c.position[1], c.position[2]);
  const float* r = c.rotation;
  return glm::vec3(r[0] * d.x + r[1] * d.y + r[2] * d.z, r[3] * d.x + r[4] * d.y + r[5] * d.z,
                   r[6] * d.x + r[7] * d.y + r[8] * d.z);
}

glm::vec2 to_pixels(const Camera& c, const glm::vec3& v) {
  return glm::vec2(c.fx * v.x / v.z + c.cx, c.fy * v.y / v.z + c.cy);
}

// A world point from a camera's view-space point (the rotation's rows are its axes).
glm::vec3 from_view(const Camera& c, const glm::vec3& v) {
  const float* r = c.rotation;
  return glm::vec3(c.position[0], c.position[1], c.position[2]) + glm::vec3(r[0], r[1], r[2]) * v.x +
         glm::vec3(r[3], r[4], r[5]) * v.y + glm::vec3(r[6], r[7], r[8]) * v.z;
}

float round_spacing(float approx) {
  const float decade = std::pow(10.0f, std::floor(std::log10(approx)));
  for (float m : {1.0f, 2.0f, 5.0f})
    if (m * decade >= approx) return m * decade;
  return 10.0f * decade;
}

}  // namespace

std::vector<WorldSegment> grid_and_axes(const glm::vec3& centre, float extent, const glm::vec3& up_in) {
  std::vector<WorldSegment> out;
  if (!(extent > 0.0f) || !std::isfinite(extent)) return out;
  const glm::vec3 up = glm::normalize(up_in);
  const glm::vec3 any = std::abs(up.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
  const glm::vec3 u = glm::normalize(glm::cross(up, any)), w = glm::cross(up, u);
  const float spacing = round_spacing(extent / 5.0f);
  const int half = 10;
  // Centred under the scene centre, snapped to the spacing so the lines stay put when it moves.
  const glm::vec3 foot = centre - up * glm::dot(centre, up);
  const glm::vec3 o = u * (std::round(glm::dot(foot, u) / spacing) * spacing) +
                      w * (std::round(glm::dot(foot, w) / spacing) * spacing);
  const std::array<float, 4> grey{0.7f, 0.7f, 0.7f, 0.45f};
  for (int i = -half; i <= half; ++i) {
    const float t = float(i) * spacing, l = float(half) * spacing;
    out.push_back({o + u * t - w * l, o + u * t + w * l, grey});
    out.push_back({o + w * t - u * l, o + w * t + u * l, grey});
  }
  out.push_back({glm::vec3(0), glm::vec3(extent, 0, 0), {1.0f, 0.25f, 0.25f, 1.0f}});
  out.push_back({glm::vec3(0), glm::vec3(0, extent, 0), {0.3f, 1.0f, 0.3f, 1.0f}});
  out.push_back({glm::vec3(0), glm::vec3(0, 0, extent), {0.35f, 0.55f, 1.0f, 1.0f}});
  return out;
}

std::vector<WorldSegment> camera_frustums(const std::vector<Camera>& cameras, float depth, int highlighted) {
  std::vector<WorldSegment> out;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const Camera& c = cameras[i];
    if (c.fx <= 0.0f || c.fy <= 0.0f) continue;
    const std::array<float, 4> colour = int(i) == highlighted ? std::array<float, 4>{0.3f, 1.0f, 0.4f, 1.0f}
                                                              : std::array<float, 4>{1.0f, 0.6f, 0.15f, 0.9f};
    const glm::vec3 eye(c.position[0], c.position[1], c.position[2]);
    // The image corners at view depth `depth`: pixel (x, y) is at ((x - cx) / fx, (y - cy) / fy) * depth.
    auto corner = [&](float x, float y) {
      return from_view(c, glm::vec3((x - c.cx) / c.fx * depth, (y - c.cy) / c.fy * depth, depth));
    };
    const float w = float(c.width), h = float(c.height);
    const glm::vec3 k[4] = {corner(0, 0), corner(w, 0), corner(w, h), corner(0, h)};
    for (int j = 0; j < 4; ++j) {
      out.push_back({eye, k[j], colour});
      out.push_back({k[j], k[(j + 1) % 4], colour});
    }
    // A tick above the top edge: which way is up in the image.
    out.push_back({corner(0.35f * w, 0), corner(0.5f * w, -0.15f * h), colour});
    out.push_back({corner(0.5f * w, -0.15f * h), corner(0.65f * w, 0), colour});
  }
  return out;
}

std::vector<ScreenSegment> project_segments(const std::vector<WorldSegment>& segments, const Camera& view,
                                            float near_depth) {
  std::vector<ScreenSegment> out;
  out.reserve(segments.size());
  for (const WorldSegment& s : segments) {
    glm::vec3 a = to_view(view, s.a), b = to_view(view, s.b);
    if (a.z <= near_depth && b.z <= near_depth) continue;
    // Cut at the near plane: the part behind the camera would project mirrored.
    if (a.z < near_depth) a = a + (b - a) * ((near_depth - a.z) / (b.z - a.z));
    if (b.z < near_depth) b = b + (a - b) * ((near_depth - b.z) / (a.z - b.z));
    const glm::vec2 pa = to_pixels(view, a), pb = to_pixels(view, b);
    if (!std::isfinite(pa.x + pa.y + pb.x + pb.y)) continue;
    out.push_back({pa.x, pa.y, pb.x, pb.y, s.rgba});
  }
  return out;
}

std::vector<ScreenSegment> centre_marks(const std::vector<ScenePart>& parts, const Camera& view, std::size_t max_marks) {
  std::vector<ScreenSegment> out;
  const std::size_t n = static_cast<std::size_t>(scene_parts_size(parts));
  if (n == 0 || max_marks == 0) return out;
  const std::size_t stride = (n + max_marks - 1) / max_marks;
  out.reserve(n / stride + 1);
  const float sh_c0 = static_cast<float>(model::kShC0);
  std::size_t part_start = 0;  // the first Gaussian of the part below, counted over all parts
  for (const ScenePart& part : parts) {
    const Scene& scene = *part.source;
    // Every stride-th Gaussian over all parts: the first of this part at or after part_start.
    for (std::size_t at = (part_start + stride - 1) / stride * stride; at < part_start + part.count; at += stride) {
      const std::size_t i = part.first + (at - part_start);
      const glm::vec3 v = to_view(view, glm::vec3(scene.positions[3 * i], scene.positions[3 * i + 1], scene.positions[3 * i + 2]));
      if (v.z <= 0.0f) continue;
      const glm::vec2 p = to_pixels(view, v);
      if (!(p.x >= 0 && p.y >= 0 && p.x < float(view.width) && p.y < float(view.height))) continue;
      std::array<float, 4> rgba{1, 1, 1, 1};
      for (int c = 0; c < 3; ++c) rgba[c] = std::clamp(0.5f + sh_c0 * scene.sh_dc[3 * i + c], 0.0f, 1.0f);
      out.push_back({p.x - 1.0f, p.y, p.x + 1.0f, p.y, rgba});
    }
    part_start += part.count;
  }
  return out;
}

namespace {

float distance_to_segment(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b) {
  const glm::vec2 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  const float t = len2 > 0.0f ? glm::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

bool inside_triangle(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b, const glm::vec2& c) {
  auto side = [](const glm::vec2& u, const glm::vec2& v, const glm::vec2& w) {
    return (v.x - u.x) * (w.y - u.y) - (v.y - u.y) * (w.x - u.x);
  };
  const float d1 = side(a, b, p), d2 = side(b, c, p), d3 = side(c, a, p);
  return !((d1 < 0 || d2 < 0 || d3 < 0) && (d1 > 0 || d2 > 0 || d3 > 0));
}

}  // namespace

int pick_camera(const std::vector<Camera>& cameras, const Camera& view, float x, float y, float radius, float depth) {
  const glm::vec2 click(x, y);
  int best = -1;
  float best_distance = 0.0f, best_depth = 0.0f;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const glm::vec3 apex = to_view(view, glm::vec3(cameras[i].position[0], cameras[i].position[1], cameras[i].position[2]));
    if (apex.z <= 0.0f) continue;
    // The frustum as drawn: its edges, and its faces (the apex with each image edge, the image
    // rectangle) where every corner is in front of the view.
    const std::vector<WorldSegment> edges = camera_frustums({cameras[i]}, depth, -1);
    float distance = std::hypot(to_pixels(view, apex).x - x, to_pixels(view, apex).y - y);
    for (const ScreenSegment& s : project_segments(edges, view, 1e-4f * depth))
      distance = std::min(distance, distance_to_segment(click, {s.x0, s.y0}, {s.x1, s.y1}));
    if (distance > 0.0f && edges.size() >= 8) {
      glm::vec2 corner[4];
      bool in_front = true;
      for (int j = 0; j < 4; ++j) {
        const glm::vec3 v = to_view(view, edges[std::size_t(2 * j)].b);
        in_front = in_front && v.z > 0.0f;
        if (in_front) corner[j] = to_pixels(view, v);
      }
      const glm::vec2 a = to_pixels(view, apex);
      if (in_front) {
        bool inside = inside_triangle(click, corner[0], corner[1], corner[2]) ||
                      inside_triangle(click, corner[0], corner[2], corner[3]);
        for (int j = 0; j < 4 && !inside; ++j) inside = inside_triangle(click, a, corner[j], corner[(j + 1) % 4]);
        if (inside) distance = 0.0f;
      }
    }
    // The nearest hit; among frustums the click is inside of, the one nearest the viewer.
    if (distance <= radius &&
        (best < 0 || distance < best_distance || (distance == 0.0f && best_distance == 0.0f && apex.z < best_depth))) {
      best_distance = distance;
      best_depth = apex.z;
      best = int(i);
    }
  }
  return best;
}

}  // namespace flashgs::viewer
