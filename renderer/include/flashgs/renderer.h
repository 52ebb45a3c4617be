// Renderer: the interface every backend (CPU, CUDA) implements, and the CPU factory.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flashgs/backend_tuning.h"
#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/scene.h"
#include "flashgs/scene_parts.h"
#include "flashgs/stats.h"

namespace flashgs {

class Renderer {
 public:
  virtual ~Renderer() = default;
  virtual std::string name() const = 0;
  // Makes `scene` the one rendered from now on (the CUDA backend uploads it once here).
  // Throws flashgs::Error when the scene cannot be held (e.g. out of GPU memory); the
  // previous scene then stays.
  virtual void set_scene(std::shared_ptr<const Scene> scene) = 0;
  // Makes the parts, one after another, the scene rendered from now on (a streamed LOD cut).
  // A backend that holds its scene on the GPU uploads only the parts whose keys it does not
  // hold, and keeps parts no longer drawn while they fit in `resident_bytes` (0: no limit) for
  // a later cut. By default the parts are assembled into one scene for set_scene.
  virtual void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes);
  // Why a scene set as parts cannot be rendered with `options` (empty: it can). A backend that
  // keeps the parts in a layout of its own (the CUDA pool) draws them with fewer options than a
  // scene set whole; by default the parts are a scene like any other.
  virtual std::string scene_parts_refusal(const RenderOptions& options) const {
    (void)options;
    return {};
  }
  // Renders one frame. `stats` may be null.
  virtual void render(const Camera& camera, const RenderOptions& options, Image& out,
                      FrameStats* stats) = 0;

  // A flag another thread sets to stop the render in flight (the viewer's progressive CPU
  // path): render() then returns at its next check with FrameStats::cancelled set and an
  // incomplete image. The caller clears the flag before each render; null = never cancelled.
  // A backend that cannot stop early finishes the frame.
  void set_cancel_flag(const std::atomic<bool>* flag) { m_cancel_flag = flag; }

 protected:
  bool cancel_requested() const {
    return m_cancel_flag != nullptr && m_cancel_flag->load(std::memory_order_relaxed);
  }
  // The flag set_cancel_flag gave (a renderer that wraps another passes it on).
  const std::atomic<bool>* cancel_flag() const { return m_cancel_flag; }

 private:
  const std::atomic<bool>* m_cancel_flag = nullptr;
};

// How the CPU backend composites its tiles: SIMD (the widest vectors this CPU has, chosen at
// run time) or the scalar reference kernel the SIMD one is tested against.
enum class CpuBlend { simd, scalar };

// The multi-threaded CPU backend; `threads` = 0 uses every core. Of `tuning` it reads cpu_simd
// (by default, as the environment sets it).
std::unique_ptr<Renderer> make_cpu_renderer(int threads = 0, CpuBlend blend = CpuBlend::simd,
                                            const BackendTuning& tuning = tuning_from_environment());

}  // namespace flashgs
