// The visual comparison: left image | right image split at a divider line, or one image (the magnified difference) alone.
#version 330 core
in vec2 v_uv;
out vec4 frag_color;
uniform sampler2D u_left;
uniform sampler2D u_right;
uniform float u_divider;      // fraction of the width where the right image starts; > 1: left image only
uniform vec2 u_viewport;      // framebuffer size in pixels
uniform float u_line_px;      // divider line width in pixels
void main() {
  float x = v_uv.x * u_viewport.x, at = u_divider * u_viewport.x;
  if (u_divider <= 1.0 && abs(x - at) < 0.5 * u_line_px) {
    frag_color = vec4(1.0, 1.0, 1.0, 1.0);
    return;
  }
  vec3 c = x < at ? texture(u_left, v_uv).rgb : texture(u_right, v_uv).rgb;
  frag_color = vec4(c, 1.0);
}
