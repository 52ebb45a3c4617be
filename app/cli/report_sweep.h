// The configurations `flashgs report` sweeps, and the measurement of one configuration on one
// backend: frame times, kv pairs, memory, error against the baseline and the fp64 reference.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/reference_renderer.h"
#include "flashgs/renderer.h"

namespace flashgs::cli {

struct SweepConfig {
  std::string name;   // e.g. "flash", "only-tight_bbox", "no-exact_tile_test", "tau=1/32"
  std::string group;  // baseline | flash | alone | left out | tau | precision | kernel | gpu alone | gpu left out
  RenderOptions options;
  bool gpu_only = false;  // a scheduling switch the CPU backend ignores: measured on CUDA only
};

// baseline; flash (everything on, default tau); each switch every backend honours alone and
// each left out; tau = 1/128 ... 1/16; the SH, the shapes or both as halves (fp16-sh,
// fp16-shape, fp16-all); flash with each other kernel (kernel=classic, kernel=antialiased,
// kernel=antialiased=0.1: how far the image moves from the trained one); and each GPU-only
// switch alone and left out. Every configuration but those of the kernel group draws with
// `trained`, the kernel the scene was trained with.
std::vector<SweepConfig> sweep_configs(const SplatKernel& trained);

// Error of a set of images against another, pooled over cameras / windows.
struct ErrorSummary {
  double psnr_db = 0;            // from the pooled MSE (infinity when identical)
  double max_abs = 0;            // over every pixel and channel
  double fraction_over = 0;      // pixels off by more than 1/255, pooled
  std::uint64_t non_finite = 0;  // NaN/Inf values
  void add(const ImageDifference& d, std::size_t pixels);
  void finish();
  double sum_sq_ = 0, over_ = 0;
  std::size_t pixels_ = 0;
};

struct SweepResult {
  std::string backend;
  SweepConfig config;
  std::vector<double> frame_ms;  // every timed frame (FrameStats total), all cameras
  double median_ms = 0, p95_ms = 0;  // p95: flashgs::kTailPercentile
  double kv_pairs = 0;           // mean per frame
  double peak_memory_mb = -1;    // backend working memory above the scene; -1: not reported
  ErrorSummary vs_baseline;      // whole images, same backend, same cameras
  ErrorSummary vs_reference;     // the reference windows
};

// Inputs shared by every configuration of one backend.
struct SweepFrames {
  std::vector<Camera> cameras;
  std::vector<PixelWindow> windows;       // per camera, where the fp64 reference is evaluated
  std::vector<std::vector<Image>> reference;  // [camera][window]
  std::vector<Image> baseline;            // this backend's baseline image per camera (filled by the first run)
};

// Renders `config` for every camera: one untimed warm-up, then `repeat` timed frames each.
SweepResult measure_config(Renderer& renderer, const std::string& backend, const SweepConfig& config,
                           SweepFrames& frames, int repeat);

}  // namespace flashgs::cli
