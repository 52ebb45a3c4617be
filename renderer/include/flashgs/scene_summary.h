// A human-readable summary of a scene: counts, bounds, opacity and scale statistics.
#pragma once

#include <string>

#include "flashgs/scene.h"

namespace flashgs {

// The kernel a scene was trained with and where that came from: "antialiased (eps 0.1) (from the
// PLY property filter_3D ...)", or "classic (no mark in the file)".
std::string kernel_summary(const TrainedKernel& kernel);

// Multi-line text for `flashgs info`; `report` (may be null) adds what the loader dropped.
std::string summarize_scene(const Scene& scene, const LoadReport* report);

}  // namespace flashgs
