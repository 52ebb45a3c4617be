// Frame-time ring buffers and the frame-time summary of scripted runs.
#include "stats_history.h"

#include <algorithm>
#include <numeric>

#include "flashgs/percentile.h"

namespace flashgs::viewer {

void StatsHistory::push(double frame_ms, const FrameStats& stats) {
  const double values[kSeriesCount] = {frame_ms,            stats.times.total_ms, stats.times.project_ms,
                                       stats.times.emit_ms, stats.times.sort_ms,  stats.times.ranges_ms,
                                       stats.times.blend_ms};
  for (int s = 0; s < kSeriesCount; ++s) m_values[s][m_next] = static_cast<float>(values[s]);
  m_next = (m_next + 1) % kLength;
  m_count = std::min(m_count + 1, kLength);
}

const float* StatsHistory::series(Series s, int* count, int* offset) const {
  *count = m_count;
  *offset = m_count < kLength ? 0 : m_next;
  return m_values[s].data();
}

double StatsHistory::mean(Series s) const {
  if (m_count == 0) return 0;
  double sum = 0;
  for (int i = 0; i < m_count; ++i) sum += m_values[s][i];
  return sum / m_count;
}

double StatsHistory::max(Series s) const {
  float m = 0;
  for (int i = 0; i < m_count; ++i) m = std::max(m, m_values[s][i]);
  return m;
}

const char* StatsHistory::name(Series s) {
  static const char* names[kSeriesCount] = {"frame", "render", "project", "emit", "sort", "ranges", "blend"};
  return names[s];
}

FrameTimeSummary summarize_frame_times(std::vector<double> ms) {
  FrameTimeSummary r;
  r.frames = ms.size();
  if (ms.empty()) return r;
  std::sort(ms.begin(), ms.end());
  r.mean_ms = std::accumulate(ms.begin(), ms.end(), 0.0) / ms.size();
  r.median_ms = median(ms);
  r.p95_ms = percentile(ms, kTailPercentile);
  r.min_ms = ms.front();
  r.max_ms = ms.back();
  r.fps = r.mean_ms > 0 ? 1000.0 / r.mean_ms : 0;
  return r;
}

}  // namespace flashgs::viewer
