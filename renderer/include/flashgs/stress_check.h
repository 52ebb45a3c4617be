// Runs one stress case on one backend and algorithm and judges it: no exception, no NaN/Inf
// pixel, the same image twice, and the error against the fp64 reference within the bound.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/renderer.h"
#include "flashgs/stress_scenes.h"

namespace flashgs {

// The fp64 reference of a case: one image per (camera, window), in that order.
struct StressReference {
  std::vector<Image> images;
  double seconds = 0;
};
// `kernel`: the footprint model the reference and the backends draw with.
StressReference render_stress_reference(const StressCase& stress_case, const SplatKernel& kernel = {});

struct StressResult {
  std::string case_name, backend, algorithm, kernel;
  bool ran = false;         // rendered without an exception
  std::string error;        // the exception's message otherwise
  bool clear_error = false; // an out-of-memory / size error with a message (allowed for huge cases)
  std::uint64_t non_finite = 0;  // NaN/Inf values in the rendered images
  double max_abs_error = 0;      // vs the reference, over every camera and window
  double bound = 0;
  bool deterministic = true;     // the second render was bit-identical
  std::uint64_t kv_pairs = 0;    // summed over the case's cameras
  std::uint64_t culled_degenerate = 0;
  double milliseconds = 0;       // total of the first render of each camera
  bool pass = false;
  std::string why_failed;
};

// `renderer` must already hold the case's scene (set_scene). `second` (may be null) is
// another renderer holding the same scene (e.g. another thread count): its image must also
// be bit-identical. `keep_images` (may be null) receives the first render of each camera.
// `kernel` must be the one `reference` was rendered with.
StressResult run_stress_case(const StressCase& stress_case, const StressReference& reference, Renderer& renderer,
                             const std::string& backend_name, Algorithm algorithm, Renderer* second = nullptr,
                             std::vector<Image>* keep_images = nullptr, const SplatKernel& kernel = {});

}  // namespace flashgs
