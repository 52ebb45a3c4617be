// The comparison's task: run_compare and the difference image on a thread of their own (or at once on a path that renders in the caller's thread), the outcome taken by the frame loop.
#include "compare_task.h"

#include "render_worker.h"
#include "rgba8_image.h"
#include "split_view.h"

namespace flashgs::viewer {

using Clock = std::chrono::steady_clock;

CompareTask::CompareTask(std::function<void()> on_done) : m_on_done(std::move(on_done)) {}

CompareTask::~CompareTask() {
  cancel();
  wait();
}

bool CompareTask::start(FramePath& path, const CompareJob& job) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    if (m_busy) return false;
    m_busy = true;
    m_done = false;
    m_started = Clock::now();
  }
  wait();  // the last comparison's thread, finished (it was taken)
  m_cancel = false;
  if (path.renders_in_background())
    m_thread = std::thread([this, &path, job] {
      lower_this_thread_priority();  // its renders run here, as the worker's do on its thread
      run(path, job);
    });
  else run(path, job);
  return true;
}

void CompareTask::run(FramePath& path, const CompareJob& job) {
  CompareOutcome outcome;
  outcome.result = run_compare(path, job.camera, job.left, job.right, job.warm_up, &m_cancel);
  if (outcome.result.valid && !m_cancel) {
    const CompareResult& r = outcome.result;
    to_rgba8(r.left_image, outcome.left_rgba);
    to_rgba8(r.right_image, outcome.right_rgba);
    to_rgba8(difference_image(r.right_image, r.left_image, &outcome.difference_factor), outcome.difference_rgba);
  }
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    outcome.elapsed_ms = std::chrono::duration<double, std::milli>(Clock::now() - m_started).count();
    m_outcome = std::move(outcome);
    m_done = true;
  }
  if (m_on_done) m_on_done();
}

bool CompareTask::busy() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_busy;
}

double CompareTask::elapsed_seconds() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_busy ? std::chrono::duration<double>(Clock::now() - m_started).count() : 0.0;
}

bool CompareTask::take(CompareOutcome* out) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_done) return false;
  *out = std::move(m_outcome);
  m_outcome = CompareOutcome{};
  if (m_cancel) {  // cancelled after the renders ended: dropped all the same
    out->result.valid = false;
    out->result.error = kCompareCancelled;
    out->left_rgba.clear();
    out->right_rgba.clear();
    out->difference_rgba.clear();
  }
  m_done = false;
  m_busy = false;
  return true;
}

void CompareTask::cancel() {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_busy) m_cancel = true;
}

void CompareTask::wait() {
  if (m_thread.joinable()) m_thread.join();
}

}  // namespace flashgs::viewer
