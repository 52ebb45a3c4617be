// RenderOptions: the one struct that the CLI flags, the viewer's toggles and the sweeps drive.
#pragma once

#include <string>

namespace flashgs {

enum class Algorithm { baseline, flash };

struct RenderOptions {
  Algorithm algorithm = Algorithm::flash;

  // FlashGS geometry optimisations (section 4 of the paper); ignored by the baseline.
  bool opacity_aware_radius = true;  // extent sqrt(2 ln(opacity / tau)) instead of 3 sigma
  bool tight_bbox = true;            // per-axis box of the ellipse instead of a square
  bool exact_tile_test = true;       // keep only tiles the ellipse really touches

  // FlashGS scheduling / kernel optimisations. The CPU backend has no warps or prefetch
  // and ignores them; the CUDA backend switches each one live.
  bool warp_cooperative_emit = true;  // a warp shares the tile tests of a large Gaussian
  bool fused_emit = true;             // emit keys inside the preprocess kernel
  bool minimal_sort_bits = true;      // radix-sort only the key bits the frame needs
  bool pipelined_blend = true;        // prefetch the next Gaussians in the render loop
  bool exp2_alpha = true;             // alpha = o * exp2(pre-scaled quadratic form)

  float tau = 1.0f / 255.0f;  // alpha below which a Gaussian contributes nothing
  float background[3] = {0.0f, 0.0f, 0.0f};
  int sh_degree_cap = 3;      // use at most this many SH bands (0..3)
  bool collect_tile_counts = false;  // fill FrameStats::tile_pair_counts

  // The options of the original 3DGS rasterizer.
  static RenderOptions baseline();
  bool is_baseline() const { return algorithm == Algorithm::baseline; }
  // Whether each geometry optimisation is in effect (false for the baseline algorithm).
  bool uses_opacity_radius() const { return !is_baseline() && opacity_aware_radius; }
  bool uses_tight_bbox() const { return !is_baseline() && tight_bbox; }
  bool uses_exact_tile_test() const { return !is_baseline() && exact_tile_test; }
  // A short label such as "flash", "baseline" or "flash-no_tight_bbox".
  std::string label() const;
};

const char* algorithm_name(Algorithm a);

}  // namespace flashgs
