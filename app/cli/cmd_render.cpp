// `flashgs render`: one frame of a scene to an image file, with its statistics.
#include <cstdio>

#include "backend_factory.h"
#include "commands.h"
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
    auto loaded = load_scene_verbose(scene_path, scene.lod, scene.read_options());
    const Camera cam = camera.select(scene.resolved_cameras());
    auto renderer = create_backend(render.backend);
    check_frame_fits(*renderer, cam, loaded->size(),
                     camera.resolution.empty() ? "the camera's size" : "--resolution");
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
