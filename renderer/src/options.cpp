// RenderOptions presets, labels and comparisons, all walked from kRenderSwitches.
#include "flashgs/options.h"

#include <algorithm>

#include "flashgs/gaussian_math.h"

namespace flashgs {

static_assert(kDefaultTau == gm::kAlphaMin, "the default tau is the blend's alpha cut (see options.h)");

RenderOptions RenderOptions::baseline() {
  RenderOptions options;
  options.algorithm = Algorithm::baseline;
  for (const RenderSwitch& s : kRenderSwitches) options.*(s.member) = false;
  return options;
}

std::string RenderOptions::label() const {
  std::string label = is_baseline() ? "baseline" : "flash";
  if (!is_baseline())
    for (const RenderSwitch& s : kRenderSwitches)
      if (!(this->*(s.member))) label += std::string("-no_") + s.label;
  if (kernel.mode != KernelMode::classic) {  // "-antialiased", "-antialiased_0.1": a file-name token
    std::string token = kernel.spec();
    std::replace(token.begin(), token.end(), '=', '_');
    label += "-" + token;
  }
  if (fp16_sh) label += "-fp16_sh";
  if (fp16_shape) label += "-fp16_shape";
  if (fp16_blend) label += "-fp16_blend";
  return label;
}

RenderOptions RenderOptions::seen_by(Backend backend) const {
  RenderOptions seen = *this;
  const RenderOptions defaults = is_baseline() ? RenderOptions::baseline() : RenderOptions{};
  for (const RenderSwitch& s : kRenderSwitches)
    if (!s.honoured_by(backend)) seen.*(s.member) = defaults.*(s.member);
  if (backend == Backend::cpu) seen.fp16_blend = false;
  return seen;
}

bool operator==(const RenderOptions& a, const RenderOptions& b) {
  for (const RenderSwitch& s : kRenderSwitches)
    if (a.*(s.member) != b.*(s.member)) return false;
  return a.algorithm == b.algorithm && a.kernel == b.kernel && a.tau == b.tau && a.sh_degree_cap == b.sh_degree_cap &&
         a.fp16_sh == b.fp16_sh && a.fp16_shape == b.fp16_shape &&
         a.fp16_blend == b.fp16_blend &&
         a.collect_tile_counts == b.collect_tile_counts &&
         a.collect_pixel_planes == b.collect_pixel_planes && std::equal(a.background, a.background + 3, b.background);
}

std::vector<RenderOptions> single_switch_configs() {
  std::vector<RenderOptions> out = {RenderOptions::baseline(), RenderOptions{}};
  for (const RenderSwitch& s : kRenderSwitches) {
    RenderOptions o;
    o.*(s.member) = false;
    out.push_back(o);
  }
  return out;
}

std::vector<RenderOptions> fp16_configs() {
  RenderOptions sh, shape, both;
  sh.fp16_sh = true;
  shape.fp16_shape = true;
  both.fp16_sh = both.fp16_shape = true;
  return {sh, shape, both};
}

std::vector<RenderOptions> fp16_blend_configs() {
  RenderOptions blend, all;
  blend.fp16_blend = true;
  all.fp16_sh = all.fp16_shape = all.fp16_blend = true;
  return {blend, all};
}

const char* algorithm_name(Algorithm a) { return a == Algorithm::baseline ? "baseline" : "flash"; }

const char* backend_name(Backend b) { return b == Backend::cpu ? "CPU" : "CUDA"; }

}  // namespace flashgs
