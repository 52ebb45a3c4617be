// ImagePresenter: the frame texture, its blit to the window, and the per-tile heat-map overlay with its legend.
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/image.h"
#include "rgba8_image.h"
#include "gl_headers_gl.h"
#include "shader_program_gl.h"

namespace flashgs::viewer {

struct HeatmapView {
  bool log_scale = true;
  float opacity = 0.6f;
  float legend_rect[4] = {0, 0, 0, 0};  // window framebuffer pixels (x0, y0, x1, y1), y down
};

class ImagePresenter {
 public:
  ImagePresenter() = default;
  ~ImagePresenter();
  ImagePresenter(const ImagePresenter&) = delete;
  ImagePresenter& operator=(const ImagePresenter&) = delete;

  // Compiles the shaders (throws flashgs::Error with the driver's log).
  void init();
  static constexpr int kMaxTextures = 2;
  // Whether the frame textures must be recreated for width x height (or another count).
  bool needs_resize(int width, int height, int count = 1) const {
    return width != m_width || height != m_height || count != m_texture_count;
  }
  // Recreates `count` RGBA8 frame textures (the old ones are deleted: detach interop first);
  // texture 0 is shown. Throws flashgs::Error when GL refuses them (none are left then).
  void resize(int width, int height, int count = 1);
  GLuint texture(int index) const { return m_textures[index]; }
  // Which frame texture draw() and read_back() use.
  void show(int index) { m_shown = index; }
  int width() const { return m_width; }
  int height() const { return m_height; }

  // Uploads a float RGB image (top row first) as RGBA8 into texture 0; the host-memory path.
  void upload(const Image& image);
  // Per-tile pair counts (row-major tiles_y x tiles_x) for the overlay; `max_count` tops the scale.
  void set_tile_counts(const std::vector<std::uint32_t>& counts, int tiles_x, int tiles_y, std::uint32_t max_count);
  std::uint32_t heatmap_max() const { return m_max_count; }

  // Draws the frame over the whole framebuffer, then the overlay when `heatmap` is non-null.
  void draw(int framebuffer_width, int framebuffer_height, const HeatmapView* heatmap);
  // The shown frame texture read back as float RGB (top row first): screenshots of the CUDA path.
  Image read_back() const;

 private:
  ShaderProgram m_blit, m_heat;
  GLuint m_vao = 0;
  GLuint m_textures[kMaxTextures] = {};
  int m_texture_count = 0, m_shown = 0;
  GLuint m_counts = 0;
  int m_width = 0, m_height = 0;
  int m_tiles_x = 0, m_tiles_y = 0;
  std::uint32_t m_max_count = 1;
  std::vector<std::uint8_t> m_rgba;    // staging for upload()
  std::vector<float> m_count_floats;   // staging for set_tile_counts()
};

}  // namespace flashgs::viewer
