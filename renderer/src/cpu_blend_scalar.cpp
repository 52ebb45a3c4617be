// CPU blend, scalar reference kernel: front-to-back alpha compositing of one tile's sorted
// Gaussians, one pixel at a time. The SIMD kernel (cpu_blend_simd.cpp) is tested against it.
#include <algorithm>
#include <cmath>

#include "cpu_frame.h"

namespace flashgs {
namespace cpu {
namespace {

constexpr int kTilePixels = gm::kTileSize * gm::kTileSize;

}  // namespace

// Composites one tile. Gaussian-outer, pixel-inner: each Gaussian is read once per tile and
// the pixel loop runs over contiguous arrays. Per pixel the rules are those of 3DGS:
// alpha = min(0.99, o e^power), skip alpha < 1/255, stop before T < 1e-4. With `planes` each
// pixel also sums its blend weights and weighted depths and counts its Gaussians.
void blend_tile_scalar(const Frame& frame, const TileJob& tile, float* rgb, const PixelPlanes* planes) {
  const std::uint32_t* ids = tile.ids;
  const std::uint64_t count = tile.count;
  const float* background = tile.background;
  const int tile_x = tile.tile_x, tile_y = tile.tile_y;
  const int width = frame.camera.width, height = frame.camera.height;
  const int x_begin = tile_x * gm::kTileSize, y_begin = tile_y * gm::kTileSize;
  const int tile_w = std::min(gm::kTileSize, width - x_begin);
  const int tile_h = std::min(gm::kTileSize, height - y_begin);
  float transmittance[kTilePixels];
  float color[kTilePixels][3];
  bool active[kTilePixels];
  float weight_sum[kTilePixels], weighted_depth[kTilePixels];
  std::uint32_t blended[kTilePixels];
  int active_count = tile_w * tile_h;
  for (int p = 0; p < kTilePixels; ++p) {
    transmittance[p] = 1.0f;
    color[p][0] = color[p][1] = color[p][2] = 0.0f;
    active[p] = true;
    weight_sum[p] = weighted_depth[p] = 0.0f;
    blended[p] = 0;
  }
  for (std::uint64_t k = 0; k < count && active_count > 0; ++k) {
    const BlendGaussian& g = frame.blend_data[ids[k]];
    const float depth = planes ? frame.footprints[ids[k]].depth : 0.0f;
    // Only the rows, and in each row the pixels, that can reach power_cut; the margins (0.5
    // in q, one pixel each side) exceed the float rounding of the per-pixel power, so pruning
    // never changes which pixels pass the exact test below.
    const float reach_y = g.row_q_coeff > 0.0f ? std::sqrt((g.q_cut + 0.5f) / g.row_q_coeff) + 1.0f : 1e30f;
    const float local_y = g.mean_y - static_cast<float>(y_begin);
    const float power_cut = -0.5f * g.q_cut;  // exact (cpu_project.cpp)
    const int y_first = static_cast<int>(std::max(0.0f, std::ceil(local_y - reach_y)));
    const int y_last = static_cast<int>(std::min(static_cast<float>(tile_h - 1), std::floor(local_y + reach_y)));
    for (int y = y_first; y <= y_last; ++y) {
      const float dy = static_cast<float>(y_begin + y) - g.mean_y;
      const float row_q = g.row_q_coeff * dy * dy;
      if (!(row_q <= g.q_cut + 0.5f)) continue;
      const float centre = g.mean_x + g.row_slope * dy - static_cast<float>(x_begin);
      const float half = std::sqrt(std::max(0.0f, g.q_cut + 0.5f - row_q) * g.inv_conic_a) + 1.0f;
      const float u_row = g.whiten[1] * dy, v_row = g.whiten[3] * dy;
      const int x0 = static_cast<int>(std::max(0.0f, std::ceil(centre - half)));
      const int x1 = static_cast<int>(std::min(static_cast<float>(tile_w - 1), std::floor(centre + half)));
      for (int x = x0; x <= x1; ++x) {
        const int p = y * gm::kTileSize + x;
        if (!active[p]) continue;
        const float dx = static_cast<float>(x_begin + x) - g.mean_x;
        // Whitened form (gm::Footprint::whiten): q >= 0 by construction and accurate far
        // along a needle, so 3DGS's "skip power > 0" (which only rounding could trigger, on a
        // needle's axis, dropping its most opaque pixels) is gone.
        const float u = g.whiten[0] * dx + u_row, v = g.whiten[2] * dx + v_row;
        const float power = -0.5f * (u * u + v * v);
        if (power < power_cut) continue;
        const float alpha = std::min(gm::kAlphaMax, g.opacity * std::exp(power));
        if (alpha < gm::kAlphaMin) continue;
        const float next_t = transmittance[p] * (1.0f - alpha);
        if (next_t < gm::kTransmittanceMin) {
          active[p] = false;
          --active_count;
          continue;
        }
        const float weight = alpha * transmittance[p];
        color[p][0] += g.rgb[0] * weight;
        color[p][1] += g.rgb[1] * weight;
        color[p][2] += g.rgb[2] * weight;
        transmittance[p] = next_t;
        if (planes) {
          weight_sum[p] += weight;
          weighted_depth[p] += weight * depth;
          ++blended[p];
        }
      }
    }
  }
  for (int y = 0; y < tile_h; ++y)
    for (int x = 0; x < tile_w; ++x) {
      const int p = y * gm::kTileSize + x;
      float* out = rgb + (static_cast<std::size_t>(y_begin + y) * width + x_begin + x) * 3;
      for (int ch = 0; ch < 3; ++ch) out[ch] = color[p][ch] + transmittance[p] * background[ch];
      if (planes) {
        const std::size_t at = static_cast<std::size_t>(y_begin + y) * width + x_begin + x;
        planes->depth[at] = blended[p] > 0 ? weighted_depth[p] / weight_sum[p] : NAN;
        planes->blended[at] = blended[p];
      }
    }
}


}  // namespace cpu
}  // namespace flashgs
