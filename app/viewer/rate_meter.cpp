// Events per second from their times within a sliding window.
#include "rate_meter.h"

namespace flashgs::viewer {

void RateMeter::record(double now_s) {
  m_times.push_back(now_s);
  while (!m_times.empty() && m_times.front() < now_s - kWindowSeconds) m_times.pop_front();
}

double RateMeter::rate(double now_s) const {
  int count = 0;
  double oldest = now_s;
  for (double t : m_times)
    if (t >= now_s - kWindowSeconds) {
      if (count == 0) oldest = t;
      ++count;
    }
  if (count == 0) return 0.0;
  // Over the span the events cover (a burst that just started is not averaged over a full
  // second), at least one frame's gap so that a single event is not infinite.
  if (count == 1) return 1.0 / kWindowSeconds;
  return (count - 1) / (m_times.back() - oldest);
}

}  // namespace flashgs::viewer
