// A scene file streamed by view in the viewer: its LOD set built on first open into a cache
// folder, and opened from there (without building again) next time.
#pragma once

#include <cstdint>
#include <string>

#include "flashgs/load_progress.h"
#include "flashgs/lod_build.h"
#include "scene_state.h"

namespace flashgs::viewer {

// The cache folders for `scene_file`'s set, in the order they are tried: beside the file
// ("<file name>.lod-<key>") and in the user's cache ($XDG_CACHE_HOME, else ~/.cache:
// "flashgs/lod/<file name>-<key>"). The key is a hash of the file's absolute path, size and
// modification time and of the options' leaf and chunk sizes, so that a changed file or other
// sizes build anew.
struct LodCacheFolders {
  std::string beside, user;
};
LodCacheFolders lod_cache_folders(const std::string& scene_file, const LodBuildOptions& options);

struct CachedLodSet {
  std::string meta_path;  // the set's lod-meta.json
  bool built = false;     // built now (else found in the cache)
  double build_seconds = 0;
};
// The set for `scene_file`: a cached one, else built now (into a temporary folder renamed once
// complete; beside the file when its folder is writable, else in the user's cache). `progress`
// (may be null) shows the build's three passes as one run over the scene's Gaussians; its
// cancel flag stops the build (flashgs::LoadCancelled). Throws flashgs::Error naming the file.
CachedLodSet open_or_build_lod_cache(const std::string& scene_file, const LodBuildOptions& options, LoadProgress* progress);

// What `--stream` opens: a LOD set at its coarsest level (the view streaming starts from), or
// any other scene through its cached set (built first when there is none). The cameras are the
// scene's own (or `cameras_path`).
LoadedScene load_streamed_scene(const std::string& path, const std::string& cameras_path, LoadProgress* progress,
                                const LodBuildOptions& options);

}  // namespace flashgs::viewer
