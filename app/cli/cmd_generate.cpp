// `flashgs generate`: the demo scene, and large scenes made by tiling a real one.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/city_scene.h"
#include "flashgs/file_write.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "flashgs/stress_scenes.h"
#include "option_checks.h"
#include "scene_source.h"

namespace flashgs::cli {
namespace {

struct GenerateArgs {
  std::string kind;  // demo when not given (or stress with --list)
  std::string output_dir = "generated";
  std::string input;  // tile: the scene to copy
  int copies = 4;
  std::size_t count = 30000;
  std::string stress;  // stress: the case name
  bool list = false;
  bool force = false;  // overwrite a scene already in output_dir
};

namespace fs = std::filesystem;

// Refuses, before any work, an output folder that already holds a scene (unless --force), or
// whose scene files could not be written.
// Returns the folders it created (check_output_folder).
std::vector<std::string> check_output_scene(const GenerateArgs& args) {
  const std::vector<std::string> created = check_output_folder("--output", args.output_dir);
  for (const char* name : {"point_cloud.ply", "cameras.json"}) {
    const fs::path existing = fs::path(args.output_dir) / name;
    check_output_file("--output", existing.string());
    if (!args.force && fs::exists(existing))
      throw Error("--output " + args.output_dir + ": already holds " + existing.string() +
                  " (give --force to overwrite it)");
  }
  return created;
}

void write_scene(const Scene& scene, const std::vector<Camera>& cameras, const std::string& dir) {
  save_ply(scene, dir + "/point_cloud.ply");
  save_cameras(cameras, dir + "/cameras.json");
  std::printf("wrote %s/point_cloud.ply (%zu Gaussians, SH degree %d) and %s/cameras.json (%zu cameras)\n",
              dir.c_str(), scene.size(), scene.sh_degree, dir.c_str(), cameras.size());
}

// --input "SCENE[:UP],...": each scene (any format; a LOD set at its finest level that fits) and
// its up axis (+z when not given).
std::vector<CitySource> city_sources(const std::string& list) {
  std::vector<CitySource> sources;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = std::min(list.find(',', start), list.size());
    const std::string item = list.substr(start, end - start);
    if (item.empty()) throw Error("--input \"" + printable_file_text(list) + "\": an empty scene name in the list");
    CitySource source;
    const std::size_t colon = item.rfind(':');
    const bool has_up = colon != std::string::npos && item.size() - colon == 3 && (item[colon + 1] == '+' || item[colon + 1] == '-');
    source.name = has_up ? item.substr(0, colon) : item;
    if (has_up) source.up = item.substr(colon + 1);
    LoadReport report;
    source.scene = load_scene_at_level(locate_scene(source.name).ply, -1, &report);
    std::fprintf(stderr, "read %s: %zu Gaussians, up %s\n", source.name.c_str(), source.scene.size(), source.up.c_str());
    sources.push_back(std::move(source));
    start = end + 1;
  }
  return sources;
}

void generate_city(const GenerateArgs& args) {
  if (args.input.empty()) throw Error("generate city: give the scenes to lay out with --input A[:UP],B[:UP],...");
  const std::vector<CitySource> sources = city_sources(args.input);
  std::vector<Camera> path;
  const std::string ply = args.output_dir + "/point_cloud.ply";
  const CityReport r = write_city_scene(sources, args.copies, ply, 60, 1920, 1080, &path);
  save_cameras(path, args.output_dir + "/cameras.json");
  std::printf("wrote %s: %llu Gaussians in %d blocks of %.1f units (%.2f GB; %.2f GB in memory as floats) and %s/cameras.json "
              "(%zu cameras from street level to an overview)\n",
              ply.c_str(), static_cast<unsigned long long>(r.gaussians), r.blocks, r.block_size, double(r.bytes) / 1e9,
              double(r.gaussians) * 56 / 1e9, args.output_dir.c_str(), path.size());
  if (r.dropped_sh)
    std::printf("note: the copies are turned, and view-dependent colour (SH bands 1-3) is not rotated with them: the "
                "city keeps each Gaussian's base colour\n");
}

// The kind asked for: --list goes with stress alone (it wrote a demo scene before).
GenerateArgs with_kind(GenerateArgs args) {
  if (args.list && !args.kind.empty() && args.kind != "stress")
    throw Error("--list: lists the stress cases; it does not go with generate " + args.kind);
  if (args.kind.empty()) args.kind = args.list ? "stress" : "demo";
  return args;
}

void generate(const GenerateArgs& args) {
  if (args.kind == "demo") {
    const Scene scene = make_demo_scene(args.count);
    const float target[3] = {0, 0.7f, 0}, up[3] = {0, 1, 0};  // the demo scene is y-up
    write_scene(scene, make_orbit_cameras(target, up, 3.2f, 1.4f, 36, 1280, 720, 60.0f), args.output_dir);
  } else if (args.kind == "tile") {
    if (args.input.empty()) throw Error("generate tile: give the scene to copy with --input");
    const Scene source = load_scene_file(args.input);
    const Scene scene = tile_scene(source, args.copies);
    // The source's cameras, pushed back from the grid centre so that the whole grid is in
    // view and every copy costs work (the grid is centred where the source was).
    std::vector<Camera> cameras = load_cameras((std::filesystem::path(args.input).parent_path() / "cameras.json").string());
    float lo[3], hi[3];
    scene_bounds(source, lo, hi);
    const float side = std::ceil(std::sqrt(static_cast<float>(args.copies)));
    for (Camera& camera : cameras)
      for (int k = 0; k < 3; ++k) {
        const float centre = 0.5f * (lo[k] + hi[k]);
        camera.position[k] = centre + (camera.position[k] - centre) * side;
      }
    write_scene(scene, cameras, args.output_dir);
  } else if (args.kind == "city") {
    generate_city(args);
  } else if (args.kind == "stress") {
    if (args.list || args.stress.empty()) {
      for (const std::string& name : stress_case_names())
        std::printf("%-16s %s\n", name.c_str(), make_stress_case(name).description.c_str());
      if (args.stress.empty() && !args.list) throw Error("generate stress: name a case (listed above)");
      return;
    }
    StressCase c = make_stress_case(args.stress);
    if (!c.raw_ply.empty()) {
      // The degenerate-file case is the file itself: written byte for byte, NaNs included.
      const std::string ply = args.output_dir + "/point_cloud.ply";
      write_file_atomically(ply, c.raw_ply);
      save_cameras(c.cameras, args.output_dir + "/cameras.json");
      std::printf("wrote %s (raw, with NaN/Inf records) and %s/cameras.json\n", ply.c_str(), args.output_dir.c_str());
    } else {
      write_scene(c.scene, c.cameras, args.output_dir);
    }
    std::printf("%s: %s\nbound vs fp64 reference: flash %.3g, baseline %.3g (%s)\n", c.name.c_str(),
                c.description.c_str(), c.bound_flash, c.bound_baseline, c.bound_reason.c_str());
  } else {
    throw Error("generate: unknown kind \"" + args.kind + "\" (demo, tile, city or stress)");
  }
}

void run(const GenerateArgs& given) {
  const GenerateArgs args = with_kind(given);
  const bool lists_only = args.kind == "stress" && (args.list || args.stress.empty());
  std::vector<std::string> created;
  if (!lists_only && (args.kind == "demo" || args.kind == "tile" || args.kind == "city" || args.kind == "stress"))
    created = check_output_scene(args);
  // A folder made here goes again when the input fails (a missing --input, an unknown case).
  try {
    generate(args);
  } catch (...) {
    remove_created_folders(created);
    throw;
  }
}

}  // namespace

void register_generate(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* sub = app.add_subcommand("generate", "write a procedural or tiled scene with cameras.json");
  sub->add_option("kind", args->kind, "demo | tile | city | stress");
  sub->add_option("name", args->stress, "stress: the case (see --list)");
  sub->add_option("--stress", args->stress, "same as `generate stress NAME`")->each([args](const std::string&) {
    args->kind = "stress";
  });
  sub->add_flag("--list", args->list, "stress: list the cases");
  sub->add_option("--output,-o", args->output_dir, "output folder");
  sub->add_option("--input,-i", args->input,
                  "tile: the scene to copy; city: the scenes to lay out, SCENE[:UP],... (UP one of +x -x +y -y +z -z, "
                  "default +z)");
  sub->add_option("--copies,-n", args->copies, "tile: number of copies; city: number of blocks")
      ->check(whole_number())
      ->check(CLI::Range(1, 1024));
  sub->add_option("--count", args->count, "demo: number of Gaussians")->check(whole_number())->check(CLI::Range(1, 200000000));
  sub->add_flag("--force", args->force, "overwrite a scene already in the output folder");
  sub->callback([args] { run(*args); });
}

}  // namespace flashgs::cli
