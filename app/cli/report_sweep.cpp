// Sweep configurations and their measurement (see report_sweep.h).
#include "report_sweep.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "flashgs/percentile.h"

namespace flashgs::cli {

std::vector<SweepConfig> sweep_configs(const SplatKernel& trained) {
  std::vector<SweepConfig> out;
  out.push_back({"baseline", "baseline", RenderOptions::baseline(), false});
  out.push_back({"flash", "flash", RenderOptions{}, false});
  // The switches every backend honours, and those only the GPU does (the CPU skips their rows).
  std::vector<const RenderSwitch*> every_backend, gpu_only;
  for (const RenderSwitch& s : kRenderSwitches) (s.honoured_by(Backend::cpu) ? every_backend : gpu_only).push_back(&s);
  // For a group of switches: each one alone (the others of the group off), then each one left
  // out (the rest of the flash defaults kept).
  auto add_group = [&out](const std::vector<const RenderSwitch*>& group, const std::string& alone_prefix,
                          const std::string& alone_kind, const std::string& left_out_kind, bool gpu_only) {
    for (const RenderSwitch* s : group) {
      RenderOptions o;
      for (const RenderSwitch* other : group) o.*(other->member) = false;
      o.*(s->member) = true;
      out.push_back({alone_prefix + s->label, alone_kind, o, gpu_only});
    }
    for (const RenderSwitch* s : group) {
      RenderOptions o;
      o.*(s->member) = false;
      out.push_back({std::string("no-") + s->label, left_out_kind, o, gpu_only});
    }
  };
  add_group(every_backend, "only-", "alone", "left out", false);
  for (int denominator : {128, 64, 32, 16}) {
    RenderOptions o;
    o.tau = 1.0f / static_cast<float>(denominator);
    out.push_back({"tau=1/" + std::to_string(denominator), "tau", o, false});
  }
  // Not exact: the SH coefficients, the shapes or both as halves (fewer scene bytes on the GPU).
  for (const RenderOptions& o : fp16_configs())
    out.push_back({o.fp16_sh && o.fp16_shape ? "fp16-all" : o.fp16_sh ? "fp16-sh" : "fp16-shape", "precision", o, false});
  // The half blend: a CUDA kernel (the CPU renders these exactly, so it skips their rows).
  for (const RenderOptions& o : fp16_blend_configs())
    out.push_back({o.fp16_sh ? "fp16-all-blend" : "fp16-blend", "precision", o, true});
  // Not the scene's image: the error says how far drawing with another kernel moves it.
  for (const SplatKernel& k : kTrainerKernels) {
    if (k == trained) continue;
    RenderOptions o;
    o.kernel = k;
    out.push_back({"kernel=" + k.spec(), "kernel", o, false});
  }
  add_group(gpu_only, "gpu-only-", "gpu alone", "gpu left out", true);
  for (SweepConfig& c : out)
    if (c.group != "kernel") c.options.kernel = trained;
  return out;
}

void ErrorSummary::add(const ImageDifference& d, std::size_t pixels) {
  sum_sq_ += d.mse * 3.0 * static_cast<double>(pixels);
  over_ += d.fraction_over_1_255 * static_cast<double>(pixels);
  pixels_ += pixels;
  max_abs = std::max(max_abs, d.max_abs);
  non_finite += d.non_finite;
}

void ErrorSummary::finish() {
  const double mse = pixels_ ? sum_sq_ / (3.0 * static_cast<double>(pixels_)) : 0.0;
  psnr_db = mse > 0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
  fraction_over = pixels_ ? over_ / static_cast<double>(pixels_) : 0.0;
}

SweepResult measure_config(Renderer& renderer, const std::string& backend, const SweepConfig& config,
                           SweepFrames& frames, int repeat) {
  SweepResult r;
  r.backend = backend;
  r.config = config;
  const bool is_baseline = config.options.is_baseline();
  if (is_baseline) frames.baseline.assign(frames.cameras.size(), Image());
  double kv_sum = 0;
  std::uint64_t peak = 0;
  bool memory_reported = false;
  for (std::size_t c = 0; c < frames.cameras.size(); ++c) {
    Image image;
    FrameStats stats;
    renderer.render(frames.cameras[c], config.options, image, &stats);  // warm-up; also the image judged
    for (int k = 0; k < repeat; ++k) {
      Image timed;
      renderer.render(frames.cameras[c], config.options, timed, &stats);
      r.frame_ms.push_back(stats.times.total_ms);
      kv_sum += static_cast<double>(stats.kv_pairs);
      if (stats.device_peak_bytes) memory_reported = true;
      peak = std::max<std::uint64_t>(peak, stats.device_peak_bytes);
    }
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    if (is_baseline) frames.baseline[c] = image;
    if (c < frames.baseline.size() && frames.baseline[c].width == image.width)
      r.vs_baseline.add(compare_images(image, frames.baseline[c]), pixels);
    if (c < frames.reference.size())
      for (std::size_t w = 0; w < frames.windows.size(); ++w) {
        const PixelWindow& window = frames.windows[w];
        r.vs_reference.add(compare_images(crop_image(image, window), frames.reference[c][w]),
                           static_cast<std::size_t>(window.width) * window.height);
      }
  }
  r.vs_baseline.finish();
  r.vs_reference.finish();
  r.median_ms = median(r.frame_ms);
  r.p95_ms = percentile(r.frame_ms, kTailPercentile);
  r.kv_pairs = r.frame_ms.empty() ? 0 : kv_sum / static_cast<double>(r.frame_ms.size());
  if (memory_reported) r.peak_memory_mb = static_cast<double>(peak) / 1e6;
  return r;
}

}  // namespace flashgs::cli
