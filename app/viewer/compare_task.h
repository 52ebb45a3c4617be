// CompareTask: one comparison (compare_mode.h's renders and the difference image) run beside the frame loop, so the window keeps answering while a slow backend renders it.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "compare_mode.h"
#include "frame_path.h"

namespace flashgs::viewer {

struct CompareJob {
  Camera camera;
  RenderOptions left, right;
  bool warm_up = true;  // see run_compare
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
  // Cancels a comparison still running and waits for its thread.
  ~CompareTask();
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
  // The finished comparison, once; false while it runs or when none was started.
  bool take(CompareOutcome* out);
  // Stops the renders where the path can (the CPU backend between stages and tiles); it then
  // ends soon, as cancelled, and is taken like any other. Nothing when none runs.
  void cancel();
  // Blocks until the comparison's thread has ended (scripted runs; before the path goes away).
  void wait();

 private:
  void run(FramePath& path, const CompareJob& job);  // the comparison itself, on any thread

  std::function<void()> m_on_done;
  mutable std::mutex m_mutex;  // guards everything up to m_cancel
  bool m_busy = false;  // started, not yet taken
  bool m_done = false;  // m_outcome is there to take
  CompareOutcome m_outcome;
  std::chrono::steady_clock::time_point m_started;
  std::atomic<bool> m_cancel{false};
  std::thread m_thread;  // UI thread only (start, wait, the destructor)
};

}  // namespace flashgs::viewer
