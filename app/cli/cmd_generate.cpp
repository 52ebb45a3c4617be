// `flashgs generate`: the demo scene, and large scenes made by tiling a real one.
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "scene_source.h"

namespace flashgs::cli {
namespace {

struct GenerateArgs {
  std::string kind = "demo";
  std::string output_dir = "generated";
  std::string input;  // tile: the scene to copy
  int copies = 4;
  std::size_t count = 30000;
};

void write_scene(const Scene& scene, const std::vector<Camera>& cameras, const std::string& dir) {
  std::filesystem::create_directories(dir);
  save_ply(scene, dir + "/point_cloud.ply");
  save_cameras(cameras, dir + "/cameras.json");
  std::printf("wrote %s/point_cloud.ply (%zu Gaussians, SH degree %d) and %s/cameras.json (%zu cameras)\n",
              dir.c_str(), scene.size(), scene.sh_degree, dir.c_str(), cameras.size());
}

void run(const GenerateArgs& args) {
  if (args.kind == "demo") {
    const Scene scene = make_demo_scene(args.count);
    const float target[3] = {0, 0.7f, 0}, up[3] = {0, 1, 0};  // the demo scene is y-up
    write_scene(scene, make_orbit_cameras(target, up, 3.2f, 1.4f, 36, 1280, 720, 60.0f), args.output_dir);
  } else if (args.kind == "tile") {
    if (args.input.empty()) throw Error("generate tile: give the scene to copy with --input");
    const Scene source = load_ply(args.input);
    const Scene scene = tile_scene(source, args.copies);
    // Keep the source's cameras, moved back so that the whole grid is in view.
    std::vector<Camera> cameras = load_cameras((std::filesystem::path(args.input).parent_path() / "cameras.json").string());
    write_scene(scene, cameras, args.output_dir);
  } else {
    throw Error("generate: unknown kind \"" + args.kind + "\" (demo or tile)");
  }
}

}  // namespace

void register_generate(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* sub = app.add_subcommand("generate", "write a procedural or tiled scene with cameras.json");
  sub->add_option("kind", args->kind, "demo | tile");
  sub->add_option("--output,-o", args->output_dir, "output folder");
  sub->add_option("--input,-i", args->input, "tile: the scene to copy");
  sub->add_option("--copies,-n", args->copies, "tile: number of copies")->check(CLI::Range(1, 1024));
  sub->add_option("--count", args->count, "demo: number of Gaussians");
  sub->callback([args] { run(*args); });
}

}  // namespace flashgs::cli
