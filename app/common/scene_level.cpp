// Loading a scene file or one level of a SOG LOD set (see scene_level.h).
#include "scene_level.h"

#include <chrono>
#include <cstdio>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/frame_memory.h"
#include "flashgs/scene_formats.h"

namespace flashgs {

namespace {

Scene load_sog_lod_level(const std::string& path, int lod, LoadReport* report) {
  const SogLodSet set = describe_sog_lod(path);
  const AvailableMemory memory = available_host_memory();
  const int level = lod >= 0 ? lod : choose_sog_lod_level(set, memory.bytes);
  if (level >= static_cast<int>(set.levels.size()))
    throw Error("--lod " + std::to_string(lod) + ": " + path + " has levels 0.." + std::to_string(set.levels.size() - 1));
  const SogLodLevel& chosen = set.levels[static_cast<std::size_t>(level)];
  std::fprintf(stderr, "%s: LOD level %d of 0..%zu, %zu Gaussians (%s)\n", path.c_str(), level, set.levels.size() - 1,
               chosen.gaussians,
               lod >= 0 ? "--lod"
                        : ("the finest needing at most half of the " + format_bytes(memory.bytes) + " available").c_str());
  const auto began = std::chrono::steady_clock::now();
  Scene scene = read_sog_lod(path, level, report);
  report->decode_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  report->format = "LOD set (lod-meta.json) of " + (report->format.empty() ? std::string("unread") : report->format) +
                   " chunks, level " + std::to_string(level);
  return scene;
}

}  // namespace

Scene load_scene_at_level(const std::string& path, int lod, LoadReport* report, const SceneReadOptions& options) {
  const bool lod_set = is_sog_lod_set(path);
  if (lod >= 0 && !lod_set) throw Error("--lod: " + path + " is not a SOG LOD set (lod-meta.json)");
  return lod_set ? load_sog_lod_level(path, lod, report) : load_scene_file(path, report, nullptr, options);
}

}  // namespace flashgs
