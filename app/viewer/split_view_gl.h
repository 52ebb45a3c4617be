// SplitViewPresenter: the comparison's images as textures, drawn split at the divider or (the difference image) alone.
#pragma once

#include <cstdint>

#include "gl_headers_gl.h"
#include "shader_program_gl.h"

namespace flashgs::viewer {

class SplitViewPresenter {
 public:
  SplitViewPresenter() = default;
  ~SplitViewPresenter();
  SplitViewPresenter(const SplitViewPresenter&) = delete;
  SplitViewPresenter& operator=(const SplitViewPresenter&) = delete;

  void init();  // compiles the shader (throws flashgs::Error with the driver's log)
  // Uploads the comparison's left (0) or right (1) render or their difference image (2),
  // `width` x `height` RGBA8 bytes (to_rgba8, done beforehand: it takes longer than a frame).
  void set_image(int index, int width, int height, const std::uint8_t* rgba);
  // Over the whole framebuffer: left | right split at `divider` (fraction of the width) with a
  // white line `line_px` wide, or the difference image when `difference` is set.
  void draw(int framebuffer_width, int framebuffer_height, float divider, float line_px, bool difference);

 private:

  ShaderProgram m_program;
  GLuint m_vao = 0;
  GLuint m_textures[3] = {};  // left, right, difference
};

}  // namespace flashgs::viewer
