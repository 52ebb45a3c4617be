// Text formatting of FrameStats for the CLI.
#include "stats_format.h"

#include <cstdio>

namespace flashgs::cli {

std::string format_stats(const FrameStats& s) {
  char text[1024];
  std::snprintf(text, sizeof text,
                "kv pairs:   %llu (max %u in one tile, %dx%d tiles; %llu sorted)\n"
                "gaussians:  %llu in scene, %llu visible; culled: %llu near, %llu off screen, "
                "%llu below tau, %llu degenerate\n"
                "time ms:    project %.3f  emit %.3f  sort %.3f  ranges %.3f  blend %.3f  total %.3f\n",
                static_cast<unsigned long long>(s.kv_pairs), s.max_tile_pairs, s.tiles_x, s.tiles_y,
                static_cast<unsigned long long>(s.sorted_pairs), static_cast<unsigned long long>(s.gaussians), static_cast<unsigned long long>(s.visible),
                static_cast<unsigned long long>(s.culled_near), static_cast<unsigned long long>(s.culled_offscreen),
                static_cast<unsigned long long>(s.culled_low_opacity),
                static_cast<unsigned long long>(s.culled_degenerate), s.times.project_ms, s.times.emit_ms,
                s.times.sort_ms, s.times.ranges_ms, s.times.blend_ms, s.times.total_ms);
  std::string out = text;
  if (*blend_time_note(s.times)) out += std::string("            ") + blend_time_note(s.times) + "\n";
  if (s.device_peak_bytes) {
    std::snprintf(text, sizeof text, "device mem: %.1f MB now, %.1f MB peak (above the scene); scene %.1f MB\n",
                  s.device_memory_bytes / 1e6, s.device_peak_bytes / 1e6, s.scene_device_bytes / 1e6);
    out += text;
  }
  return out;
}

}  // namespace flashgs::cli
