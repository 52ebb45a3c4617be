// RenderOptions: the one struct that the CLI flags, the viewer's toggles and the sweeps drive,
// and kRenderSwitches, the one table of its optimisation switches they are all derived from.
#pragma once

#include <string>
#include <vector>

#include "flashgs/splat_kernel.h"

namespace flashgs {

enum class Algorithm { baseline, flash };

// The backends, as bits of RenderSwitch::backends.
enum class Backend : unsigned { cpu = 1u << 0, cuda = 1u << 1 };

// The blend's alpha cut of 3DGS: with tau at it the flash path removes only work that
// contributes nothing (options.cpp checks it against gaussian_math.h's kAlphaMin).
constexpr float kDefaultTau = 1.0f / 255.0f;

struct RenderOptions {
  Algorithm algorithm = Algorithm::flash;

  // The optimisation switches, each described in kRenderSwitches below; all on by default,
  // all off (and ignored) for the baseline.
  bool opacity_aware_radius = true;
  bool tight_bbox = true;
  bool exact_tile_test = true;
  bool warp_cooperative_emit = true;
  bool fused_emit = true;
  bool minimal_sort_bits = true;
  bool macro_bins = true;
  bool dense_tiles_first = true;
  bool pipelined_blend = true;
  bool exp2_alpha = true;

  // The footprint model: not an optimisation but part of the image (the scene's trained kernel
  // by default where the CLI and the viewer set it; classic here). Both algorithms honour it.
  SplatKernel kernel;
  float tau = kDefaultTau;    // alpha below which a Gaussian contributes nothing
  float background[3] = {0.0f, 0.0f, 0.0f};
  int sh_degree_cap = 3;      // use at most this many SH bands (0..3)
  // A precision option, not an exact switch: the scene's SH coefficients (DC and higher bands)
  // are used as IEEE half values (gm::round_to_half), so that the CUDA backend can keep them in
  // half the bytes. Off by default; `flashgs report` shows its error against the fp64 reference.
  bool fp16_sh = false;
  // The same for each Gaussian's rotation, scale and opacity: the CUDA backend keeps them in one
  // 16-byte record instead of 32 bytes of floats. Positions stay floats.
  bool fp16_shape = false;
  // The CUDA flash blend in half2 arithmetic: each Gaussian staged as 20 bytes of halves and
  // each pixel's alpha, transmittance and colour as halves, two pixels per instruction. Only
  // with exp2_alpha (the float expf loop has no half form); the CPU renders the exact image.
  bool fp16_blend = false;
  bool collect_tile_counts = false;  // fill FrameStats::tile_pair_counts
  // Fill FrameStats::pixel_depth and pixel_blended (the debug views) from the walk that makes
  // the colour: on the CPU the scalar blend kernel, on CUDA the per-pixel (3DGS) blend kernel,
  // whatever the algorithm (the image is the same; the frame is slower).
  bool collect_pixel_planes = false;

