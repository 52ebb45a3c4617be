// FramePath: how a rendered frame reaches the window's texture (CUDA-GL interop, or a renderer's image uploaded from host memory).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/renderer.h"
#include "flashgs/scene.h"
#include "flashgs/stats.h"

namespace flashgs::viewer {

class FramePath {
 public:
  virtual ~FramePath() = default;
  // What the window shows as the active path, e.g. "CUDA-GL interop" or "CPU + texture upload".
  virtual std::string name() const = 0;
  // Throws flashgs::Error when the scene cannot be held (the previous one then stays).
  virtual void set_scene(std::shared_ptr<const Scene> scene) = 0;
  // Binds the frame texture (a GL texture name, RGBA8, width x height). Called again after
  // every resize; release_texture() comes first. Throws flashgs::Error when the path cannot
  // write into it (e.g. interop refused): the caller then falls back to another path.
  virtual void attach_texture(unsigned texture, int width, int height) = 0;
  virtual void release_texture() = 0;
  // Renders the camera's view into the attached texture.
  virtual void render_to_texture(const Camera& camera, const RenderOptions& options, FrameStats* stats) = 0;
  // Renders into host memory (compare mode, float screenshots).
  virtual void render_image(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) = 0;
  // Per-tile pair counts of the last render_to_texture (needs options.collect_tile_counts).
  virtual void tile_counts(const FrameStats& stats, std::vector<std::uint32_t>& out) = 0;
  // The last frame in float if this path keeps one in host memory, else null.
  virtual const Image* last_image() const { return nullptr; }
};

class ImagePresenter;

// Any Renderer's float image converted and uploaded with glTexSubImage2D (CPU backend, or the
// CUDA backend when interop is refused). `label` names the path in the window.
std::unique_ptr<FramePath> make_upload_path(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter,
                                            std::string label);

// The CUDA backend writing straight into the GL texture through interop; when interop is
// refused (Mesa context, GPU not driving the display) the CUDA backend through host memory.
// Returns null with `why` filled when there is no usable CUDA device or this build has none.
// Needs the GL context current.
std::unique_ptr<FramePath> make_cuda_path(ImagePresenter* presenter, std::string* why);

}  // namespace flashgs::viewer
