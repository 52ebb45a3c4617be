// Guide lines (grid, axes, frustums): positions already in clip space, a colour per vertex.
#version 330 core
layout(location = 0) in vec2 a_position;
layout(location = 1) in vec4 a_colour;
out vec4 v_colour;
void main() {
  v_colour = a_colour;
  gl_Position = vec4(a_position, 0.0, 1.0);
}
