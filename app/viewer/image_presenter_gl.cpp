// Frame texture management, the blit and heat-map passes, and texture read-back.
#include "image_presenter_gl.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>

#include "flashgs/error.h"
#include "heatmap_legend.h"

#include "viewer_shaders.h"  // generated from shaders/*.glsl by CMake

namespace flashgs::viewer {

ImagePresenter::~ImagePresenter() {
  glDeleteTextures(m_texture_count, m_textures);
  if (m_counts) glDeleteTextures(1, &m_counts);
  if (m_vao) glDeleteVertexArrays(1, &m_vao);
}

void ImagePresenter::init() {
  m_blit.build("image_blit", shaders::kFullscreenVert, shaders::kImageBlitFrag);
  m_heat.build("heatmap", shaders::kFullscreenVert, shaders::kHeatmapFrag);
  // Core profiles require a bound VAO even for attribute-less draws.
  glGenVertexArrays(1, &m_vao);
  glGenTextures(1, &m_counts);
  glBindTexture(GL_TEXTURE_2D, m_counts);
  // Nearest: one flat colour per tile, no blending across tile borders.
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

void ImagePresenter::resize(int width, int height, int count) {
  glDeleteTextures(m_texture_count, m_textures);
  while (glGetError() != GL_NO_ERROR) {}  // only this call's errors count below
  m_width = width;
  m_height = height;
  m_texture_count = std::clamp(count, 1, kMaxTextures);
  m_shown = 0;
  glGenTextures(m_texture_count, m_textures);
  for (int i = 0; i < m_texture_count; ++i) {
    glBindTexture(GL_TEXTURE_2D, m_textures[i]);
    // Linear filtering: the frame may be rendered below the window size (render scale < 1).
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  }
  if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
    // Out of memory or beyond the size limit: no textures rather than unusable ones, so
    // that the next resize() starts clean.
    glDeleteTextures(m_texture_count, m_textures);
    m_texture_count = m_width = m_height = 0;
    char text[128];
    std::snprintf(text, sizeof text, "OpenGL refused %dx%d frame textures (error 0x%04x)", width, height, error);
    throw Error(text);
  }
}

void ImagePresenter::upload(const Image& image) {
  if (image.width != m_width || image.height != m_height || m_texture_count == 0) resize(image.width, image.height);
  to_rgba8(image, m_rgba);
  m_shown = 0;
  glBindTexture(GL_TEXTURE_2D, m_textures[0]);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE, m_rgba.data());
}

void ImagePresenter::set_tile_counts(const std::vector<std::uint32_t>& counts, int tiles_x, int tiles_y,
                                     std::uint32_t max_count) {
  if (tiles_x <= 0 || tiles_y <= 0 || counts.size() < static_cast<std::size_t>(tiles_x) * tiles_y) return;
  m_count_floats.assign(counts.begin(), counts.begin() + static_cast<std::size_t>(tiles_x) * tiles_y);
  m_max_count = std::max<std::uint32_t>(1, max_count);
  glBindTexture(GL_TEXTURE_2D, m_counts);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  if (tiles_x != m_tiles_x || tiles_y != m_tiles_y) {
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, tiles_x, tiles_y, 0, GL_RED, GL_FLOAT, m_count_floats.data());
    m_tiles_x = tiles_x;
    m_tiles_y = tiles_y;
  } else {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, tiles_x, tiles_y, GL_RED, GL_FLOAT, m_count_floats.data());
  }
}

void ImagePresenter::draw(int fb_width, int fb_height, const HeatmapView* heatmap) {
  glViewport(0, 0, fb_width, fb_height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_BLEND);
  glBindVertexArray(m_vao);
  if (m_texture_count > 0) {
    glUseProgram(m_blit.id());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, m_textures[m_shown]);
    glUniform1i(m_blit.uniform("u_image"), 0);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  if (heatmap && m_tiles_x > 0 && m_width > 0) {
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glUseProgram(m_heat.id());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, m_counts);
    glUniform1i(m_heat.uniform("u_counts"), 0);
    glUniform2f(m_heat.uniform("u_tile_scale"), float(m_width) / float(16 * m_tiles_x),
                float(m_height) / float(16 * m_tiles_y));
    glUniform1f(m_heat.uniform("u_max_count"), float(m_max_count));
    glUniform1i(m_heat.uniform("u_log_scale"), heatmap->log_scale ? 1 : 0);
    glUniform1f(m_heat.uniform("u_opacity"), heatmap->opacity);
    glUniform3fv(m_heat.uniform("u_ramp"), kRampStops, kHeatRamp[0].data());
    glUniform4f(m_heat.uniform("u_legend_rect"), heatmap->legend_rect[0], heatmap->legend_rect[1],
                heatmap->legend_rect[2], heatmap->legend_rect[3]);
    glUniform2f(m_heat.uniform("u_viewport"), float(fb_width), float(fb_height));
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_BLEND);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

Image ImagePresenter::read_back() const {
  Image image;
  if (m_texture_count == 0) return image;
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(m_width) * m_height * 4);
  glBindTexture(GL_TEXTURE_2D, m_textures[m_shown]);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  image.resize(m_width, m_height);
  for (std::size_t i = 0; i < static_cast<std::size_t>(m_width) * m_height; ++i)
    for (int c = 0; c < 3; ++c) image.rgb[i * 3 + c] = rgba[i * 4 + c] / 255.0f;
  return image;
}

}  // namespace flashgs::viewer
