#include "background_job.h"

#include "render_worker.h"

namespace flashgs::viewer {

BackgroundJob::BackgroundJob(std::function<void()> on_done) : m_on_done(std::move(on_done)) {}

BackgroundJob::~BackgroundJob() {
  cancel();
  wait();
}

bool BackgroundJob::start(bool on_thread, Job job) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    if (m_busy) return false;
    m_busy = true;
    m_done = false;
  }
  wait();  // the last job's thread, finished (it was taken)
  m_cancel = false;
  if (on_thread)
    m_thread = std::thread([this, job = std::move(job)] {
      lower_this_thread_priority();  // its renders run here, as the worker's do on its thread
      run(job);
    });
  else run(job);
  return true;
}

void BackgroundJob::run(const Job& job) {
  std::string error;
  try {
    error = job(m_cancel);
  } catch (const std::exception& e) {
    error = e.what();
    if (error.empty()) error = "failed";
  }
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_error = std::move(error);
    m_done = true;
  }
  if (m_on_done) m_on_done();
}

bool BackgroundJob::busy() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_busy;
}

bool BackgroundJob::take(std::string* error) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_done) return false;
  *error = std::move(m_error);
  m_error.clear();
  m_done = false;
  m_busy = false;
  return true;
}

void BackgroundJob::cancel() {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_busy) m_cancel = true;
}

void BackgroundJob::wait() {
  if (m_thread.joinable()) m_thread.join();
}

}  // namespace flashgs::viewer
