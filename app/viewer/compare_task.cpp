// The comparison's task: run_compare and the difference image as a BackgroundJob (on a thread of its own, or at once on a path that renders in the caller's thread), the outcome taken by the frame loop.
#include "compare_task.h"

#include "rgba8_image.h"
#include "split_view.h"

namespace flashgs::viewer {

using Clock = std::chrono::steady_clock;

CompareTask::CompareTask(std::function<void()> on_done) : m_job(std::move(on_done)) {}

bool CompareTask::start(FramePath& path, const CompareJob& job) {
  if (m_job.busy()) return false;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_outcome = CompareOutcome{};
    m_started = Clock::now();
  }
  m_renders_done = 0;
  m_renders_total = 2 * (job.rounds + 1);
  return m_job.start(path.renders_in_background(), [this, &path, job](const std::atomic<bool>& cancel) {
    run(path, job, cancel);
    return std::string();
  });
}

void CompareTask::run(FramePath& path, const CompareJob& job, const std::atomic<bool>& cancel) {
  CompareOutcome outcome;
  outcome.result = run_compare(path, job.camera, job.left, job.right, job.rounds, &cancel,
                               [this](int done, int total) {
                                 m_renders_done = done;
                                 m_renders_total = total;
                               });
  if (outcome.result.valid && !cancel) {
    const CompareResult& r = outcome.result;
    to_rgba8(r.left_image, outcome.left_rgba);
    to_rgba8(r.right_image, outcome.right_rgba);
    to_rgba8(difference_image(r.right_image, r.left_image, &outcome.difference_factor), outcome.difference_rgba);
  }
  std::lock_guard<std::mutex> lock(m_mutex);
  outcome.elapsed_ms = std::chrono::duration<double, std::milli>(Clock::now() - m_started).count();
  m_outcome = std::move(outcome);
}

bool CompareTask::busy() const { return m_job.busy(); }

double CompareTask::elapsed_seconds() const {
  if (!m_job.busy()) return 0.0;
  std::lock_guard<std::mutex> lock(m_mutex);
  return std::chrono::duration<double>(Clock::now() - m_started).count();
}

bool CompareTask::take(CompareOutcome* out) {
  const bool cancelled = m_job.cancel_requested();  // before take(): it ends the job's turn
  std::string error;
  if (!m_job.take(&error)) return false;
  std::lock_guard<std::mutex> lock(m_mutex);
  *out = std::move(m_outcome);
  m_outcome = CompareOutcome{};
  if (!error.empty()) {  // the job threw (out of memory converting the images)
    out->result.valid = false;
    out->result.error = error;
  }
  if (cancelled) {  // cancelled after the renders ended: dropped all the same
    out->result.valid = false;
    out->result.error = kCompareCancelled;
    out->left_rgba.clear();
    out->right_rgba.clear();
    out->difference_rgba.clear();
  }
  return true;
}

void CompareTask::cancel() { m_job.cancel(); }

void CompareTask::wait() { m_job.wait(); }

}  // namespace flashgs::viewer
