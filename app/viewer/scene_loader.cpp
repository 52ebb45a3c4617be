// Background scene loads on detached threads (the thread and the viewer share the job, so whichever finishes last frees it), and how far one is.
#include "scene_loader.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <new>
#include <thread>

#include "render_gate.h"

namespace flashgs::viewer {

float load_fraction(std::uint64_t bytes_done, std::uint64_t bytes_total, std::uint64_t gaussians_done,
                    std::uint64_t gaussians_total) {
  const auto part = [](std::uint64_t done, std::uint64_t total) {
    return total > 0 ? std::min(1.0, double(done) / double(total)) : -1.0;
  };
  const double read = part(bytes_done, bytes_total), decoded = part(gaussians_done, gaussians_total);
  if (read >= 0 && decoded >= 0) return float(0.5 * read + 0.5 * decoded);
  if (read > 0) return float(read);
  if (decoded > 0) return float(decoded);
  return -1.0f;
}
namespace {

std::atomic<int> g_running{0};

}  // namespace

struct SceneLoader::Job {
  std::mutex mutex;
  bool done = false;
  LoadedScene scene;
  std::string error;
  LoadProgress progress;  // written by the thread (atomics), read by the viewer
  std::atomic<bool> waiting_at_gate{false};
};

SceneLoader::SceneLoader(LoadFunction load) : m_load(std::move(load)) {}

SceneLoader::~SceneLoader() { abandon(); }

int SceneLoader::running() { return g_running.load(); }

bool SceneLoader::start(const std::string& path, LoadFunction load) {
  if (m_job) return false;
  if (!load) load = m_load;
  auto job = std::make_shared<Job>();
  ++g_running;
  try {
    // Detached: a thread blocked in open() cannot be interrupted, and the viewer must be able
    // to close anyway; the job outlives whichever side lets go of it first.
    std::thread([job, load = std::move(load), path, gate = m_gate_file] {
      LoadedScene scene;
      std::string error;
      try {
        if (!gate.empty())
          wait_at_gate(gate, [&job] { return job->progress.cancel_requested.load(); }, job->waiting_at_gate);
        scene = load(path, job->progress);
      } catch (const std::bad_alloc&) {
        error = path + ": out of memory while loading";
      } catch (const std::exception& e) {
        error = e.what();
      }
      {
        std::lock_guard<std::mutex> lock(job->mutex);
        job->scene = std::move(scene);
        job->error = std::move(error);
        job->done = true;
      }
      --g_running;
    }).detach();
  } catch (const std::exception& e) {  // no thread could be started
    --g_running;
    job->done = true;
    job->error = path + ": the loader thread could not start (" + e.what() + ")";
  }
  m_job = std::move(job);
  m_path = path;
  m_started = std::chrono::steady_clock::now();
  return true;
}

const LoadProgress* SceneLoader::progress() const { return m_job ? &m_job->progress : nullptr; }

bool SceneLoader::waiting_at_gate() const { return m_job && m_job->waiting_at_gate; }

double SceneLoader::elapsed_seconds() const {
  return m_job ? std::chrono::duration<double>(std::chrono::steady_clock::now() - m_started).count() : 0.0;
}

bool SceneLoader::take(LoadedScene* scene, std::string* error) {
  if (!m_job) return false;
  {
    std::lock_guard<std::mutex> lock(m_job->mutex);
    if (!m_job->done) return false;
    *scene = std::move(m_job->scene);
    *error = std::move(m_job->error);
  }
  m_job.reset();
  m_path.clear();
  return true;
}

void SceneLoader::abandon() {
  if (m_job) m_job->progress.cancel_requested = true;
  m_job.reset();
  m_path.clear();
}

}  // namespace flashgs::viewer
