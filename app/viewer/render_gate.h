// File gates for scripted tests, so that a test keeps work in flight for exactly as long as it needs, on a fast machine as on a slow one: a Renderer that holds each render until a file exists (--render-gate), and the wait the scene loader uses to hold each load (--load-gate).
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "flashgs/renderer.h"

namespace flashgs::viewer {

// Returns once `gate_file` exists (true) or `stop()` is true (false); `waiting` is true while
// it waits.
bool wait_at_gate(const std::string& gate_file, const std::function<bool()>& stop, std::atomic<bool>& waiting);

class FileGatedRenderer final : public Renderer {
 public:
  // Renders with `inner` once `gate_file` exists; a render whose cancel flag is raised while
  // it waits goes on at once (and `inner` stops it as a cancelled frame).
  FileGatedRenderer(std::unique_ptr<Renderer> inner, std::string gate_file);

  std::string name() const override { return m_inner->name(); }
  void set_scene(std::shared_ptr<const Scene> scene) override { m_inner->set_scene(std::move(scene)); }
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) override {
    m_inner->set_scene_parts(parts, resident_bytes);
  }
  std::string scene_parts_refusal(const RenderOptions& options) const override {
    return m_inner->scene_parts_refusal(options);
  }
  void render(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) override;
  // A render waits at the closed gate now (tests wait for it before they open it).
  bool waiting() const { return m_waiting; }

 private:
  std::unique_ptr<Renderer> m_inner;
  std::string m_gate_file;
  std::atomic<bool> m_waiting{false};
};

}  // namespace flashgs::viewer
