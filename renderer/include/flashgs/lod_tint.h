// The level overlay of a streamed LOD set: every drawn Gaussian coloured by the level it was
// drawn at, from one palette that the image and the viewer's legend share.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "flashgs/lod_set.h"
#include "flashgs/scene.h"
#include "flashgs/scene_parts.h"

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

// A tinted part's key: the untinted part's with the top bit set (LodStreamer's keys, a chunk
// file below 2^23 shifted by 40, never have it), so that a renderer holding parts by key never
// takes one for the other.
constexpr std::uint64_t kTintedPartKeyBit = std::uint64_t{1} << 63;

// Tinted copies of parts by tinted key: a part's copy is made once while cuts keep drawing it.
using TintedParts = std::unordered_map<std::uint64_t, std::shared_ptr<const Scene>>;

// The level overlay of a cut handed over as parts (LodStreamer::update_parts, whose drawn
// ranges give the runs): each part as a copy coloured by its run's level, keyed with
// kTintedPartKeyBit. A copy's DC colour is the level's colour and its view-dependent SH is
// dropped (SH degree 0), so that every view shows the palette. Copies come from `copies` where there and are added to it; copies of parts
// no longer in `parts` leave it. Throws flashgs::Error when the runs do not cover the parts
// exactly, a part spans two runs or a part's key already has the bit.
std::vector<ScenePart> tint_parts_by_level(const std::vector<ScenePart>& parts, const std::vector<LodLevelRun>& runs,
                                           TintedParts& copies);

}  // namespace flashgs
