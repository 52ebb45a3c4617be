// Choosing the levels of a LOD set's leaves for a view: frustum test, projected error, budget.
#include "flashgs/lod_cut.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>

namespace flashgs {
namespace {

constexpr float kNear = 0.2f;         // the renderers' near plane
constexpr float kViewMargin = 0.25f;  // of a cell's diagonal: Gaussians reach beyond their centres' box

void to_view(const Camera& c, const float p[3], float v[3]) {
  const float d[3] = {p[0] - c.position[0], p[1] - c.position[1], p[2] - c.position[2]};
  for (int r = 0; r < 3; ++r) v[r] = c.rotation[r * 3] * d[0] + c.rotation[r * 3 + 1] * d[1] + c.rotation[r * 3 + 2] * d[2];
}

float distance_to_box(const LodBox& box, const float p[3]) {
  float d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const float below = box.min[k] - p[k], above = p[k] - box.max[k];
    const float d = std::max({below, above, 0.0f});
    d2 += d * d;
  }
  return std::sqrt(d2);
}

// The finest level below `level` that holds the leaf's Gaussians (-1: none).
int finer_level(const LodLeaf& leaf, int level) {
  for (int l = level - 1; l >= 0; --l)
    if (leaf.levels[static_cast<std::size_t>(l)].file >= 0) return l;
  return -1;
}

int coarsest_level(const LodLeaf& leaf) {
  for (int l = static_cast<int>(leaf.levels.size()) - 1; l >= 0; --l)
    if (leaf.levels[static_cast<std::size_t>(l)].file >= 0) return l;
  return -1;
}

// The files a cut draws from, each counted once, against a file budget (none: no limit).
class FileUse {
 public:
  FileUse(const LodFileBudget* budget, std::size_t files) : m_budget(budget) {
    if (!m_budget) return;
    m_users.assign(files, 0);
    for (std::size_t f = 0; f < files && f < m_budget->always_held.size(); ++f)
      if (m_budget->always_held[f]) m_bytes += bytes(static_cast<int>(f));
  }
  bool fits(int file) const {
    if (!m_budget || m_budget->limit == 0 || counted(file)) return true;
    return m_bytes + bytes(file) <= m_budget->limit;
  }
  void add(int file) {
    if (!m_budget) return;
    if (!counted(file)) m_bytes += bytes(file);
    ++m_users[static_cast<std::size_t>(file)];
  }
  void remove(int file) {
    if (!m_budget) return;
    --m_users[static_cast<std::size_t>(file)];
    if (!counted(file)) m_bytes -= bytes(file);
  }
  std::uint64_t total() const { return m_bytes; }

 private:
  bool held(int file) const {
    return static_cast<std::size_t>(file) < m_budget->always_held.size() && m_budget->always_held[static_cast<std::size_t>(file)];
  }
  bool counted(int file) const { return held(file) || m_users[static_cast<std::size_t>(file)] > 0; }
  std::uint64_t bytes(int file) const {
    return static_cast<std::size_t>(file) < m_budget->bytes.size() ? m_budget->bytes[static_cast<std::size_t>(file)] : 0;
  }

  const LodFileBudget* m_budget;
  std::vector<int> m_users;  // leaves of the cut drawing from each file
  std::uint64_t m_bytes = 0;
};

}  // namespace

float lod_leaf_error_px(const LodSet& set, int leaf, int level, const Camera& camera) {
  if (level <= 0) return 0.0f;
  const LodLeaf& l = set.leaves[static_cast<std::size_t>(leaf)];
  const std::uint64_t count = l.levels[static_cast<std::size_t>(level)].count;
  if (count == 0) return 0.0f;
  const float e[3] = {l.bound.max[0] - l.bound.min[0], l.bound.max[1] - l.bound.min[1], l.bound.max[2] - l.bound.min[2]};
  const float half_surface = e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
  const float spacing = std::sqrt(half_surface / static_cast<float>(count));
  const float distance = distance_to_box(l.bound, camera.position);
  if (distance <= 0.0f) return spacing > 0 ? std::numeric_limits<float>::infinity() : 0.0f;
  return spacing * std::max(camera.fx, camera.fy) / distance;
}

bool lod_leaf_in_view(const LodSet& set, int leaf, const Camera& camera) {
  const LodBox& b = set.leaves[static_cast<std::size_t>(leaf)].bound;
  float diagonal = 0;
  for (int k = 0; k < 3; ++k) diagonal += (b.max[k] - b.min[k]) * (b.max[k] - b.min[k]);
  const float margin = kViewMargin * std::sqrt(diagonal);
  // Outside when every corner is beyond one and the same plane of the view frustum.
  const float left = camera.cx + 0.5f, right = static_cast<float>(camera.width) - camera.cx - 0.5f;
  const float top = camera.cy + 0.5f, bottom = static_cast<float>(camera.height) - camera.cy - 0.5f;
  int outside[5] = {0, 0, 0, 0, 0};
  for (int corner = 0; corner < 8; ++corner) {
    const float p[3] = {corner & 1 ? b.max[0] + margin : b.min[0] - margin, corner & 2 ? b.max[1] + margin : b.min[1] - margin,
                        corner & 4 ? b.max[2] + margin : b.min[2] - margin};
    float v[3];
    to_view(camera, p, v);
    outside[0] += v[2] < kNear;
    outside[1] += v[0] * camera.fx < -v[2] * left;
    outside[2] += v[0] * camera.fx > v[2] * right;
    outside[3] += v[1] * camera.fy < -v[2] * top;
    outside[4] += v[1] * camera.fy > v[2] * bottom;
  }
  return std::none_of(outside, outside + 5, [](int n) { return n == 8; });
}

