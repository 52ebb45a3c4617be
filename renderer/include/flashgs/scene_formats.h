// The one entry point for scene files in every format the project reads; the format is chosen by content.
#pragma once

#include <string>

#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs {

// Reads the scene file at `path` (for now the INRIA PLY; each further format adds a reader
// behind this function). Throws flashgs::Error naming the file and the problem, or
// flashgs::LoadCancelled when `progress->cancel_requested` was set. `report` and `progress`
// may be null.
Scene load_scene_file(const std::string& path, LoadReport* report = nullptr,
                      LoadProgress* progress = nullptr);

}  // namespace flashgs
