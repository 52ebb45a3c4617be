// A scene file streamed by view in the viewer: its LOD set built on first open into a cache
// folder, and opened from there (without building again) next time.
#pragma once

#include <cstdint>
#include <string>

#include "flashgs/load_progress.h"
#include "scene_state.h"

namespace flashgs::viewer {

struct LodCacheOptions {
  std::uint64_t leaf_gaussians = 16384;    // as `flashgs lod build --leaf-size`
  std::uint64_t file_gaussians = 262144;   // as --file-size
  std::uint64_t memory_bytes = 2ull << 30; // as --memory
};

// The cache folders for `scene_file`'s set, in the order they are tried: beside the file
// ("<file name>.lod-<key>") and in the user's cache ($XDG_CACHE_HOME, else ~/.cache:
// "flashgs/lod/<file name>-<key>"). The key is a hash of the file's absolute path, size and
// modification time and of the options, so that a changed file or other options build anew.
struct LodCacheFolders {
  std::string beside, user;
};
LodCacheFolders lod_cache_folders(const std::string& scene_file, const LodCacheOptions& options);

struct CachedLodSet {
  std::string meta_path;  // the set's lod-meta.json
  bool built = false;     // built now (else found in the cache)
  double build_seconds = 0;
};
// The set for `scene_file`: a cached one, else built now (into a temporary folder renamed once
// complete; beside the file when its folder is writable, else in the user's cache). `progress`
// (may be null) shows the build's passes as Gaussians done of three times the scene's; its
// cancel flag stops the build (flashgs::LoadCancelled). Throws flashgs::Error naming the file.
CachedLodSet open_or_build_lod_cache(const std::string& scene_file, const LodCacheOptions& options, LoadProgress* progress);

// What `--stream` opens: a LOD set at its coarsest level (the view streaming starts from), or
// any other scene through its cached set (built first when there is none). The cameras are the
// scene's own (or `cameras_path`).
LoadedScene load_streamed_scene(const std::string& path, const std::string& cameras_path, LoadProgress* progress,
                                const LodCacheOptions& options);

}  // namespace flashgs::viewer
