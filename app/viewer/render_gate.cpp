#include "render_gate.h"

#include <chrono>
#include <filesystem>
#include <system_error>
#include <thread>

namespace flashgs::viewer {

void wait_at_gate(const std::string& gate_file, const std::function<bool()>& stop, std::atomic<bool>& waiting) {
  // Polled: the file comes from another process (the test's script), which cannot signal us.
  std::error_code ignored;
  while (!stop() && !std::filesystem::exists(gate_file, ignored)) {
    waiting = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  waiting = false;
}

FileGatedRenderer::FileGatedRenderer(std::unique_ptr<Renderer> inner, std::string gate_file)
    : m_inner(std::move(inner)), m_gate_file(std::move(gate_file)) {}

void FileGatedRenderer::render(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) {
  wait_at_gate(m_gate_file, [this] { return cancel_requested(); }, m_waiting);
  m_inner->set_cancel_flag(cancel_flag());
  m_inner->render(camera, options, out, stats);
}

}  // namespace flashgs::viewer
