// The streamed bytes per second: one sample per half second, the last kLength kept.
#include "read_rate_history.h"

namespace flashgs::viewer {

void ReadRateHistory::observe(double now_s, std::uint64_t bytes_read) {
  if (!m_started || bytes_read < m_last_bytes) {  // the first look, or a new stream counting from 0
    m_started = true;
    m_last_s = now_s;
    m_last_bytes = bytes_read;
    return;
  }
  const double elapsed = now_s - m_last_s;
  if (elapsed < kSampleSeconds) return;
  m_rates.push_back(static_cast<float>(static_cast<double>(bytes_read - m_last_bytes) / elapsed));
  if (static_cast<int>(m_rates.size()) > kLength) m_rates.erase(m_rates.begin());
  m_last_s = now_s;
  m_last_bytes = bytes_read;
}

void ReadRateHistory::clear() { *this = ReadRateHistory{}; }

}  // namespace flashgs::viewer
