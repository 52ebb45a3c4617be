// Per-tile Gaussian-tile pair counts as a colour map blended over the frame, and the colour legend.
#version 330 core
in vec2 v_uv;
out vec4 frag_color;
uniform sampler2D u_counts;   // R32F, tiles_x x tiles_y, row 0 = top tile row, nearest filtering
uniform vec2 u_tile_scale;    // image uv -> count-texture uv (image size / (16 * tiles))
uniform float u_max_count;    // count mapped to the top of the scale (>= 1)
uniform int u_log_scale;      // 1: log(1 + c) / log(1 + max), so sparse tiles stay visible
uniform float u_opacity;      // blend weight of the overlay
uniform vec4 u_legend_rect;   // window-pixel rect (x0, y0, x1, y1), y down; the bar runs 0 -> max left to right
uniform vec2 u_viewport;      // window framebuffer size in pixels

uniform vec3 u_ramp[9];       // the colour ramp's evenly spaced stops (heatmap_legend.h: kHeatRamp)

// Piecewise linear between the stops, as heat_colour() on the host: legend and overlay agree.
vec3 ramp(float t) {
  float s = clamp(t, 0.0, 1.0) * 8.0;
  int i = min(int(s), 7);
  return mix(u_ramp[i], u_ramp[i + 1], s - float(i));
}

float normalised(float c) {
  if (u_log_scale == 1) return log(1.0 + c) / log(1.0 + u_max_count);
  return c / u_max_count;
}

void main() {
  vec2 px = vec2(v_uv.x, v_uv.y) * u_viewport;  // window pixels, y down
  if (px.x >= u_legend_rect.x && px.x < u_legend_rect.z && px.y >= u_legend_rect.y && px.y < u_legend_rect.w) {
    float t = (px.x - u_legend_rect.x) / (u_legend_rect.z - u_legend_rect.x);
    frag_color = vec4(ramp(t), 1.0);
    return;
  }
  vec2 tile_uv = v_uv * u_tile_scale;
  if (tile_uv.x >= 1.0 || tile_uv.y >= 1.0) discard;
  float c = texture(u_counts, tile_uv).r;
  if (c <= 0.0) {
    frag_color = vec4(0.0, 0.0, 0.0, u_opacity * 0.5);  // empty tiles darkened, not coloured
    return;
  }
  frag_color = vec4(ramp(normalised(c)), u_opacity);
}