  // The options of the original 3DGS rasterizer (every switch off).
  static RenderOptions baseline();
  bool is_baseline() const { return algorithm == Algorithm::baseline; }
  // Whether each geometry optimisation is in effect (false for the baseline algorithm).
  bool uses_opacity_radius() const { return !is_baseline() && opacity_aware_radius; }
  bool uses_tight_bbox() const { return !is_baseline() && tight_bbox; }
  bool uses_exact_tile_test() const { return !is_baseline() && exact_tile_test; }
  // A short label such as "flash", "baseline", "flash-no_tight_bbox" or "flash-antialiased".
  std::string label() const;
  // These options as `backend` renders them: each switch it does not honour is back at its
  // default, so that two option sets with the same image on that backend compare equal.
  RenderOptions seen_by(Backend backend) const;
};

// Every field, so the viewer re-renders when anything changes.
bool operator==(const RenderOptions& a, const RenderOptions& b);
inline bool operator!=(const RenderOptions& a, const RenderOptions& b) { return !(a == b); }

// A switch's bool in RenderOptions (an alias: nvcc's host code would otherwise parenthesise
// the declarator, which -Wparentheses flags).
using SwitchMember = bool RenderOptions::*;

// One optimisation switch of RenderOptions. Adding a switch: a bool member above, a row
// below, and the code that implements it; the flags, checkboxes, sweeps and tests follow.
struct RenderSwitch {
  const char* cli_name;      // "opacity-radius": the CLI flag --no-opacity-radius
  const char* label;         // "opacity_radius": label() token (flash-no_opacity_radius), CSV column
  const char* ui_name;       // "Opacity radius": the viewer's checkbox
  SwitchMember member;
  unsigned backends;         // Backend bits: the backends that honour it
  bool changes_pairs;        // changes which Gaussian-tile pairs exist (else only how fast they are made)
  const char* help;          // what it removes, one line
  const char* paper;         // where the FlashGS paper describes it
  const char* why_ignored;   // why a backend that does not honour it has nothing to switch
  constexpr bool honoured_by(Backend b) const { return (backends & static_cast<unsigned>(b)) != 0; }
};

constexpr unsigned kEveryBackend = static_cast<unsigned>(Backend::cpu) | static_cast<unsigned>(Backend::cuda);
constexpr unsigned kCudaOnly = static_cast<unsigned>(Backend::cuda);

inline constexpr RenderSwitch kRenderSwitches[] = {
    {"opacity-radius", "opacity_radius", "Opacity radius", &RenderOptions::opacity_aware_radius, kEveryBackend, true,
     "extent sqrt(2 ln(opacity / tau)) instead of 3 sigma: no tiles where alpha stays below tau",
     "section 4, precise intersection (opacity-aware extent)", ""},
    {"tight-bbox", "tight_bbox", "Tight box", &RenderOptions::tight_bbox, kEveryBackend, true,
     "per-axis box of the ellipse instead of a square: no tiles in the square's empty corners",
     "section 4, precise intersection (tight bounding box)", ""},
    {"exact-tile-test", "exact_tile_test", "Exact tile test", &RenderOptions::exact_tile_test, kEveryBackend, true,
     "keys only for the tiles the ellipse touches, not for every tile of its box",
     "section 4, precise intersection (ellipse-tile test)", ""},
    {"warp-emit", "warp_emit", "Warp emit", &RenderOptions::warp_cooperative_emit, kCudaOnly, false,
     "a warp shares the tile tests of a large Gaussian: no thread left looping over a big box alone",
     "section 4.3, adaptive size-aware scheduling", "the CPU backend has no warps"},
    {"fused-emit", "fused_emit", "Fused emit", &RenderOptions::fused_emit, kCudaOnly, false,
     "keys emitted inside the preprocess kernel: no separate emit pass re-reading every Gaussian",
     "section 4, preprocess and key emission in one kernel", "the CPU backend emits keys in a stage of its own"},
    {"sort-bits", "sort_bits", "Sort bits", &RenderOptions::minimal_sort_bits, kCudaOnly, false,
     "radix sort over only the key bits the frame needs instead of all 64",
     "section 4, sort of the Gaussian-tile keys", "the CPU backend counting-sorts by tile, not by key bits"},
    {"macro-bins", "macro_bins", "Macro bins", &RenderOptions::macro_bins, kCudaOnly, false,
     "keys per 32x32-pixel bin carrying the bin's touched tiles: about half the pairs to sort",
     "not in it: HiGS-style macro-tile binning, blended per tile", "the CPU backend sorts each tile's list on its own"},
    {"dense-tiles-first", "dense_tiles_first", "Dense tiles first", &RenderOptions::dense_tiles_first, kCudaOnly,
     false, "the blend takes tiles fullest first: no dense tile starting last and setting the frame's length",
     "not in it: our order of the blend's tiles", "the CPU backend schedules its tiles dynamically"},
    {"pipelined-blend", "pipelined_blend", "Pipelined blend", &RenderOptions::pipelined_blend, kCudaOnly, false,
     "the render loop prefetches the next Gaussians: no stall on each load",
     "section 4, multi-stage pipelining of the render loop", "the CPU backend has no prefetch stage"},
    {"exp2-alpha", "exp2_alpha", "exp2 alpha", &RenderOptions::exp2_alpha, kCudaOnly, false,
     "alpha = o * exp2 of a pre-scaled quadratic form: no expf and its scaling per pixel",
     "section 4, instruction-level optimisation of the render loop", "the CPU backend computes alpha with expf"},
};

// baseline, flash, then flash with each switch of kRenderSwitches off, in table order: the
// configurations `flashgs bench` times and the CUDA tests compare.
std::vector<RenderOptions> single_switch_configs();
// flash with the precision options that store the scene in fewer bytes: fp16_sh, fp16_shape,
// then both (the whole fp16 storage).
std::vector<RenderOptions> fp16_configs();
// flash with the half blend (fp16_blend), alone and with the whole fp16 storage: CUDA only.
std::vector<RenderOptions> fp16_blend_configs();

const char* algorithm_name(Algorithm a);
const char* backend_name(Backend b);

}  // namespace flashgs
