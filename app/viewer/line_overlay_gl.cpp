// Vertex upload and the blended GL_LINES draw of the guides.
#include "line_overlay_gl.h"

#include "viewer_shaders.h"  // generated from shaders/*.glsl by CMake

namespace flashgs::viewer {

LineOverlay::~LineOverlay() {
  if (m_vbo) glDeleteBuffers(1, &m_vbo);
  if (m_vao) glDeleteVertexArrays(1, &m_vao);
}

void LineOverlay::init() {
  m_program.build("lines", shaders::kLinesVert, shaders::kLinesFrag);
  glGenVertexArrays(1, &m_vao);
  glGenBuffers(1, &m_vbo);
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(2 * sizeof(float)));
  glBindVertexArray(0);
}

void LineOverlay::draw(const std::vector<ScreenSegment>& segments, int image_width, int image_height, int fb_width,
                       int fb_height) {
  if (segments.empty() || image_width <= 0 || image_height <= 0) return;
  m_vertices.clear();
  const float sx = 2.0f / float(image_width), sy = 2.0f / float(image_height);
  for (const ScreenSegment& s : segments) {
    const float ends[2][2] = {{s.x0, s.y0}, {s.x1, s.y1}};
    for (const auto& e : ends) {
      m_vertices.push_back(e[0] * sx - 1.0f);
      m_vertices.push_back(1.0f - e[1] * sy);  // image y runs down, clip y up
      m_vertices.insert(m_vertices.end(), s.rgba.begin(), s.rgba.end());
    }
  }
  glViewport(0, 0, fb_width, fb_height);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(m_program.id());
  glBindVertexArray(m_vao);
  glBindBuffer(GL_ARRAY_BUFFER, m_vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(m_vertices.size() * sizeof(float)), m_vertices.data(), GL_STREAM_DRAW);
  glDrawArrays(GL_LINES, 0, GLsizei(m_vertices.size() / 6));
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_BLEND);
}

}  // namespace flashgs::viewer
