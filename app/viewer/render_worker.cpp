// The render worker's thread: one pending request at most, the newest wins, the one in flight is cancelled.
#include "render_worker.h"

#include <chrono>
#include <exception>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "flashgs/error.h"

namespace flashgs::viewer {

RenderWorker::RenderWorker(std::unique_ptr<Renderer> renderer, std::function<void()> on_finished)
    : m_renderer(std::move(renderer)), m_on_finished(std::move(on_finished)) {
  m_renderer->set_cancel_flag(&m_cancel);
  m_thread = std::thread([this] { loop(); });
}

RenderWorker::~RenderWorker() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stop = true;
    m_cancel = true;
  }
  m_wake.notify_all();
  m_thread.join();
}

std::uint64_t RenderWorker::request(const FrameRequest& request, bool cancel_in_flight) {
  std::uint64_t id = 0;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_pending = request;
    m_has_pending = true;
    id = m_pending_id = m_next_id++;
    if (m_rendering && cancel_in_flight) m_cancel = true;
  }
  m_wake.notify_all();
  return id;
}

bool RenderWorker::take(FinishedFrame* out) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_has_finished) return false;
  *out = std::move(m_finished);
  m_has_finished = false;
  return true;
}

bool RenderWorker::busy() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_has_pending || m_rendering || m_pending_scene;
}

void RenderWorker::wait_until_idle() {
  std::unique_lock<std::mutex> lock(m_mutex);
  m_idle.wait(lock, [this] { return !m_has_pending && !m_rendering && !m_pending_scene; });
}

void RenderWorker::set_scene(std::shared_ptr<const Scene> scene) {
  set_pending_scene([scene = std::move(scene)](Renderer& r) { r.set_scene(scene); });
}

void RenderWorker::set_scene_parts(std::vector<ScenePart> parts, std::uint64_t resident_bytes) {
  set_pending_scene([parts = std::move(parts), resident_bytes](Renderer& r) { r.set_scene_parts(parts, resident_bytes); });
}

void RenderWorker::set_pending_scene(std::function<void(Renderer&)> set) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_pending_scene = std::move(set);  // replaces one not yet set
    if (m_rendering) m_cancel = true;  // a frame of the old scene is not worth finishing
  }
  m_wake.notify_all();
}

void RenderWorker::with_renderer(const std::function<void(Renderer&)>& fn, const std::atomic<bool>* cancel) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    ++m_waiting_users;  // the worker starts no frame until this call is done (no starvation)
    if (m_rendering) m_cancel = true;  // the worker puts the frame back as pending
  }
  struct Done {
    RenderWorker* w;
    ~Done() {
      {
        std::lock_guard<std::mutex> lock(w->m_mutex);
        --w->m_waiting_users;
      }
      w->m_wake.notify_all();
    }
  } done{this};
  std::lock_guard<std::mutex> renderer_lock(m_renderer_mutex);
  m_cancel = false;  // nothing of the worker's renders now: the flag was for its frame only
  // The caller's flag while `fn` runs (the worker's own stops only the worker's frames).
  struct WatchedFlag {
    Renderer& r;
    const std::atomic<bool>* worker_flag;
    ~WatchedFlag() { r.set_cancel_flag(worker_flag); }
  } watched{*m_renderer, &m_cancel};
  m_renderer->set_cancel_flag(cancel);
  fn(*m_renderer);
}

void lower_this_thread_priority() {
#ifdef __linux__
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 5);  // threads it starts inherit it
#endif
}

void RenderWorker::loop() {
  using Clock = std::chrono::steady_clock;
  lower_this_thread_priority();  // the renderer's OpenMP threads, started from here, too
  for (;;) {
    std::unique_lock<std::mutex> renderer_lock(m_renderer_mutex, std::defer_lock);
    {
      std::unique_lock<std::mutex> lock(m_mutex);
      m_wake.wait(lock, [this] { return m_stop || ((m_has_pending || m_pending_scene) && m_waiting_users == 0); });
      if (m_stop) return;
      // The renderer lock is taken without holding m_mutex: with_renderer() holds it while it
      // runs, and request() must never wait for that.
      lock.unlock();
      renderer_lock.lock();
      lock.lock();
      if (m_stop) return;
      if (m_waiting_users > 0) continue;  // with_renderer came first: after it
      if (m_pending_scene) {  // a new scene before any further frame
        std::function<void(Renderer&)> set_scene = std::move(m_pending_scene);
        m_pending_scene = nullptr;
        m_rendering = true;  // busy meanwhile
        lock.unlock();
        std::string error;
        try {
          set_scene(*m_renderer);
        } catch (const std::exception& e) {
          error = error_text(e);
        }
        lock.lock();
        m_rendering = false;
        if (!error.empty()) {  // the next take() reports it
          m_finished = FinishedFrame{};
          m_finished.error = "the new scene could not be set: " + error;
          m_has_finished = true;
        }
        m_idle.notify_all();
        continue;
      }
      if (!m_has_pending) continue;
      m_in_flight = m_pending;
      m_in_flight_id = m_pending_id;
      m_has_pending = false;
      m_rendering = true;
      m_cancel = false;
    }
    FinishedFrame frame;
    frame.request = m_in_flight;
    frame.id = m_in_flight_id;
    const auto t0 = Clock::now();
    try {
      m_renderer->render(frame.request.camera, frame.request.options, frame.image, &frame.stats);
    } catch (const std::exception& e) {
      frame.error = error_text(e);
    }
    frame.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    renderer_lock.unlock();
    bool delivered = false;
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_rendering = false;
      // A finished frame is shown even when a newer one is pending (a backend that cannot
      // stop early still shows progress); a stopped one is incomplete. request() leaves a
      // newer request pending; with_renderer() does not: that frame is rendered again.
      const bool stopped = frame.stats.cancelled;
      if (stopped && !m_has_pending && !m_stop) {
        m_pending = frame.request;
        m_pending_id = frame.id;
        m_has_pending = true;
      } else if (!stopped) {
        m_finished = std::move(frame);
        m_has_finished = true;
        delivered = true;
      }
      m_cancel = false;
    }
    if (delivered && m_on_finished) m_on_finished();
    m_idle.notify_all();
  }
}

}  // namespace flashgs::viewer
