// RenderWorker: a thread that renders the newest requested view with a slow backend (the CPU), cancelling and restarting when the view changes, so the UI thread never waits for a frame.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/renderer.h"
#include "flashgs/scene.h"
#include "flashgs/stats.h"

namespace flashgs::viewer {

struct FrameRequest {
  Camera camera;
  RenderOptions options;
  bool reduced = false;  // fewer pixels than the full frame (the view is moving)
};

struct FinishedFrame {
  FrameRequest request;
  Image image;
  FrameStats stats;
  double wall_ms = 0;  // the render's wall time on the worker
  std::uint64_t id = 0;  // request() numbers its requests from 1
  std::string error;  // non-empty: the render threw (out of memory, ...); image and stats are empty
};

// Puts the calling thread below the UI thread (and the OpenMP threads it starts later): on a
// machine with few cores the window must still answer at once. For the threads that render.
void lower_this_thread_priority();

class RenderWorker {
 public:
  // `on_finished` runs on the worker thread after each finished frame (the viewer wakes its
  // event loop with it); it must not call back into the worker.
  RenderWorker(std::unique_ptr<Renderer> renderer, std::function<void()> on_finished);
  // Cancels the frame in flight and joins the thread.
  ~RenderWorker();
  RenderWorker(const RenderWorker&) = delete;
  RenderWorker& operator=(const RenderWorker&) = delete;

  // Asks for a frame; it replaces a request not yet started. With `cancel_in_flight` the frame
  // rendering now stops early (Renderer::set_cancel_flag) and is dropped; a backend that
  // cannot stop finishes it, and it is shown. Returns the request's id.
  std::uint64_t request(const FrameRequest& request, bool cancel_in_flight = true);
  // The newest finished frame since the last call (older ones are dropped unseen).
  bool take(FinishedFrame* out);
  // A frame requested and not yet finished.
  bool busy() const;
  // Blocks until no frame is requested or rendering (scripted runs: the frame they time).
  void wait_until_idle();
  // Makes `scene` the one rendered from the next frame on without waiting: the frame in flight
  // stops (where the backend can), the worker sets the scene, then renders what is pending.
  // A failure comes back from take() as a frame with `error` set.
  void set_scene(std::shared_ptr<const Scene> scene);
  // The same for a streamed cut's parts (Renderer::set_scene_parts, on the worker: the CPU
  // backend assembles them there, not on the caller's thread).
  void set_scene_parts(std::vector<ScenePart> parts, std::uint64_t resident_bytes);
  // Runs `fn` with the renderer on the calling thread once no frame renders: the one in flight
  // is cancelled and requested again afterwards. Thread-safe (set_scene from the UI thread,
  // the comparison's renders from a task thread); exceptions from `fn` propagate. The renders
  // `fn` makes stop early once `cancel` is set (null: they finish).
  void with_renderer(const std::function<void(Renderer&)>& fn, const std::atomic<bool>* cancel = nullptr);

 private:
  void loop();

  std::unique_ptr<Renderer> m_renderer;
  std::function<void()> m_on_finished;
  std::mutex m_renderer_mutex;  // held while anything uses m_renderer
  mutable std::mutex m_mutex;   // guards everything below
  std::condition_variable m_wake, m_idle;
  bool m_stop = false;
  bool m_has_pending = false;
  void set_pending_scene(std::function<void(Renderer&)> set);

  std::function<void(Renderer&)> m_pending_scene;  // sets the new scene before the next frame
  FrameRequest m_pending;
  std::uint64_t m_pending_id = 0, m_next_id = 1;
  bool m_rendering = false;  // a frame of the worker's own is in flight
  int m_waiting_users = 0;   // with_renderer() calls waiting or running
  FrameRequest m_in_flight;
  std::uint64_t m_in_flight_id = 0;
  bool m_has_finished = false;
  FinishedFrame m_finished;
  std::atomic<bool> m_cancel{false};
  std::thread m_thread;  // last: starts once everything above exists
};

}  // namespace flashgs::viewer
