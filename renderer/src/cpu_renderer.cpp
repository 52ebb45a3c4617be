// The CPU backend: runs the stages in order, times them, fills FrameStats.
#include <chrono>
#include <cstdio>
#include <functional>
#include <new>
#include <thread>

#include "cpu_frame.h"
#include "flashgs/error.h"
#include "flashgs/frame_params.h"
#include "flashgs/renderer.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace flashgs {

namespace {

// The blend kernel's name, after the cpu_simd knob has picked the SIMD target.
std::string blend_kernel_name(CpuBlend blend, const std::string& simd_limit) {
  cpu::apply_simd_target_limit(simd_limit);
  return blend == CpuBlend::scalar ? "scalar" : cpu::simd_target_name();
}

class CpuRenderer final : public Renderer {
 public:
  CpuRenderer(int threads, CpuBlend blend, const BackendTuning& tuning)
      : kernel_(blend == CpuBlend::scalar ? cpu::BlendKernel::scalar : cpu::BlendKernel::simd),
        kernel_name_(blend_kernel_name(blend, tuning.cpu_simd)) {
#ifdef _OPENMP
    frame_.threads = threads > 0 ? threads : omp_get_max_threads();
#else
    (void)threads;
    frame_.threads = 1;
#endif
  }
  std::string name() const override {
    return "cpu (" + std::to_string(frame_.threads) + " threads, " + kernel_name_ + " blend)";
  }
  void set_scene(std::shared_ptr<const Scene> scene) override {
    assembled_.reset();
    spare_.reset();
    install(std::move(scene));
  }
  // A streamed cut changes nearly every frame of a flight: it is assembled into the arrays of
  // the cut before last when nothing else holds that one, so no new pages are zeroed for it.
  // The streamer's host cap counts two drawn scenes (the one drawn and the next).
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t) override {
    std::shared_ptr<Scene> target = spare_ && spare_.use_count() == 1 ? std::move(spare_) : std::make_shared<Scene>();
    spare_.reset();
    assemble_scene_parts_into(parts, *target);
    spare_ = std::move(assembled_);
    assembled_ = target;
    install(std::move(target));
  }

  void render(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats_out) override {
    // A frame too large for this machine's memory (e.g. 65536^2: 51 GB of float RGB) is a
    // clear error naming the size, not a bare std::bad_alloc.
    try {
      render_frame(camera, options, out, stats_out);
    } catch (const std::bad_alloc&) {
      const double gb = static_cast<double>(camera.width) * camera.height * 12.0 / 1e9;
      char text[200];
      std::snprintf(text, sizeof text,
                    "cpu renderer: out of memory for a %dx%d frame (%.1f GB of float RGB, plus pairs for %zu "
                    "Gaussians)",
                    camera.width, camera.height, gb, scene_ ? scene_->size() : std::size_t{0});
      throw Error(text);
    }
  }

 private:
  void render_frame(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats_out) {
    using Clock = std::chrono::steady_clock;
    auto ms_since = [](Clock::time_point t) {
      return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
    };
    if (!scene_) throw Error("cpu renderer: no scene set");
    if (camera.width < 1 || camera.height < 1) throw Error("cpu renderer: image size must be at least 1x1");
    FrameStats stats;
    const auto start = Clock::now();
    frame_.camera = make_camera_params(camera);
    frame_.geometry = make_geometry_params(options);
    stats.gaussians = scene_->size();
    stats.tiles_x = frame_.camera.tiles_x;
    stats.tiles_y = frame_.camera.tiles_y;

    // A cancelled frame stops between stages or between tiles and returns what it has.
    auto finish_cancelled = [&] {
      stats.cancelled = true;
      stats.times.total_ms = ms_since(start);
      if (stats_out) *stats_out = std::move(stats);
    };
    const std::function<bool()> cancelled = [this] { return cancel_requested(); };

    auto t = Clock::now();
    cpu::project(*scene_, options, frame_, stats);
    stats.times.project_ms = ms_since(t);
    if (cancelled()) return finish_cancelled();
    // The sort stage runs in two parts: the depth order before emit, the tile order after it.
    t = Clock::now();
    cpu::order_by_depth(frame_, static_cast<std::int64_t>(scene_->size()));
    const double depth_order_ms = ms_since(t);
    if (cancelled()) return finish_cancelled();
    cpu::check_pairs_fit(options, frame_);
    t = Clock::now();
    cpu::emit(options, frame_, stats);
    stats.times.emit_ms = ms_since(t);
    if (cancelled()) return finish_cancelled();
    t = Clock::now();
    cpu::sort_by_tile(frame_, stats, &stats.times.ranges_ms);
    stats.times.sort_ms = depth_order_ms + ms_since(t) - stats.times.ranges_ms;
    if (cancelled()) return finish_cancelled();
    t = Clock::now();
    if (out.width != camera.width || out.height != camera.height) out.resize(camera.width, camera.height);
    cpu::PixelPlanes planes{};
    const bool want_planes = options.collect_pixel_planes && stats_out;
    if (want_planes) {
      const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
      stats.pixel_depth.resize(pixels);
      stats.pixel_blended.resize(pixels);
      planes = {stats.pixel_depth.data(), stats.pixel_blended.data()};
    }
    const bool complete =
        cpu::blend(options, frame_, kernel_, cancelled, out.rgb.data(), want_planes ? &planes : nullptr);
    stats.times.blend_ms = ms_since(t);
    if (!complete) return finish_cancelled();
    stats.times.total_ms = ms_since(start);

    if (options.collect_tile_counts) {
      const std::size_t tiles = frame_.tile_start.size() - 1;
      stats.tile_pair_counts.resize(tiles);
      for (std::size_t i = 0; i < tiles; ++i)
        stats.tile_pair_counts[i] = static_cast<std::uint32_t>(frame_.tile_start[i + 1] - frame_.tile_start[i]);
    }
    if (stats_out) *stats_out = std::move(stats);
  }

  void install(std::shared_ptr<const Scene> scene) {
    scene_ = std::move(scene);
    frame_.half_sh_of = nullptr;  // another scene may live at the old one's address
    frame_.half_shape_of = nullptr;
    frame_.opacity_terms_of = nullptr;
  }

  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<Scene> assembled_, spare_;  // set_scene_parts' scene drawn now, and the one before
  const cpu::BlendKernel kernel_;
  const std::string kernel_name_;  // the SIMD target, or "scalar"
  cpu::Frame frame_;
};

}  // namespace

std::unique_ptr<Renderer> make_cpu_renderer(int threads, CpuBlend blend, const BackendTuning& tuning) {
  return std::make_unique<CpuRenderer>(threads, blend, tuning);
}

}  // namespace flashgs
