// Baseline-vs-current rendering and comparison for the compare panel.
#include "compare_mode.h"

#include <chrono>
#include <exception>

namespace flashgs::viewer {

CompareResult run_compare(FramePath& path, const Camera& camera, const RenderOptions& current) {
  CompareResult r;
  r.current_label = current.label();
  r.width = camera.width;
  r.height = camera.height;
  try {
    RenderOptions baseline = RenderOptions::baseline();
    // Only the algorithm differs: the same colour inputs, so any difference is the algorithm's.
    baseline.tau = current.tau;
    baseline.sh_degree_cap = current.sh_degree_cap;
    for (int c = 0; c < 3; ++c) baseline.background[c] = current.background[c];
    RenderOptions cur = current;
    cur.collect_tile_counts = false;
    Image a, b;
    FrameStats sa, sb;
    using clock = std::chrono::steady_clock;
    // Each rendered twice; the second is timed, so a first-use allocation does not count.
    path.render_image(camera, cur, a, &sa);
    auto t0 = clock::now();
    path.render_image(camera, cur, a, &sa);
    auto t1 = clock::now();
    path.render_image(camera, baseline, b, &sb);
    auto t2 = clock::now();
    path.render_image(camera, baseline, b, &sb);
    auto t3 = clock::now();
    r.current_wall_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    r.baseline_wall_ms = std::chrono::duration<double, std::milli>(t3 - t2).count();
    r.current_ms = sa.times.total_ms;
    r.baseline_ms = sb.times.total_ms;
    r.current_kv = sa.kv_pairs;
    r.baseline_kv = sb.kv_pairs;
    r.difference = compare_images(a, b);
    r.valid = true;
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

}  // namespace flashgs::viewer
