// BackgroundJob: one job at a time beside the frame loop (a path export's frame: render and write), on a thread of its own where the frame path renders in the background, its outcome polled by the frame loop.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace flashgs::viewer {

class BackgroundJob {
 public:
  // A job gets the cancel flag to pass on to its renders and returns an error message, or
  // an empty string when it succeeded; an exception it throws becomes its message.
  using Job = std::function<std::string(const std::atomic<bool>& cancel)>;

  // `on_done` runs on the job's thread when a job ends (the viewer wakes its event loop with
  // it); it must not call back into this object.
  explicit BackgroundJob(std::function<void()> on_done = {});
  // Cancels a job still running and waits for its thread.
  ~BackgroundJob();
  BackgroundJob(const BackgroundJob&) = delete;
  BackgroundJob& operator=(const BackgroundJob&) = delete;

  // Starts `job`: on a thread of its own with `on_thread`, else before returning. False, and
  // nothing started, while another job runs or waits to be taken.
  bool start(bool on_thread, Job job);
  // Started and not yet taken.
  bool busy() const;
  // The finished job's outcome, once (its message, empty for success); false while it runs
  // or when none was started.
  bool take(std::string* error);
  // Raises the running job's cancel flag; it ends as soon as its renders stop.
  void cancel();
  // cancel() was called since this job started (it may have ended all the same).
  bool cancel_requested() const { return m_cancel; }
  // Blocks until the job's thread has ended (before what it uses goes away).
  void wait();

 private:
  void run(const Job& job);

  std::function<void()> m_on_done;
  mutable std::mutex m_mutex;  // guards the three below
  bool m_busy = false;  // started, not yet taken
  bool m_done = false;  // m_error is there to take
  std::string m_error;
  std::atomic<bool> m_cancel{false};
  std::thread m_thread;  // the owner's thread only (start, wait, the destructor)
};

}  // namespace flashgs::viewer
