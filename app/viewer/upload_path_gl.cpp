// The host-memory frame path: render to a float image, convert to RGBA8, glTexSubImage2D.
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
  void attach_textures(const unsigned*, int, int) override {}
  void release_textures() override {}

  void render_to_texture(const Camera& camera, const RenderOptions& options, FrameStats* stats) override {
    m_renderer->render(camera, options, m_image, stats);
    m_presenter->upload(m_image);
  }
  void render_image(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) override {
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

}  // namespace

std::unique_ptr<FramePath> make_upload_path(std::unique_ptr<Renderer> renderer, ImagePresenter* presenter,
                                            std::string label) {
  return std::make_unique<UploadPath>(std::move(renderer), presenter, std::move(label));
}

}  // namespace flashgs::viewer
