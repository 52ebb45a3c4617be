// The level overlay of a streamed LOD set: every drawn Gaussian coloured by the level it was
// drawn at, from one palette that the image and the viewer's legend share.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "flashgs/lod_set.h"
#include "flashgs/scene.h"

namespace flashgs {

// A run of consecutive Gaussians of a drawn scene that come from one level (0 the finest).
struct LodLevelRun {
  int level = 0;
  std::uint64_t count = 0;
};

// The levels of a drawn scene made of `ranges` of `set`'s chunk files, one after another: a
// chunk file holds one level. Throws flashgs::Error naming the set when a range's file is not
// one level's.
std::vector<LodLevelRun> lod_level_runs(const LodSet& set, const std::vector<LodRange>& ranges);

// The overlay's colour of `level` (linear RGB in [0, 1]); the palette repeats after
// lod_palette_size() levels.
std::array<float, 3> lod_level_colour(int level);
int lod_palette_size();

// A copy of `scene` whose Gaussians are coloured by their run's level: the DC colour becomes the
// level's colour and the view-dependent SH is dropped (SH degree 0), so that every view shows
// the palette. Throws flashgs::Error when the runs do not cover the scene exactly.
Scene tint_by_level(const Scene& scene, const std::vector<LodLevelRun>& runs);

}  // namespace flashgs
