// LineOverlay: screen-space guide lines (grid, axes, frustums) drawn with GL over the frame.
#pragma once

#include <vector>

#include "gl_headers_gl.h"
#include "scene_lines.h"
#include "shader_program_gl.h"

namespace flashgs::viewer {

class LineOverlay {
 public:
  LineOverlay() = default;
  ~LineOverlay();
  LineOverlay(const LineOverlay&) = delete;
  LineOverlay& operator=(const LineOverlay&) = delete;

  void init();  // throws flashgs::Error with the driver's log
  // Draws `segments` (render-image pixels of an image width x height stretched over the
  // framebuffer, as the frame is), blended.
  void draw(const std::vector<ScreenSegment>& segments, int image_width, int image_height, int framebuffer_width,
            int framebuffer_height);

 private:
  ShaderProgram m_program;
  GLuint m_vao = 0, m_vbo = 0;
  std::vector<float> m_vertices;  // x, y, r, g, b, a per vertex
};

}  // namespace flashgs::viewer
