// A human-readable summary of a scene: counts, bounds, opacity and scale statistics.
#pragma once

#include <string>

#include "flashgs/scene.h"

namespace flashgs {

// Multi-line text for `flashgs info`; `report` (may be null) adds what the loader dropped.
std::string summarize_scene(const Scene& scene, const LoadReport* report);

}  // namespace flashgs
