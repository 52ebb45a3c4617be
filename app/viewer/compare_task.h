// CompareTask: one comparison (compare_mode.h's renders and the difference image) run beside the frame loop, so the window keeps answering while a slow backend renders it.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <vector>

#include "background_job.h"
#include "compare_mode.h"
#include "frame_path.h"

namespace flashgs::viewer {

struct CompareJob {
  Camera camera;
  RenderOptions left, right;
  int rounds = kCompareRounds;  // see run_compare
};

struct CompareOutcome {
  CompareResult result;        // error kCompareCancelled when cancel() came first
  float difference_factor = 1.0f;  // difference_image(right, left)'s magnification
  // When the result is valid: left, right and the difference image as texture bytes
  // (to_rgba8), converted on the task's thread; result.width x result.height each.
  std::vector<std::uint8_t> left_rgba, right_rgba, difference_rgba;
  double elapsed_ms = 0;       // from start() to the end of the difference image
  bool cancelled() const { return result.error == kCompareCancelled; }
};

class CompareTask {
 public:
  // `on_done` runs on the task's thread when a comparison ends (the viewer wakes its event
  // loop with it); it must not call back into the task.
  explicit CompareTask(std::function<void()> on_done = {});
  // A comparison still running is cancelled and its thread waited for (by m_job's destructor).
  CompareTask(const CompareTask&) = delete;
  CompareTask& operator=(const CompareTask&) = delete;

  // Starts comparing `job` through `path`, which must outlive it (wait() before it goes). On
  // a path that renders_in_background() (its render_image is thread-safe) on a thread of its
  // own; on the others here, before returning (a GPU frame takes milliseconds). False, and
  // nothing started, while another comparison runs or waits to be taken.
  bool start(FramePath& path, const CompareJob& job);
  // Started and not yet taken.
  bool busy() const;
  // Seconds since the comparison started (0 when none is busy).
  double elapsed_seconds() const;
  // Renders done and to do of the comparison that runs (run_compare's progress).
  int renders_done() const { return m_renders_done.load(); }
  int renders_total() const { return m_renders_total.load(); }
  // The finished comparison, once; false while it runs or when none was started.
  bool take(CompareOutcome* out);
  // Stops the renders where the path can (the CPU backend between stages and tiles); it then
  // ends soon, as cancelled, and is taken like any other. Nothing when none runs.
  void cancel();
  // Blocks until the comparison's thread has ended (scripted runs; before the path goes away).
  void wait();

 private:
  // The comparison itself, on the job's thread (or the caller's).
  void run(FramePath& path, const CompareJob& job, const std::atomic<bool>& cancel);

  mutable std::mutex m_mutex;  // guards the two below
  CompareOutcome m_outcome;
  std::chrono::steady_clock::time_point m_started;
  std::atomic<int> m_renders_done{0}, m_renders_total{0};
  BackgroundJob m_job;  // last: its destructor stops the thread before the members above go
};

}  // namespace flashgs::viewer