LodCut choose_lod_cut(const LodSet& set, const Camera& camera, const LodCutOptions& options, const LodCut* previous,
                      const LodFileBudget* files) {
  const int leaves = static_cast<int>(set.leaves.size());
  LodCut cut;
  FileUse used(files, set.files.size());
  cut.level.assign(static_cast<std::size_t>(leaves), -1);
  const std::uint64_t budget = options.budget ? options.budget : std::numeric_limits<std::uint64_t>::max();
  // The leaves in view at their coarsest level, the largest on screen first while the budget lasts.
  std::vector<std::pair<float, int>> visible;
  for (int leaf = 0; leaf < leaves; ++leaf) {
    const int coarse = coarsest_level(set.leaves[static_cast<std::size_t>(leaf)]);
    if (coarse >= 0 && lod_leaf_in_view(set, leaf, camera))
      visible.emplace_back(lod_leaf_error_px(set, leaf, coarse, camera), leaf);
  }
  std::sort(visible.begin(), visible.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  auto count_at = [&](int leaf, int level) {
    return set.leaves[static_cast<std::size_t>(leaf)].levels[static_cast<std::size_t>(level)].count;
  };
  auto file_at = [&](int leaf, int level) {
    return set.leaves[static_cast<std::size_t>(leaf)].levels[static_cast<std::size_t>(level)].file;
  };
  // Max-heap on (error, -leaf): equal errors refine the lower leaf index first.
  std::priority_queue<std::pair<float, int>> refine;
  auto bound_for = [&](int leaf, int finer) {
    const bool had_it = previous && previous->level.size() == cut.level.size() &&
                        previous->level[static_cast<std::size_t>(leaf)] >= 0 &&
                        previous->level[static_cast<std::size_t>(leaf)] <= finer;
    return had_it ? options.max_error_px / options.hysteresis : options.max_error_px;
  };
  auto consider = [&](int leaf) {
    const int level = cut.level[static_cast<std::size_t>(leaf)];
    const int finer = finer_level(set.leaves[static_cast<std::size_t>(leaf)], level);
    if (finer < 0) return;
    const float error = lod_leaf_error_px(set, leaf, level, camera);
    if (error > bound_for(leaf, finer)) refine.emplace(error, -leaf);
  };
  for (const auto& [error, leaf] : visible) {
    const int coarse = coarsest_level(set.leaves[static_cast<std::size_t>(leaf)]);
    if (cut.gaussians + count_at(leaf, coarse) > budget) {
      cut.budget_bound = true;
      continue;
    }
    if (!used.fits(file_at(leaf, coarse))) {
      cut.files_bound = true;
      continue;
    }
    cut.level[static_cast<std::size_t>(leaf)] = coarse;
    cut.gaussians += count_at(leaf, coarse);
    used.add(file_at(leaf, coarse));
  }
  for (int leaf = 0; leaf < leaves; ++leaf)
    if (cut.level[static_cast<std::size_t>(leaf)] >= 0) consider(leaf);
  while (!refine.empty()) {
    const int leaf = -refine.top().second;
    refine.pop();
    const int level = cut.level[static_cast<std::size_t>(leaf)];
    const int finer = finer_level(set.leaves[static_cast<std::size_t>(leaf)], level);
    const std::uint64_t total = cut.gaussians - count_at(leaf, level) + count_at(leaf, finer);
    if (total > budget) {
      cut.budget_bound = true;
      break;
    }
    if (!used.fits(file_at(leaf, finer))) {  // the leaf stays; others may refine within their files
      cut.files_bound = true;
      continue;
    }
    used.add(file_at(leaf, finer));
    used.remove(file_at(leaf, level));
    cut.gaussians = total;
    cut.level[static_cast<std::size_t>(leaf)] = finer;
    consider(leaf);
  }
  cut.file_bytes = used.total();
  for (int leaf = 0; leaf < leaves; ++leaf)
    if (cut.level[static_cast<std::size_t>(leaf)] >= 0)
      cut.worst_error_px = std::max(cut.worst_error_px, lod_leaf_error_px(set, leaf, cut.level[static_cast<std::size_t>(leaf)], camera));
  return cut;
}

}  // namespace flashgs
