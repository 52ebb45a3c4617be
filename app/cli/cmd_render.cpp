// `flashgs render`: one frame of a scene to an image file, with its statistics; or a keyframed camera path's frames.
#include <cstdio>

#include "backend_factory.h"
#include "commands.h"
#include "flashgs/debug_view.h"
#include "flashgs/error.h"
#include "flashgs/image_io.h"
#include "flashgs/io.h"
#include "flashgs/keyframe_path.h"
#include "flashgs/parse.h"
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
  std::string path_file;  // --path: a camera path's frames into the folder `output`
  int fps = 0;            // --fps: overrides the path file's
  std::string view = "colour";  // --view: the colour, or a debug view (flashgs/debug_view.h)

  void run() const {
    if (!path_file.empty()) return run_path();
    check_output_image("--output", output);  // before the render, which may take long
    const std::string scene_path = scene.resolved_scene();
    const std::string size_option = camera.resolution.empty() ? "the camera's size" : "--resolution";
    check_declared_scene(scene_path, size_option);
    // The scene's errors, then the camera's, then the backend's note.
    auto loaded = load_scene_verbose(scene_path, scene.lod, scene.read_options());
    const Camera cam = camera.select(scene.resolved_cameras());
    auto renderer = create_backend(render.backend);
    check_frame_fits(*renderer, cam, loaded->size(), size_option);
    renderer->set_scene(loaded);
    FrameView frame_view = FrameView::colour;
    parse_frame_view(view, &frame_view);  // checked by the option
    RenderOptions options = render.options(*loaded);
    options.collect_pixel_planes = frame_view != FrameView::colour;
    Image image;
    FrameStats stats;
    for (int i = 0; i < repeat; ++i) renderer->render(cam, options, image, &stats);
    std::string scale_line;
    if (frame_view != FrameView::colour) image = debug_image(frame_view, stats, cam, options, &scale_line);
    write_image(image, output);
    std::printf("%s: %zu Gaussians (SH degree %d), camera %d \"%s\" at %dx%d, %s on %s\n", scene_path.c_str(),
                loaded->size(), loaded->sh_degree, camera.index, cam.name.c_str(), cam.width, cam.height,
                options.label().c_str(), renderer->name().c_str());
    std::printf("kernel: %s\n", render.kernel.chosen() ? (options.kernel.description() + " (--kernel)").c_str()
                                                        : kernel_summary(loaded->trained_kernel).c_str());
    std::printf("%s", format_stats(stats).c_str());
    std::printf("%swrote %s\n", scale_line.c_str(), output.c_str());
  }

  // The frame's debug view, and in `scale_line` what its colours stand for.
  static Image debug_image(FrameView frame_view, const FrameStats& stats, const Camera& cam,
                           const RenderOptions& options, std::string* scale_line) {
    const DebugScale scale = debug_scale(stats);
    char text[200];
    if (frame_view == FrameView::depth && scale.any_blended)
      std::snprintf(text, sizeof text,
                    "view depth: blended depth from %.6g (dark) to %.6g (bright) scene units; the background where "
                    "nothing blended\n", scale.near_depth, scale.far_depth);
    else if (frame_view == FrameView::depth)
      std::snprintf(text, sizeof text, "view depth: nothing blended, the background only\n");
    else
      std::snprintf(text, sizeof text, "view count: Gaussians blended per pixel, log scale from 0 (dark) to %u (bright)\n",
                    scale.max_blended);
    *scale_line = text;
    return debug_view_image(frame_view, stats, cam.width, cam.height, scale, options.background);
  }

  // What the scene file declares, against loading it and one frame, before it is read. A
  // camera that cannot be had skips this: its error comes after the scene's, as always.
  void check_declared_scene(const std::string& scene_path, const std::string& size_option) const {
    Camera cam;
    try {
      cam = camera.select(scene.resolved_cameras());
    } catch (const Error&) {
      return;
    }
    check_declared_scene_fits(backend_kind(render.backend), cam, scene_path, size_option);
  }

  // The path's frames, frame_00000.png on, at the path's size (or --resolution) and fps (or --fps).
  void run_path() const {
    KeyframePath path = read_camera_path(path_file);
    if (fps > 0) path.fps = fps;
    if (!camera.resolution.empty()) {
      const Resolution size = parse_resolution(camera.resolution);
      path.width = size.width;
      path.height = size.height;
    }
    const std::vector<std::string> created = check_output_folder("--output", output);
    const std::string scene_path = scene.resolved_scene();
    auto loaded = load_scene_verbose(scene_path, scene.lod);
    auto renderer = create_backend(render.backend);
    check_frame_fits(*renderer, path.camera_at(path.frame_time(0), path.width, path.height), loaded->size(), "the path's size");
    renderer->set_scene(loaded);
    const RenderOptions options = render.options(*loaded);
    const int frames = path.frame_count();
    std::printf("%s: %zu keyframes, %.2f s at %d fps: %d frames at %dx%d, %s on %s\n", path_file.c_str(),
                path.keys.size(), path.duration_s(), path.fps, frames, path.width, path.height,
                options.label().c_str(), renderer->name().c_str());
    Image image;
    FrameStats stats;
    for (int i = 0; i < frames; ++i) {
      renderer->render(path.camera_at(path.frame_time(i), path.width, path.height), options, image, &stats);
      char name[32];  // PNG where OpenImageIO is built in, else PPM (the same 8-bit bytes)
      std::snprintf(name, sizeof name, "/frame_%05d%s", i, image_io_writes_png() ? ".png" : ".ppm");
      write_image(image, output + name);
    }
    std::printf("wrote %d frames to %s\n", frames, output.c_str());
  }

};

}  // namespace

void register_render(CLI::App& app) {
  auto command = std::make_shared<RenderCommand>();
  CLI::App* sub = app.add_subcommand("render", "render one frame to an image (PNG, EXR, PPM, PFM)");
  command->scene.add_to(sub);
  command->camera.add_to(sub);
  command->render.add_to(sub);
  sub->add_option("--output,-o", command->output,
                  "output image (the extension picks the format); with --path, the frames' folder");
  sub->add_option("--repeat", command->repeat, "render this many times (statistics of the last)")
      ->check(whole_number())->check(CLI::PositiveNumber);
  auto* path = sub->add_option("--path", command->path_file,
                               "render a camera path (the viewer's JSON or nerfstudio's camera_path.json) as "
                               "frame_00000.png ... into the --output folder");
  sub->add_option("--fps", command->fps, "with --path: frames per second (default: the path file's)")
      ->check(whole_number())->check(CLI::Range(1, kMaxPathFps))->needs(path);
  auto* view = sub->add_option("--view", command->view,
                               std::string("what the image shows: ") + kFrameViewChoices +
                                   " (depth: the blended depth, count: Gaussians blended per pixel, both on a "
                                   "colour scale printed with the frame; from the per-pixel blend, slower)")
                   ->check([](const std::string& text) {
                     FrameView v;
                     return parse_frame_view(text, &v) ? std::string()
                                                       : "'" + text + "' is not one of " + kFrameViewChoices;
                   });
  path->excludes("--camera")->excludes("--eye")->excludes("--repeat")->excludes(view);
  sub->callback([command, sub] {
    if (!command->path_file.empty() && sub->get_option("--output")->count() == 0) command->output = "path_frames";
    command->run();
  });
}

}  // namespace flashgs::cli
