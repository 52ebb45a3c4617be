// The level overlay: a per-level palette and a drawn scene recoloured by it.
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

Scene tint_by_level(const Scene& scene, const std::vector<LodLevelRun>& runs) {
  std::uint64_t covered = 0;
  for (const LodLevelRun& r : runs) covered += r.count;
  if (covered != scene.size())
    throw Error("level overlay: the level runs cover " + std::to_string(covered) + " Gaussians, the drawn scene has " +
                std::to_string(scene.size()));
  Scene out;
  out.sh_degree = 0;
  out.trained_kernel = scene.trained_kernel;
  out.positions = scene.positions;
  out.scales = scene.scales;
  out.rotations = scene.rotations;
  out.opacities = scene.opacities;
  out.sh_dc.resize(scene.sh_dc.size());
  std::size_t at = 0;
  for (const LodLevelRun& r : runs) {
    const std::array<float, 3> colour = lod_level_colour(r.level);
    float dc[3];  // the renderer's colour is 0.5 + C0 * dc
    for (int k = 0; k < 3; ++k) dc[k] = static_cast<float>((colour[static_cast<std::size_t>(k)] - 0.5) / model::kShC0);
    for (std::uint64_t i = 0; i < r.count; ++i, ++at)
      for (int k = 0; k < 3; ++k) out.sh_dc[at * 3 + static_cast<std::size_t>(k)] = dc[k];
  }
  return out;
}

}  // namespace flashgs
