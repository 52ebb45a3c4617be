// FrameStats: what one rendered frame cost and what it did, per stage.
#pragma once

#include <cstdint>
#include <vector>

namespace flashgs {

// Milliseconds per stage; stage names are the same on every backend.
struct StageTimes {
  double project_ms = 0;  // cull, 3D->2D covariance, extent, box, SH -> colour
  double emit_ms = 0;     // Gaussian-tile keys
  double sort_ms = 0;     // by tile, then depth (CPU: the depth order before emit, the pairs placed by tile after)
  double ranges_ms = 0;   // per-tile start/end in the sorted list (CUDA bin sort: in sort_ms, 0 here)
  double blend_ms = 0;    // front-to-back compositing
  double total_ms = 0;
  // CUDA bin-sort frames whose blend ran beside the sort's per-bin blocks: those blocks' time
  // is in blend_ms (the two cannot be timed apart), sort_ms is the counting and scatter passes.
  bool sort_in_blend = false;
};

// What blend_ms holds beside the blend, to print next to it ("" when nothing).
inline const char* blend_time_note(const StageTimes& t) {
  return t.sort_in_blend ? "blend includes the bin sort's per-bin blocks, which ran beside it" : "";
}

struct FrameStats {
  std::uint64_t kv_pairs = 0;  // Gaussian-tile pairs emitted this frame
  // Pairs the sort ordered: kv_pairs, or with CUDA macro bins (RenderOptions::macro_bins) one
  // per Gaussian and 2x2-tile bin it touches.
  std::uint64_t sorted_pairs = 0;
  int tiles_x = 0, tiles_y = 0;
  // Pairs per tile, row-major tiles_y x tiles_x; filled only when
  // RenderOptions::collect_tile_counts is set.
  std::vector<std::uint32_t> tile_pair_counts;
  std::uint32_t max_tile_pairs = 0;
  // Per pixel, row-major width x height, filled only when RenderOptions::collect_pixel_planes
  // is set: the alpha-weighted mean view depth of the Gaussians blended there,
  // sum(w_i z_i) / sum(w_i) with w_i = alpha_i T_i (NaN where none was), and how many were
  // blended (alpha >= 1/255 before the pixel's transmittance stopped it).
  std::vector<float> pixel_depth;
  std::vector<std::uint32_t> pixel_blended;

  std::uint64_t gaussians = 0;          // in the scene
  std::uint64_t visible = 0;            // emitted at least one pair
  std::uint64_t culled_near = 0;        // view-space z <= 0.2 (behind or straddling the near plane)
  std::uint64_t culled_offscreen = 0;   // box misses the image
  std::uint64_t culled_low_opacity = 0; // opacity below tau (flash opacity-aware radius only)
  std::uint64_t culled_degenerate = 0;  // non-finite projection or empty covariance
  // CUDA flash: Gaussians of 256-Gaussian chunks that lay wholly outside the view, classified
  // from their centres without being projected (also counted in the culled_* above).
  std::uint64_t culled_by_chunk = 0;

  StageTimes times;
  std::uint64_t device_memory_bytes = 0;  // backend working memory now (GPU; 0 on CPU)
  std::uint64_t device_peak_bytes = 0;    // high-water mark of the above
  std::uint64_t scene_device_bytes = 0;   // the scene as the backend holds it (GPU; 0 on CPU)
  // The render stopped early on Renderer::set_cancel_flag's flag: the image is incomplete.
  bool cancelled = false;
};

}  // namespace flashgs
