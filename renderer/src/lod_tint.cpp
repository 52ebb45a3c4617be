// The level overlay: a per-level palette and a drawn cut's parts recoloured by it.
#include "flashgs/lod_tint.h"

#include <string>

#include "flashgs/error.h"
#include "flashgs/model_constants.h"

namespace flashgs {
namespace {

// Far apart in hue, finest (red) to coarsest (violet), then pink for an eighth level.
constexpr std::array<std::array<float, 3>, 8> kPalette = {{{0.90f, 0.15f, 0.15f},
                                                           {0.95f, 0.55f, 0.05f},
                                                           {0.90f, 0.90f, 0.10f},
                                                           {0.15f, 0.80f, 0.20f},
                                                           {0.10f, 0.80f, 0.90f},
                                                           {0.20f, 0.30f, 0.95f},
                                                           {0.65f, 0.25f, 0.95f},
                                                           {0.95f, 0.40f, 0.75f}}};

// Appends Gaussians [first, first + count) of `from` to `out` (SH degree 0) in `level`'s colour.
void append_tinted(const Scene& from, std::size_t first, std::size_t count, int level, Scene& out) {
  const auto append = [&](std::vector<float>& to, const std::vector<float>& values, std::size_t per_gaussian) {
    to.insert(to.end(), values.begin() + static_cast<std::ptrdiff_t>(first * per_gaussian),
              values.begin() + static_cast<std::ptrdiff_t>((first + count) * per_gaussian));
  };
  append(out.positions, from.positions, 3);
  append(out.scales, from.scales, 3);
  append(out.rotations, from.rotations, 4);
  append(out.opacities, from.opacities, 1);
  const std::array<float, 3> colour = lod_level_colour(level);
  float dc[3];  // the renderer's colour is 0.5 + C0 * dc
  for (int k = 0; k < 3; ++k) dc[k] = static_cast<float>((colour[static_cast<std::size_t>(k)] - 0.5) / model::kShC0);
  for (std::size_t i = 0; i < count; ++i) out.sh_dc.insert(out.sh_dc.end(), dc, dc + 3);
}

}  // namespace

int lod_palette_size() { return static_cast<int>(kPalette.size()); }

std::array<float, 3> lod_level_colour(int level) {
  const int n = lod_palette_size();
  return kPalette[static_cast<std::size_t>(((level % n) + n) % n)];
}

std::vector<LodLevelRun> lod_level_runs(const LodSet& set, const std::vector<LodRange>& ranges) {
  std::vector<int> level_of(set.files.size(), -1);
  for (const LodLeaf& leaf : set.leaves)
    for (std::size_t level = 0; level < leaf.levels.size(); ++level) {
      const int file = leaf.levels[level].file;
      if (file < 0 || static_cast<std::size_t>(file) >= level_of.size()) continue;  // read_lod_set refuses these
      int& known = level_of[static_cast<std::size_t>(file)];
      if (known >= 0 && known != static_cast<int>(level))
        throw Error(printable_file_text(set.meta_path, kMaxPrintedPathBytes) + ": chunk file " + std::to_string(file) +
                    " holds levels " + std::to_string(known) + " and " + std::to_string(level));
      known = static_cast<int>(level);
    }
  std::vector<LodLevelRun> runs;
  for (const LodRange& r : ranges) {
    const bool known = r.file >= 0 && static_cast<std::size_t>(r.file) < level_of.size();
    const int level = known ? level_of[static_cast<std::size_t>(r.file)] : -1;
    if (level < 0)
      throw Error(printable_file_text(set.meta_path, kMaxPrintedPathBytes) + ": a drawn range names chunk file " +
                  std::to_string(r.file) + ", which no level holds");
    if (runs.empty() || runs.back().level != level) runs.push_back({level, 0});
    runs.back().count += r.count;
  }
  return runs;
}

std::vector<ScenePart> tint_parts_by_level(const std::vector<ScenePart>& parts, const std::vector<LodLevelRun>& runs,
                                           TintedParts& copies) {
  std::uint64_t covered = 0;
  for (const LodLevelRun& r : runs) covered += r.count;
  if (covered != scene_parts_size(parts))
    throw Error("level overlay: the level runs cover " + std::to_string(covered) + " Gaussians, the drawn parts have " +
                std::to_string(scene_parts_size(parts)));
  std::vector<ScenePart> tinted;
  tinted.reserve(parts.size());
  TintedParts kept;
  std::size_t run = 0;
  std::uint64_t left_in_run = runs.empty() ? 0 : runs[0].count;
  for (const ScenePart& part : parts) {
    if (part.key & kTintedPartKeyBit) throw Error("level overlay: a part's key " + std::to_string(part.key) + " has the tint bit");
    while (left_in_run == 0 && run + 1 < runs.size()) left_in_run = runs[++run].count;
    if (part.count > left_in_run)
      throw Error("level overlay: a part of " + std::to_string(part.count) + " Gaussians spans two levels' runs");
    left_in_run -= part.count;
    const std::uint64_t key = part.key | kTintedPartKeyBit;
    std::shared_ptr<const Scene>& copy = kept[key];
    if (!copy) {
      const auto known = copies.find(key);
      if (known != copies.end()) {
        copy = known->second;
      } else {
        auto made = std::make_shared<Scene>();
        made->trained_kernel = part.source->trained_kernel;
        made->reserve(part.count);
        append_tinted(*part.source, part.first, part.count, runs[run].level, *made);
        copy = std::move(made);
      }
    }
    tinted.push_back(ScenePart{key, copy, 0, part.count});
  }
  copies = std::move(kept);
  return tinted;
}

}  // namespace flashgs
