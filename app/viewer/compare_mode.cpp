// The comparison's configuration choices and the two timed renders.
#include "compare_mode.h"

#include <chrono>
#include <exception>
#include <iterator>

namespace flashgs::viewer {
namespace {

constexpr int kSwitchCount = static_cast<int>(std::size(kRenderSwitches));

RenderOptions untracked(RenderOptions o) {
  o.collect_tile_counts = false;  // not a configuration, only what the heat map needs
  // The baseline ignores the optimisation switches (switch_algorithm keeps them for flash):
  // any baseline is the same configuration.
  if (o.is_baseline())
    for (const RenderSwitch& sw : kRenderSwitches) o.*(sw.member) = RenderOptions::baseline().*(sw.member);
  return o;
}

}  // namespace

int compare_choice_count() { return 3 + kSwitchCount; }

RenderOptions compare_choice_options(int choice, const RenderOptions& current) {
  if (choice <= kCompareCurrent || choice >= compare_choice_count()) return untracked(current);
  RenderOptions o = choice == kCompareBaseline ? RenderOptions::baseline() : RenderOptions{};
  if (choice >= 3) o.*(kRenderSwitches[choice - 3].member) = false;
  o.tau = current.tau;
  o.sh_degree_cap = current.sh_degree_cap;
  o.kernel = current.kernel;
  for (int c = 0; c < 3; ++c) o.background[c] = current.background[c];
  return o;
}

std::string compare_choice_name(int choice) {
  if (choice <= kCompareCurrent || choice >= compare_choice_count()) return "current";
  return compare_choice_options(choice, RenderOptions{}).label();
}

int compare_choice_from_name(const std::string& name) {
  for (int c = 0; c < compare_choice_count(); ++c)
    if (compare_choice_name(c) == name) return c;
  return -1;
}

std::string same_configuration_problem(const RenderOptions& left, const RenderOptions& right) {
  if (!(untracked(left) == untracked(right))) return "";
  return "both sides are " + left.label() + ": nothing to compare (choose another configuration for one side)";
}

CompareResult run_compare(FramePath& path, const Camera& camera, const RenderOptions& left_options,
                          const RenderOptions& right_options, bool warm_up, const std::atomic<bool>* cancel) {
  CompareResult r;
  r.left_label = left_options.label();
  r.right_label = right_options.label();
  r.width = camera.width;
  r.height = camera.height;
  r.error = same_configuration_problem(left_options, right_options);
  if (!r.error.empty()) return r;
  try {
    const RenderOptions left = untracked(left_options), right = untracked(right_options);
    FrameStats sl, sr;
    // Each render, unless cancelled before it or during it; true when stopped.
    auto render = [&](const RenderOptions& options, Image& out, FrameStats& stats) {
      if (cancel && cancel->load()) return true;
      path.render_image(camera, options, out, &stats, cancel);
      return stats.cancelled;
    };
    auto stopped = [&] {
      r.error = kCompareCancelled;
      r.left_image = r.right_image = Image{};
      return r;
    };
    using clock = std::chrono::steady_clock;
    if (warm_up && render(right, r.right_image, sr)) return stopped();
    auto t0 = clock::now();
    if (render(right, r.right_image, sr)) return stopped();
    auto t1 = clock::now();
    if (warm_up && render(left, r.left_image, sl)) return stopped();
    auto t2 = clock::now();
    if (render(left, r.left_image, sl)) return stopped();
    auto t3 = clock::now();
    r.right_wall_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    r.left_wall_ms = std::chrono::duration<double, std::milli>(t3 - t2).count();
    r.right_ms = sr.times.total_ms;
    r.left_ms = sl.times.total_ms;
    r.right_kv = sr.kv_pairs;
    r.left_kv = sl.kv_pairs;
    r.difference = compare_images(r.right_image, r.left_image);
    r.valid = true;
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

}  // namespace flashgs::viewer
