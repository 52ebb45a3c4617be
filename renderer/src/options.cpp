// RenderOptions presets and labels.
#include "flashgs/options.h"

namespace flashgs {

RenderOptions RenderOptions::baseline() {
  RenderOptions options;
  options.algorithm = Algorithm::baseline;
  options.opacity_aware_radius = options.tight_bbox = options.exact_tile_test = false;
  options.warp_cooperative_emit = options.fused_emit = options.minimal_sort_bits = false;
  options.pipelined_blend = options.exp2_alpha = false;
  return options;
}

std::string RenderOptions::label() const {
  if (is_baseline()) return "baseline";
  std::string label = "flash";
  const std::pair<bool, const char*> switches[] = {
      {opacity_aware_radius, "opacity_radius"}, {tight_bbox, "tight_bbox"},
      {exact_tile_test, "exact_tile_test"},     {warp_cooperative_emit, "warp_emit"},
      {fused_emit, "fused_emit"},               {minimal_sort_bits, "sort_bits"},
      {pipelined_blend, "pipelined_blend"},     {exp2_alpha, "exp2_alpha"}};
  for (const auto& [on, name] : switches)
    if (!on) label += std::string("-no_") + name;
  return label;
}

const char* algorithm_name(Algorithm a) { return a == Algorithm::baseline ? "baseline" : "flash"; }

}  // namespace flashgs
