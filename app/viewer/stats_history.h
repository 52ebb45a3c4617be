// StatsHistory: short ring buffers of per-frame times for the stats panel's plots and the scripted report.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "flashgs/stats.h"

namespace flashgs::viewer {

class StatsHistory {
 public:
  static constexpr int kLength = 240;  // about four seconds at 60 FPS
  enum Series { kFrame, kRender, kProject, kEmit, kSort, kRanges, kBlend, kSeriesCount };

  void push(double frame_ms, const FrameStats& stats);
  // Oldest first, for ImGui::PlotLines.
  const float* series(Series s, int* count, int* offset) const;
  double mean(Series s) const;
  double max(Series s) const;
  static const char* name(Series s);

 private:
  std::array<std::array<float, kLength>, kSeriesCount> m_values{};
  int m_next = 0;
  int m_count = 0;
};

// Summary of a list of frame times (the scripted run's report).
struct FrameTimeSummary {
  std::size_t frames = 0;
  double mean_ms = 0, median_ms = 0, p95_ms = 0, min_ms = 0, max_ms = 0, fps = 0;
};
FrameTimeSummary summarize_frame_times(std::vector<double> ms);

}  // namespace flashgs::viewer
