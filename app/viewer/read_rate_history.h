// ReadRateHistory: the bytes a streamed LOD set read per second, sampled over the last half
// minute, for the Scene panel's graph.
#pragma once

#include <cstdint>
#include <vector>

namespace flashgs::viewer {

class ReadRateHistory {
 public:
  static constexpr double kSampleSeconds = 0.5;
  static constexpr int kLength = 60;  // samples kept: thirty seconds
  // The stream's total bytes read so far, at `now_s` (seconds on a steady clock): a sample is
  // taken once kSampleSeconds have passed since the last one.
  void observe(double now_s, std::uint64_t bytes_read);
  // Bytes per second, oldest first.
  const std::vector<float>& rates() const { return m_rates; }
  float latest() const { return m_rates.empty() ? 0.0f : m_rates.back(); }
  void clear();

 private:
  std::vector<float> m_rates;
  bool m_started = false;
  double m_last_s = 0;
  std::uint64_t m_last_bytes = 0;
};

}  // namespace flashgs::viewer
