// The writer of each scene format, for the registry in scene_formats.cpp, and the helpers
// their quantisation shares.
#pragma once

#include <string>

#include "flashgs/scene.h"
#include "flashgs/scene_formats.h"

namespace flashgs {

// One writer per format (beside save_ply, io.h, and save_splat, scene_formats.h). Each writes
// whole or not at all and throws flashgs::Error naming the file and the problem.
void save_compressed_ply(const Scene& scene, const std::string& path, const SceneWriteOptions& options);
void save_spz(const Scene& scene, const std::string& path, const SceneWriteOptions& options);
// SOG v2: `path` is meta.json, the textures are written beside it.
void save_sog_folder(const Scene& scene, const std::string& path, const SceneWriteOptions& options);
// SOG v2 as one zip archive (.sog): meta.json and the textures, stored.
void save_sog_bundle(const Scene& scene, const std::string& path, const SceneWriteOptions& options);

// A value in [0, 1] to the nearest step of a `bits`-bit unsigned field, clamped.
unsigned quantise_unit(double t, int bits);
// `v` between `lo` and `hi` as a `bits`-bit field, to the nearest step (0 when lo == hi).
unsigned quantise_range(double v, double lo, double hi, int bits);

}  // namespace flashgs
