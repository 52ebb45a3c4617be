// `flashgs info`: what a scene file holds and what loading it dropped.
#include <cstdio>

#include "commands.h"
#include "flashgs/scene_formats.h"
#include "flashgs/scene_summary.h"
#include "scene_source.h"

namespace flashgs::cli {

void register_info(CLI::App& app) {
  auto args = std::make_shared<SceneArgs>();
  CLI::App* sub = app.add_subcommand("info", "summarise a scene: count, SH degree, bounds, statistics");
  args->add_to(sub);
  sub->callback([args] {
    const std::string path = args->resolved_scene();
    LoadReport report;
    const Scene scene = load_scene_at_level(path, args->lod, &report, args->read_options());
    std::printf("%s", summarize_scene(scene, &report).c_str());
    std::printf("%s", describe_lod_levels(path).c_str());
  });
}

}  // namespace flashgs::cli
