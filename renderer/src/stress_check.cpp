// Stress-case judge (see stress_check.h).
#include "flashgs/stress_check.h"

#include <chrono>
#include <cstring>
#include <new>

#include "flashgs/error.h"
#include "flashgs/reference_renderer.h"

namespace flashgs {
namespace {

std::vector<PixelWindow> windows_of(const StressCase& c, const Camera& camera) {
  if (!c.windows.empty()) return c.windows;
  PixelWindow whole;
  whole.width = camera.width;
  whole.height = camera.height;
  return {whole};
}

bool bit_identical(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

}  // namespace

StressReference render_stress_reference(const StressCase& c, const SplatKernel& kernel) {
  StressReference ref;
  const auto start = std::chrono::steady_clock::now();
  RenderOptions options;  // the reference uses only the background, the SH cap and the kernel
  options.kernel = kernel;
  for (const Camera& camera : c.cameras)
    for (const PixelWindow& w : windows_of(c, camera)) ref.images.push_back(render_reference(c.scene, camera, options, w));
  ref.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return ref;
}

StressResult run_stress_case(const StressCase& c, const StressReference& reference, Renderer& renderer,
                             const std::string& backend_name, Algorithm algorithm, Renderer* second,
                             std::vector<Image>* keep_images, const SplatKernel& kernel) {
  StressResult r;
  r.case_name = c.name;
  r.backend = backend_name;
  r.algorithm = algorithm_name(algorithm);
  r.kernel = kernel.spec();
  r.bound = algorithm == Algorithm::baseline ? c.bound_baseline : c.bound_flash;
  RenderOptions options = algorithm == Algorithm::baseline ? RenderOptions::baseline() : RenderOptions{};
  options.kernel = kernel;
  std::size_t ref_index = 0;
  try {
    for (const Camera& camera : c.cameras) {
      Image first, again;
      FrameStats stats;
      renderer.render(camera, options, first, &stats);
      r.milliseconds += stats.times.total_ms;
      r.kv_pairs += stats.kv_pairs;
      r.culled_degenerate += stats.culled_degenerate;
      r.non_finite += count_non_finite(first);
      renderer.render(camera, options, again, nullptr);
      if (!bit_identical(first, again)) r.deterministic = false;
      if (second) {
        second->render(camera, options, again, nullptr);
        if (!bit_identical(first, again)) r.deterministic = false;
      }
      again = Image();  // free before the comparisons: the huge cases are gigabytes
      for (const PixelWindow& w : windows_of(c, camera)) {
        const Image crop = c.windows.empty() ? first : crop_image(first, w);
        const ImageDifference d = compare_images(crop, reference.images.at(ref_index++));
        if (d.max_abs > r.max_abs_error) r.max_abs_error = d.max_abs;
      }
      if (keep_images) keep_images->push_back(std::move(first));
    }
    r.ran = true;
  } catch (const std::bad_alloc&) {
    r.error = "out of memory";
    r.clear_error = true;
  } catch (const Error& e) {
    r.error = e.what();
    r.clear_error = true;  // flashgs::Error carries a message naming the problem
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  if (!r.ran) {
    // A huge image may be refused, with a clear message, where memory does not allow it.
    r.pass = c.huge && r.clear_error;
    r.why_failed = r.pass ? "" : "exception: " + r.error;
    return r;
  }
  std::string why;
  if (r.non_finite) why += "NaN/Inf pixels; ";
  if (!r.deterministic) why += "not deterministic; ";
  if (!(r.max_abs_error <= r.bound)) why += "error above the bound; ";
  r.pass = why.empty();
  r.why_failed = why;
  return r;
}

}  // namespace flashgs
