// FramePath: how a rendered frame reaches the window's texture (CUDA-GL interop, or a renderer's image uploaded from host memory).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/renderer.h"
#include "flashgs/scene.h"
#include "flashgs/stats.h"
#include "render_worker.h"

namespace flashgs::viewer {

class FramePath {
 public:
  virtual ~FramePath() = default;
  // What the window shows as the active path, e.g. "CUDA-GL interop" or "CPU + texture upload".
  virtual std::string name() const = 0;
  // Throws flashgs::Error when the scene cannot be held (the previous one then stays).
  virtual void set_scene(std::shared_ptr<const Scene> scene) = 0;
  // The parts of a streamed cut as the scene (Renderer::set_scene_parts: the CUDA backend keeps
  // them on the GPU under `resident_bytes`, the CPU backend assembles them). Failures as set_scene's.
  virtual void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) = 0;
  // Why parts set here cannot be rendered with `options` (Renderer::scene_parts_refusal; empty:
  // they can). By default they can: a host renderer assembles them.
  virtual std::string scene_parts_refusal(const RenderOptions& options) const {
    (void)options;
    return {};
  }
  // How many frame textures the path writes in turn: 2 when it renders the next frame into
  // one while the window shows the other.
  virtual int texture_count() const { return 1; }
  // Binds the frame textures (texture_count() GL texture names, RGBA8, width x height). Called
  // again after every resize; release_textures() comes first. Throws flashgs::Error when the
  // path cannot write into them (e.g. interop refused): the caller then falls back to another path.
  virtual void attach_textures(const unsigned* textures, int width, int height) = 0;
  virtual void release_textures() = 0;
  // Renders the camera's view into an attached texture. A path with two textures may leave
  // this frame in flight and have the window show the previous one (shown_texture()), so
  // that the GPU renders while the window system presents; present_latest() ends that.
  virtual void render_to_texture(const Camera& camera, const RenderOptions& options, FrameStats* stats) = 0;
  // The attached texture the window shows now.
  virtual int shown_texture() const { return 0; }
  // Makes the last render the shown texture (waits for nothing on the host: GL orders its
  // use after the render). For frames that render nothing, screenshots and checks.
  virtual void present_latest() {}
  // Renders into host memory (compare mode, float screenshots). Thread-safe on a path that
  // renders_in_background(): the comparison calls it from a task thread, and there the render
  // stops early (stats->cancelled set) once `cancel` is set; the other paths finish it (a GPU
  // frame takes milliseconds). `cancel` may be null.
  virtual void render_image(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats,
                            const std::atomic<bool>* cancel) = 0;

  // The viewer's one way to get frames, on every path. A path that renders in the background
  // (the CPU backend on its worker thread) returns from submit() at once and delivers the frame
  // later through take_finished(); the others render it in submit() (exceptions propagate:
  // the caller falls back to the CPU path) and deliver it at the next take_finished().
  virtual bool renders_in_background() const { return false; }
  // Asks for the view; `cancel_in_flight`: a background frame rendering now is stopped.
  virtual void submit(const FrameRequest& request, bool cancel_in_flight);
  // The frame that reached the texture since the last call: its request, stats and wall time
  // (the image stays in the path: last_image()). False when none did.
  virtual bool take_finished(FinishedFrame* frame);
  // A submitted frame is not yet delivered.
  virtual bool busy() const { return false; }
  // Blocks until every submitted frame is delivered (scripted runs time and check it).
  virtual void wait_until_idle() {}
  // Per-tile pair counts of the last render_to_texture (needs options.collect_tile_counts).
  virtual void tile_counts(const FrameStats& stats, std::vector<std::uint32_t>& out) = 0;
  // The last frame in float if this path keeps one in host memory, else null.
  virtual const Image* last_image() const { return nullptr; }

 private:
  bool m_has_done = false;  // submit()'s frame, for take_finished() (synchronous paths)
  FinishedFrame m_done;
};

class ImagePresenter;

// Any Renderer's float image converted and uploaded with glTexSubImage2D (the CUDA backend
// when interop is refused). `label` names the path in the window.
std::unique_ptr<FramePath> make_upload_path(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter,
                                            std::string label);
// The same upload, the renders on a RenderWorker thread (the CPU backend): the window never
// waits for a frame. `wake` runs on the worker after each frame (it wakes the event loop).
std::unique_ptr<FramePath> make_background_upload_path(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter,
                                                       std::string label, std::function<void()> wake);

// The CUDA backend writing straight into the GL texture through interop; when interop is
// refused (Mesa context, GPU not driving the display) the CUDA backend through host memory.
// Returns null with `why` filled when there is no usable CUDA device or this build has none.
// Needs the GL context current.
std::unique_ptr<FramePath> make_cuda_path(ImagePresenter* presenter, std::string* why);

}  // namespace flashgs::viewer
