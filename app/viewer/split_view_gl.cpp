// Texture upload and the split / difference draw of the comparison.
#include "split_view_gl.h"

#include "viewer_shaders.h"  // generated from shaders/*.glsl by CMake

namespace flashgs::viewer {

SplitViewPresenter::~SplitViewPresenter() {
  if (m_textures[0]) glDeleteTextures(3, m_textures);
  if (m_vao) glDeleteVertexArrays(1, &m_vao);
}

void SplitViewPresenter::init() {
  m_program.build("split_view", shaders::kFullscreenVert, shaders::kSplitViewFrag);
  glGenVertexArrays(1, &m_vao);
  glGenTextures(3, m_textures);
  for (GLuint t : m_textures) {
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
}

void SplitViewPresenter::set_image(int index, int width, int height, const std::uint8_t* rgba) {
  glBindTexture(GL_TEXTURE_2D, m_textures[index]);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
}

void SplitViewPresenter::draw(int fb_width, int fb_height, float divider, float line_px, bool difference) {
  glViewport(0, 0, fb_width, fb_height);
  glDisable(GL_BLEND);
  glBindVertexArray(m_vao);
  glUseProgram(m_program.id());
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, m_textures[difference ? 2 : 0]);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, m_textures[1]);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(m_program.uniform("u_left"), 0);
  glUniform1i(m_program.uniform("u_right"), 1);
  glUniform1f(m_program.uniform("u_divider"), difference ? 2.0f : divider);
  glUniform2f(m_program.uniform("u_viewport"), float(fb_width), float(fb_height));
  glUniform1f(m_program.uniform("u_line_px"), line_px);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  glUseProgram(0);
}

}  // namespace flashgs::viewer
