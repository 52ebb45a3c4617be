// SplitViewPresenter: the comparison's images as textures, drawn split at the divider or (the difference image) alone.
#pragma once

#include "flashgs/image.h"
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
  // Uploads the comparison's left and right renders and their difference image (float RGB,
  // top row first; the same conversion to 8 bits as the frame's upload).
  void set_images(const Image& left, const Image& right, const Image& difference);
  // Over the whole framebuffer: left | right split at `divider` (fraction of the width) with a
  // white line `line_px` wide, or the difference image when `difference` is set.
  void draw(int framebuffer_width, int framebuffer_height, float divider, float line_px, bool difference);

 private:
  void upload(GLuint texture, const Image& image);

  ShaderProgram m_program;
  GLuint m_vao = 0;
  GLuint m_textures[3] = {};  // left, right, difference
};

}  // namespace flashgs::viewer
