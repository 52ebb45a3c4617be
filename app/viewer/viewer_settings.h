// ViewerSettings: every user-facing choice of the viewer in one plain struct (the UI and the script both edit it).
#pragma once

#include "flashgs/options.h"

namespace flashgs::viewer {

enum class NavigationMode { fly, orbit };

struct ViewerSettings {
  RenderOptions options;            // algorithm, every optimisation, tau, background, SH cap
  NavigationMode mode = NavigationMode::fly;
  float fov_x_degrees = 60.0f;      // horizontal field of view of the viewer camera
  float render_scale = 1.0f;        // render resolution = framebuffer size * scale
  bool adaptive_resolution = true;  // fewer pixels while moving when a full frame takes > 33 ms
  int forced_width = 0, forced_height = 0;  // > 0: render at exactly this size (scripted runs)
  bool flip_up = false;             // invert the world-up axis guessed from the scene
  float move_speed = 1.0f;          // fly speed in scene extents per second (wheel scales it)
  float look_sensitivity = 0.004f;  // radians per window point of mouse motion
  bool heatmap = false;             // per-tile pair-count overlay (tile counts collected only then)
  bool heatmap_log = true;          // log scale for the overlay
  float heatmap_opacity = 0.45f;
  bool vsync = true;
  bool continuous = true;           // re-render every frame (FPS); off: only when something changed
  bool show_ui = true;
  float path_seconds_per_camera = 2.0f;
};

}  // namespace flashgs::viewer
