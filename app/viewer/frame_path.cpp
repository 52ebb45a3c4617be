// FramePath's synchronous frame delivery: submit() renders now, take_finished() hands the frame over once.
#include "frame_path.h"

#include <chrono>

namespace flashgs::viewer {

void FramePath::submit(const FrameRequest& request, bool /*cancel_in_flight*/) {
  const auto t0 = std::chrono::steady_clock::now();
  FinishedFrame done;
  done.request = request;
  render_to_texture(request.camera, request.options, &done.stats);
  done.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  m_done = std::move(done);
  m_has_done = true;
}

bool FramePath::take_finished(FinishedFrame* frame) {
  if (!m_has_done) return false;
  *frame = std::move(m_done);
  m_has_done = false;
  return true;
}

}  // namespace flashgs::viewer
