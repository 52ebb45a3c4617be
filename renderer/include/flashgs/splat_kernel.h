// SplatKernel: the screen-space footprint model a scene is drawn with (3DGS's classic kernel, or
// the anti-aliased one of gsplat and Mip-Splatting), its names, and the text form users type.
#pragma once

#include <string>

namespace flashgs {

enum class KernelMode { classic, antialiased };

// 3DGS's dilation: px^2 added to the 2D covariance diagonal, opacity unchanged.
constexpr float kClassicDilation = 0.3f;
// The anti-aliased kernel adds epsilon and scales opacity by sqrt(det S / det(S + eps I)):
// gsplat's rasterize_mode="antialiased" uses eps2d = 0.3, Mip-Splatting's 2D mip filter 0.1.
constexpr float kGsplatAntialiasEpsilon = 0.3f;
constexpr float kMipSplattingEpsilon = 0.1f;
// Beyond this a "filter" would blur a Gaussian by more than a few pixels: a typo, not a kernel.
// (The CUDA chunk cull's margin grows with it.)
constexpr float kMaxAntialiasEpsilon = 16.0f;

struct SplatKernel {
  KernelMode mode = KernelMode::classic;
  float epsilon = kClassicDilation;  // px^2 added to the 2D covariance diagonal

  static SplatKernel classic() { return {}; }
  static SplatKernel antialiased(float epsilon = kGsplatAntialiasEpsilon) { return {KernelMode::antialiased, epsilon}; }
  bool compensates_opacity() const { return mode == KernelMode::antialiased; }
  // What the footprint adds: 3DGS's 0.3 for classic whatever `epsilon` holds (classic kernels
  // compare equal), the epsilon for the anti-aliased one.
  float dilation() const { return compensates_opacity() ? epsilon : kClassicDilation; }
  // "classic", "antialiased" (eps 0.3) or "antialiased=0.1": what parse_splat_kernel reads back.
  std::string spec() const;
  // spec() for messages and the UI: "antialiased (eps 0.1)".
  std::string description() const;
};

// The kernels trainers use: classic, gsplat's anti-aliased (eps 0.3), Mip-Splatting's (eps 0.1).
// The viewer offers these, the report sweeps them.
inline constexpr SplatKernel kTrainerKernels[] = {
    {KernelMode::classic, kClassicDilation},
    {KernelMode::antialiased, kGsplatAntialiasEpsilon},
    {KernelMode::antialiased, kMipSplattingEpsilon},
};

bool operator==(const SplatKernel& a, const SplatKernel& b);
inline bool operator!=(const SplatKernel& a, const SplatKernel& b) { return !(a == b); }

// The trainer kernel after `k` in kTrainerKernels, round (the first for any other kernel).
SplatKernel next_trainer_kernel(const SplatKernel& k);

// Reads "classic", "antialiased" or "antialiased=EPS" (0 < EPS <= kMaxAntialiasEpsilon);
// throws flashgs::Error starting with `what` (the option or field) otherwise.
SplatKernel parse_splat_kernel(const std::string& text, const std::string& what);

// The kernel a scene was trained with, as its file says, and which mark said so ("SPZ header
// flag antialiased", ...). No mark: classic, with an empty source.
struct TrainedKernel {
  SplatKernel kernel;
  std::string source;
  bool marked() const { return !source.empty(); }
};

}  // namespace flashgs
