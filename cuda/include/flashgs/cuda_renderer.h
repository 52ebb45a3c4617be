// The CUDA backend's public face: no CUDA headers here, so the CLI and viewer build without them.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flashgs/backend_tuning.h"
#include "flashgs/renderer.h"

namespace flashgs {

// True when a CUDA device can run our kernels; otherwise `why` says what is missing.
bool cuda_available(std::string* why);

class CudaRenderer : public Renderer {
 public:
  // Renders and writes the frame as RGBA8 (alpha 255, values clamped to [0, 1]) into a CUDA
  // surface object (a cudaSurfaceObject_t, e.g. of a GL texture mapped through interop);
  // image row 0 (the top) goes to surface row 0. No copy to the host, and no wait for the
  // frame's end: the caller presents it while the GPU finishes (work queued later on stream()
  // runs after it). So `stats` has this frame's counts but the previous frame's stage times
  // (this frame's on the first call, or after a failed one).
  virtual void render_to_surface(const Camera& camera, const RenderOptions& options,
                                 std::uint64_t surface_object, FrameStats* stats) = 0;
  // Renders into the renderer's own device image (float RGB, as render() computes it) and
  // returns without copying it to the host or waiting for the frame's end, as
  // render_to_surface does: frames queued back to back, the way the viewer renders them, so that
  // the host's launches for the next frame overlap this one's GPU work (`flashgs bench` times
  // these). `stats` as render_to_surface; a later render() waits for every queued frame.
  virtual void render_queued(const Camera& camera, const RenderOptions& options, FrameStats* stats) = 0;
  // Renders as render() does (this frame's statistics, the frame finished when it returns) but
  // copies the float RGB image (height x width x 3, row 0 the top) into `destination`, a buffer
  // of that many floats on this renderer's device, instead of the host: for callers whose
  // frames stay on the GPU (a PyTorch tensor). Work the caller queued elsewhere that the buffer
  // depends on must be finished or waited for on stream() first.
  virtual void render_to_device(const Camera& camera, const RenderOptions& options, void* destination,
                                FrameStats* stats) = 0;
  // Returns once every queued frame has finished on the GPU.
  virtual void finish() = 0;
  // Per-tile pair counts of the last frame (row-major tiles_y x tiles_x), copied from the
  // device only when this is called.
  virtual void download_tile_counts(std::vector<std::uint32_t>& counts) = 0;
  // The cudaStream_t all work is queued on (for interop map/unmap on the same stream).
  virtual void* stream() const = 0;
};

// `tuning`: how it makes frames (by default, as the environment sets it).
std::unique_ptr<CudaRenderer> make_cuda_renderer(const BackendTuning& tuning = tuning_from_environment());

}  // namespace flashgs
