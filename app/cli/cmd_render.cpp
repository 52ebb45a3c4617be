// `flashgs render`: one frame of a scene to an image file, with its statistics.
#include <cstdio>

#include "backend_factory.h"
#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/image_io.h"
#include "flashgs/io.h"
#include "flashgs/scene_summary.h"
#include "option_checks.h"
#include "scene_source.h"
#include "stats_format.h"

namespace flashgs::cli {
namespace {

struct RenderCommand {
  SceneArgs scene;
  CameraArgs camera;
  RenderArgs render;
  std::string output = "render.png";
  int repeat = 1;

  void run() const {
    check_output_image("--output", output);  // before the render, which may take long
    const std::string scene_path = scene.resolved_scene();
    const std::string size_option = camera.resolution.empty() ? "the camera's size" : "--resolution";
    auto renderer = create_backend(render.backend);
    check_declared_scene(*renderer, scene_path, size_option);
    auto loaded = load_scene_verbose(scene_path, scene.lod);
    const Camera cam = camera.select(scene.resolved_cameras());
    check_frame_fits(*renderer, cam, loaded->size(), size_option);
    renderer->set_scene(loaded);
    const RenderOptions options = render.options(*loaded);
    Image image;
    FrameStats stats;
    for (int i = 0; i < repeat; ++i) renderer->render(cam, options, image, &stats);
    write_image(image, output);
    std::printf("%s: %zu Gaussians (SH degree %d), camera %d \"%s\" at %dx%d, %s on %s\n", scene_path.c_str(),
                loaded->size(), loaded->sh_degree, camera.index, cam.name.c_str(), cam.width, cam.height,
                options.label().c_str(), renderer->name().c_str());
    std::printf("kernel: %s\n", render.kernel.chosen() ? (options.kernel.description() + " (--kernel)").c_str()
                                                        : kernel_summary(loaded->trained_kernel).c_str());
    std::printf("%s", format_stats(stats).c_str());
    std::printf("wrote %s\n", output.c_str());
  }

  // What the scene file declares, against loading it and one frame, before it is read. A
  // camera that cannot be had skips this: its error comes after the scene's, as always.
  void check_declared_scene(const Renderer& renderer, const std::string& scene_path,
                            const std::string& size_option) const {
    Camera cam;
    try {
      cam = camera.select(scene.resolved_cameras());
    } catch (const Error&) {
      return;
    }
    check_declared_scene_fits(renderer, cam, scene_path, size_option);
  }
};

}  // namespace

void register_render(CLI::App& app) {
  auto command = std::make_shared<RenderCommand>();
  CLI::App* sub = app.add_subcommand("render", "render one frame to an image (PNG, EXR, PPM, PFM)");
  command->scene.add_to(sub);
  command->camera.add_to(sub);
  command->render.add_to(sub);
  sub->add_option("--output,-o", command->output, "output image (the extension picks the format)");
  sub->add_option("--repeat", command->repeat, "render this many times (statistics of the last)")
      ->check(whole_number())->check(CLI::PositiveNumber);
  sub->callback([command] { command->run(); });
}

}  // namespace flashgs::cli
