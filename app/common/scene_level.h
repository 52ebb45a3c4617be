// Loading a scene file, or one level of a SOG LOD set, for the CLI and the Python module.
#pragma once

#include <string>

#include "flashgs/scene.h"
#include "flashgs/scene_formats.h"

namespace flashgs {

// Reads the scene file into `report`'s scene: a SOG LOD set at level `lod` (-1: the finest
// that fits in memory; the choice is printed to stderr); `lod` >= 0 for any other scene is an error.
Scene load_scene_at_level(const std::string& path, int lod, LoadReport* report, const SceneReadOptions& options = {});

}  // namespace flashgs
