// Guide lines: their vertex colour, blended over the frame.
#version 330 core
in vec4 v_colour;
out vec4 frag_color;
void main() { frag_color = v_colour; }
