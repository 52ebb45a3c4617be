// The comparison's configuration choices and the two timed renders.
#include "compare_mode.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iterator>

#include "flashgs/percentile.h"

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

std::string compare_choice_title(int choice) {
  if (choice >= 3 && choice < compare_choice_count()) return std::string("flash without ") + kRenderSwitches[choice - 3].ui_name;
  return compare_choice_name(choice);
}

bool compare_choice_offered(int choice, Backend backend) {
  return choice < 3 || choice >= compare_choice_count() || kRenderSwitches[choice - 3].honoured_by(backend);
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

Spread spread_of(const std::vector<double>& samples) {
  Spread s;
  if (samples.empty()) return s;
  s.median = median(samples);
  s.min = *std::min_element(samples.begin(), samples.end());
  s.max = *std::max_element(samples.begin(), samples.end());
  s.samples = static_cast<int>(samples.size());
  return s;
}

bool within_noise(const Spread& speed_up) { return speed_up.min <= 1.0 && speed_up.max >= 1.0; }

std::string speed_up_text(const CompareResult& r) {
  char text[160];
  std::snprintf(text, sizeof text, "speed-up %.2fx (%.2f-%.2f over %d rounds)%s", r.speed_up.median, r.speed_up.min,
                r.speed_up.max, r.speed_up.samples, within_noise(r.speed_up) ? ": within noise" : "");
  return text;
}

std::string compare_sides_problem(int left, int right, const RenderOptions& current, Backend backend) {
  for (int choice : {left, right})
    if (!compare_choice_offered(choice, backend))
      return compare_choice_title(choice) + " renders as flash here (" + kRenderSwitches[choice - 3].why_ignored +
             "): choose another configuration";
  return same_configuration_problem(compare_choice_options(left, current), compare_choice_options(right, current));
}

CompareResult run_compare(FramePath& path, const Camera& camera, const RenderOptions& left_options,
                          const RenderOptions& right_options, int rounds, const std::atomic<bool>* cancel,
                          const std::function<void(int done, int total)>& progress) {
  CompareResult r;
  r.left_label = left_options.label();
  r.right_label = right_options.label();
  r.width = camera.width;
  r.height = camera.height;
  r.error = same_configuration_problem(left_options, right_options);
  if (!r.error.empty()) return r;
  rounds = std::max(rounds, 1);
  try {
    const RenderOptions left = untracked(left_options), right = untracked(right_options);
    const int total = 2 * (rounds + 1);
    int done = 0;
    std::vector<double> left_ms, right_ms, left_wall, right_wall, ratios;
    // One render of a side, unless cancelled before it or during it; false when stopped.
    auto render = [&](bool left_side, std::vector<double>* ms, std::vector<double>* wall) {
      if (cancel && cancel->load()) return false;
      FrameStats stats;
      const auto t0 = std::chrono::steady_clock::now();
      path.render_image(camera, left_side ? left : right, left_side ? r.left_image : r.right_image, &stats, cancel);
      const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (stats.cancelled) return false;
      (left_side ? r.left_kv : r.right_kv) = stats.kv_pairs;
      if (ms) ms->push_back(stats.times.total_ms);
      if (wall) wall->push_back(wall_ms);
      if (progress) progress(++done, total);
      return true;
    };
    auto stopped = [&] {
      r.error = kCompareCancelled;
      r.left_image = r.right_image = Image{};
      return r;
    };
    if (!render(false, nullptr, nullptr) || !render(true, nullptr, nullptr)) return stopped();  // warm-up
    for (int round = 0; round < rounds; ++round) {
      const bool left_first = round % 2 == 1;  // right, left; then left, right; ...
      if (!render(left_first, left_first ? &left_ms : &right_ms, left_first ? &left_wall : &right_wall) ||
          !render(!left_first, left_first ? &right_ms : &left_ms, left_first ? &right_wall : &left_wall))
        return stopped();
      if (right_ms.back() > 0) ratios.push_back(left_ms.back() / right_ms.back());
    }
    r.left_ms = spread_of(left_ms);
    r.right_ms = spread_of(right_ms);
    r.left_wall_ms = spread_of(left_wall);
    r.right_wall_ms = spread_of(right_wall);
    r.speed_up = spread_of(ratios);
    r.difference = compare_images(r.right_image, r.left_image);
    r.valid = true;
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

}  // namespace flashgs::viewer
