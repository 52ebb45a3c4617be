// Range enforcement for the viewer's settings: whatever the panels or a typed value left, each number ends in its range.
#include "viewer_settings.h"

#include <algorithm>
#include <cmath>

namespace flashgs::viewer {

float ValueRange::clamp(float value, float fallback) const {
  if (!std::isfinite(value)) value = std::isfinite(fallback) ? fallback : min;
  return std::clamp(value, min, max);
}

void keep_settings_valid(ViewerSettings& s, const ViewerSettings& before) {
  s.fov_x_degrees = kFovRange.clamp(s.fov_x_degrees, before.fov_x_degrees);
  s.render_scale = kRenderScaleRange.clamp(s.render_scale, before.render_scale);
  s.move_speed = kMoveSpeedRange.clamp(s.move_speed, before.move_speed);
  s.look_sensitivity = kLookSensitivityRange.clamp(s.look_sensitivity, before.look_sensitivity);
  s.heatmap_opacity = kHeatmapOpacityRange.clamp(s.heatmap_opacity, before.heatmap_opacity);
  s.path_seconds_per_camera = kPathSecondsRange.clamp(s.path_seconds_per_camera, before.path_seconds_per_camera);
  RenderOptions& o = s.options;
  o.tau = kTauRange.clamp(o.tau, before.options.tau);
  for (int c = 0; c < 3; ++c) o.background[c] = kBackgroundRange.clamp(o.background[c], before.options.background[c]);
  o.sh_degree_cap = std::clamp(o.sh_degree_cap, 0, kMaxShDegree);
  s.up_axis = std::clamp(s.up_axis, 0, kUpAxisCount - 1);
  s.stream_max_error_px = kStreamErrorRange.clamp(s.stream_max_error_px, before.stream_max_error_px);
  s.stream_budget_millions = kStreamBudgetRange.clamp(s.stream_budget_millions, before.stream_budget_millions);
}

void switch_algorithm(RenderOptions& options, Algorithm to) { options.algorithm = to; }

}  // namespace flashgs::viewer
