// The viewer's LOD set cache: where a scene file's set lives, and building it when absent.
#include "lod_cache.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include <unistd.h>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"
#include "flashgs/lod_build.h"

namespace flashgs::viewer {
namespace {

namespace fs = std::filesystem;

// FNV-1a, 64 bits: a stable key (std::hash may differ between builds).
std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string user_cache_root() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg == '/') return xdg;  // the spec ignores a relative value
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : "/tmp") + "/.cache";
}

bool holds_set(const std::string& folder) {
  std::error_code error;
  return fs::is_regular_file(fs::path(folder) / "lod-meta.json", error);
}

// Builds into `folder` through a temporary sibling; false when that cannot be created (the
// caller tries the next place); throws when the build itself fails.
bool build_into(const std::string& scene_file, const std::string& folder, const LodBuildOptions& options,
                LoadProgress* progress) {
  std::error_code error;
  const fs::path target(folder), partial = target.string() + ".partial-" + std::to_string(::getpid());
  fs::create_directories(target.parent_path(), error);
  if (error || ::access(target.parent_path().c_str(), W_OK) != 0) return false;
  fs::remove_all(partial, error);
  if (!fs::create_directory(partial, error) || error) return false;
  LodBuildOptions build = options;
  if (progress) {
    // Three passes over the scene: the load bar runs once over all of them (a third each).
    build.progress = [progress, &scene_file](const char* stage, std::uint64_t done, std::uint64_t total) {
      if (progress->cancel_requested) throw LoadCancelled(scene_file);
      const std::string s = stage;
      const std::uint64_t pass = s == "sampling" ? 0 : s == "sorting" ? 1 : 2;
      progress->gaussians_total = total;
      progress->gaussians_done = (pass * total + std::min(done, total)) / 3;
    };
  }
  std::fprintf(stderr, "flashgs-viewer: building the LOD set of %s into %s (once: later opens read it from there)\n",
               printable_file_text(scene_file, kMaxPrintedPathBytes).c_str(), printable_file_text(folder, kMaxPrintedPathBytes).c_str());
  try {
    build_lod_set(scene_file, partial.string(), build);
    fs::rename(partial, target, error);
    if (error) {  // another viewer finished the same set first: keep theirs
      fs::remove_all(partial, error);
      if (!holds_set(folder)) throw Error(printable_file_text(folder, kMaxPrintedPathBytes) + ": cannot move the built LOD set there");
    }
  } catch (...) {
    fs::remove_all(partial, error);
    throw;
  }
  return true;
}

}  // namespace

LodCacheFolders lod_cache_folders(const std::string& scene_file, const LodBuildOptions& options) {
  std::error_code error;
  const fs::path file = fs::absolute(scene_file, error);
  const std::uintmax_t size = fs::file_size(file, error);
  if (error) throw Error(printable_file_text(scene_file, kMaxPrintedPathBytes) + ": cannot read its size: " + error.message());
  const auto mtime = fs::last_write_time(file, error).time_since_epoch().count();
  const std::string identity = file.lexically_normal().string() + "\n" + std::to_string(size) + "\n" + std::to_string(mtime) +
                               "\n" + std::to_string(options.leaf_gaussians) + "\n" + std::to_string(options.file_gaussians);
  char key[17];
  std::snprintf(key, sizeof key, "%016llx", static_cast<unsigned long long>(fnv1a(identity)));
  const std::string name = file.filename().string();
  return {(file.parent_path() / (name + ".lod-" + key)).string(), user_cache_root() + "/flashgs/lod/" + name + "-" + key};
}

CachedLodSet open_or_build_lod_cache(const std::string& scene_file, const LodBuildOptions& options, LoadProgress* progress) {
  const LodCacheFolders folders = lod_cache_folders(scene_file, options);
  CachedLodSet out;
  for (const std::string& folder : {folders.beside, folders.user})
    if (holds_set(folder)) {
      out.meta_path = (fs::path(folder) / "lod-meta.json").string();
      return out;
    }
  const auto start = std::chrono::steady_clock::now();
  for (const std::string& folder : {folders.beside, folders.user})
    if (build_into(scene_file, folder, options, progress)) {
      out.meta_path = (fs::path(folder) / "lod-meta.json").string();
      out.built = true;
      out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return out;
    }
  throw Error(printable_file_text(scene_file, kMaxPrintedPathBytes) + ": no writable place for its LOD set (tried " +
              printable_file_text(folders.beside, kMaxPrintedPathBytes) + " and " +
              printable_file_text(folders.user, kMaxPrintedPathBytes) + ")");
}

LoadedScene load_streamed_scene(const std::string& path, const std::string& cameras_path, LoadProgress* progress,
                                const LodBuildOptions& options) {
  const SceneLocation location = locate_scene(path);
  if (is_sog_lod_set(location.ply)) return load_scene(path, cameras_path, progress, kCoarsestLodLevel);
  const CachedLodSet set = open_or_build_lod_cache(location.ply, options, progress);
  const std::string scene = printable_file_text(location.ply, kMaxPrintedPathBytes),
                    meta = printable_file_text(set.meta_path, kMaxPrintedPathBytes);
  if (set.built)
    std::fprintf(stderr, "flashgs-viewer: built the LOD set of %s in %.1f s: %s\n", scene.c_str(), set.build_seconds, meta.c_str());
  else
    std::fprintf(stderr, "flashgs-viewer: opened the cached LOD set of %s: %s\n", scene.c_str(), meta.c_str());
  if (progress) {  // the set's own load starts its bar anew
    progress->gaussians_done = 0;
    progress->gaussians_total = 0;
    progress->bytes_done = 0;
    progress->bytes_total = 0;
  }
  return load_scene(set.meta_path, cameras_path.empty() ? location.cameras : cameras_path, progress, kCoarsestLodLevel);
}

}  // namespace flashgs::viewer
