// Full-screen triangle from gl_VertexID alone (no vertex buffer): the image blit and the heat-map overlay share it.
#version 330 core
out vec2 v_uv;  // (0,0) = top-left of the image, (1,1) = bottom-right
void main() {
  // Three vertices covering clip space [-1,3]^2; the visible part maps uv to [0,1]^2.
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  // The textures hold the image's top row in texel row 0, which GL samples at t = 0:
  // flipping y here shows row 0 at the top of the window.
  v_uv = vec2(p.x, 1.0 - p.y);
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
