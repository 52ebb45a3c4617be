// RateMeter: events per second over the last second (the HUD's rendered frames per second), zero once they stop.
#pragma once

#include <deque>

namespace flashgs::viewer {

class RateMeter {
 public:
  static constexpr double kWindowSeconds = 1.0;
  // One event at `now_s` (seconds on any steady clock).
  void record(double now_s);
  // Events per second over the window ending at `now_s`; 0 when none fell in it.
  double rate(double now_s) const;

 private:
  std::deque<double> m_times;  // inside the window, oldest first
};

}  // namespace flashgs::viewer
