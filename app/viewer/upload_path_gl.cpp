// The host-memory frame paths: render to a float image (here, or on a worker thread), convert to RGBA8, glTexSubImage2D.
#include "frame_path.h"
#include "image_presenter_gl.h"

namespace flashgs::viewer {
namespace {

class UploadPath final : public FramePath {
 public:
  UploadPath(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter, std::string label)
      : m_renderer(std::move(renderer)), m_presenter(presenter), m_label(std::move(label)) {}

  std::string name() const override { return m_label; }
  void set_scene(std::shared_ptr<const Scene> scene) override { m_renderer->set_scene(std::move(scene)); }
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) override {
    m_renderer->set_scene_parts(parts, resident_bytes);
  }
  std::string scene_parts_refusal(const RenderOptions& options) const override {
    return m_renderer->scene_parts_refusal(options);
  }
  void attach_textures(const unsigned*, int, int) override {}
  void release_textures() override {}

  void render_to_texture(const Camera& camera, const RenderOptions& options, FrameStats* stats) override {
    m_renderer->render(camera, options, m_image, stats);
    m_presenter->upload(m_image);
  }
  void render_image(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats,
                    const std::atomic<bool>*) override {
    m_renderer->render(camera, options, out, stats);
  }
  void tile_counts(const FrameStats& stats, std::vector<std::uint32_t>& out) override { out = stats.tile_pair_counts; }
  const Image* last_image() const override { return &m_image; }

 private:
  std::unique_ptr<Renderer> m_renderer;
  ImagePresenter* m_presenter;
  std::string m_label;
  Image m_image;
};

// The renders run on a RenderWorker; the UI thread uploads each finished frame.
class BackgroundUploadPath final : public FramePath {
 public:
  BackgroundUploadPath(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter, std::string label,
                       std::function<void()> wake)
      : m_worker(std::move(renderer), std::move(wake)), m_presenter(presenter), m_label(std::move(label)) {}

  std::string name() const override { return m_label; }
  // Never waits for a frame of the old scene: the worker switches before its next frame.
  void set_scene(std::shared_ptr<const Scene> scene) override { m_worker.set_scene(std::move(scene)); }
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) override {
    m_worker.set_scene_parts(parts, resident_bytes);
  }
  void attach_textures(const unsigned*, int, int) override {}
  void release_textures() override {}

  bool renders_in_background() const override { return true; }
  void submit(const FrameRequest& request, bool cancel_in_flight) override {
    m_worker.request(request, cancel_in_flight);
  }
  bool take_finished(FinishedFrame* frame) override {
    if (!m_worker.take(frame)) return false;
    if (frame->error.empty()) {
      m_image = std::move(frame->image);
      m_presenter->upload(m_image);  // may throw (a texture refused): the caller reports it
    }
    return true;
  }
  bool busy() const override { return m_worker.busy(); }
  void wait_until_idle() override { m_worker.wait_until_idle(); }

  void render_to_texture(const Camera& camera, const RenderOptions& options, FrameStats* stats) override {
    m_worker.with_renderer([&](Renderer& r) { r.render(camera, options, m_image, stats); });
    m_presenter->upload(m_image);
  }
  void render_image(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats,
                    const std::atomic<bool>* cancel) override {
    m_worker.with_renderer([&](Renderer& r) { r.render(camera, options, out, stats); }, cancel);
  }
  void tile_counts(const FrameStats& stats, std::vector<std::uint32_t>& out) override { out = stats.tile_pair_counts; }
  const Image* last_image() const override { return &m_image; }

 private:
  RenderWorker m_worker;
  ImagePresenter* m_presenter;
  std::string m_label;
  Image m_image;  // the last frame uploaded (UI thread only)
};

}  // namespace

std::unique_ptr<FramePath> make_background_upload_path(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter,
                                                       std::string label, std::function<void()> wake) {
  return std::make_unique<BackgroundUploadPath>(std::move(renderer), presenter, std::move(label), std::move(wake));
}

std::unique_ptr<FramePath> make_upload_path(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter,
                                            std::string label) {
  return std::make_unique<UploadPath>(std::move(renderer), presenter, std::move(label));
}

}  // namespace flashgs::viewer
