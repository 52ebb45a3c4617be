// The cut through a LOD set for one view: per leaf cell, the level whose detail the view needs
// (projected error in pixels), within a budget of Gaussians; deterministic for a pose and budget.
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/lod_set.h"

namespace flashgs {

// The detail bound every program starts with. Coarse levels are merges whose look differs from
// their sources beyond their spacing: at 1 px the overview of a city fell to 29.8 dB against
// full detail, at 0.5 px its worst frame held 36.5 dB (docs/LOD.md, "Image quality").
constexpr float kDefaultLodMaxErrorPx = 0.5f;

struct LodCutOptions {
  std::uint64_t budget = 0;                     // Gaussians drawn at most; 0 = no limit
  float max_error_px = kDefaultLodMaxErrorPx;   // refine a leaf while its level's error is larger than this
  // A leaf drawn finer in the previous cut keeps that level until its coarser level's error
  // falls below max_error_px / hysteresis: a camera near a level boundary does not flicker.
  float hysteresis = 1.5f;
};

// The memory a cut's chunk files take: a chunk file holds the ranges of many leaves and is
// loaded whole, so a cut within the Gaussian budget can still need more files than fit. A cut
// given this uses only files that fit together; each is counted once however many leaves use it.
struct LodFileBudget {
  std::vector<std::uint64_t> bytes;  // per file of the set: what it takes in memory
  std::vector<bool> always_held;     // files held whatever the view: counted before any leaf
  std::uint64_t limit = 0;           // the most the cut's files may take together; 0 = no limit
};

struct LodCut {
  std::vector<int> level;       // per leaf: the level to draw, -1 = not drawn (outside the view, or over the budget)
  std::uint64_t gaussians = 0;  // drawn in total
  std::uint64_t file_bytes = 0; // the files the cut draws from, with those always held (given a file budget)
  float worst_error_px = 0;     // the largest error of a drawn leaf's level
  bool budget_bound = false;    // the budget stopped a refinement the error asked for
  bool files_bound = false;     // a refinement the error asked for needed a file that does not fit
};

// A leaf's error at `level` as `camera` sees it: the spacing of its Gaussians there
// (sqrt(half the cell's surface / count)) projected at the cell's distance; 0 at level 0.
float lod_leaf_error_px(const LodSet& set, int leaf, int level, const Camera& camera);
// Whether the leaf's cell, grown by a margin for the Gaussians' extent, is in the view.
bool lod_leaf_in_view(const LodSet& set, int leaf, const Camera& camera);

// Every leaf in view starts at its coarsest level; the leaf with the largest error is refined
// one level at a time while its error exceeds the bound and the budget allows, and (given
// `files`) while the file its finer level lies in fits. `previous` (may be null) gives the
// hysteresis its memory.
LodCut choose_lod_cut(const LodSet& set, const Camera& camera, const LodCutOptions& options,
                      const LodCut* previous = nullptr, const LodFileBudget* files = nullptr);

}  // namespace flashgs
