#include "render_gate.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <system_error>
#include <thread>

namespace flashgs::viewer {

bool wait_at_gate(const std::string& gate_file, const std::function<bool()>& stop, std::atomic<bool>& waiting) {
  // Polled: the file comes from another process (the test's script), which cannot signal us.
  std::error_code ignored;
  while (!std::filesystem::exists(gate_file, ignored)) {
    if (stop()) {
      waiting = false;
      return false;
    }
    waiting = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  waiting = false;
  return true;
}

FileGatedRenderer::FileGatedRenderer(std::unique_ptr<Renderer> inner, std::string gate_file)
    : m_inner(std::move(inner)), m_gate_file(std::move(gate_file)) {}

void FileGatedRenderer::render(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) {
  // Logged for the tests: which frames waited at the closed gate, and which a newer request
  // stopped there.
  std::error_code ignored;
  if (!std::filesystem::exists(m_gate_file, ignored))
    std::fprintf(stderr, "flashgs-viewer: render gate: a %dx%d frame waits\n", camera.width, camera.height);
  if (!wait_at_gate(m_gate_file, [this] { return cancel_requested(); }, m_waiting))
    std::fprintf(stderr, "flashgs-viewer: render gate: the waiting frame was cancelled\n");
  m_inner->set_cancel_flag(cancel_flag());
  m_inner->render(camera, options, out, stats);
}

}  // namespace flashgs::viewer
