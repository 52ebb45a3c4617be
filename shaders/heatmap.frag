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

// A perceptually ordered blue -> cyan -> green -> yellow -> red ramp, piecewise linear so that
// the legend and the overlay agree exactly.
vec3 ramp(float t) {
  t = clamp(t, 0.0, 1.0);
  const vec3 c0 = vec3(0.05, 0.03, 0.35);
  const vec3 c1 = vec3(0.00, 0.45, 0.95);
  const vec3 c2 = vec3(0.10, 0.85, 0.45);
  const vec3 c3 = vec3(0.98, 0.90, 0.15);
  const vec3 c4 = vec3(0.90, 0.10, 0.05);
  float s = t * 4.0;
  if (s < 1.0) return mix(c0, c1, s);
  if (s < 2.0) return mix(c1, c2, s - 1.0);
  if (s < 3.0) return mix(c2, c3, s - 2.0);
  return mix(c3, c4, s - 3.0);
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
