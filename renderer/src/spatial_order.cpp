// Spatial order of a scene's Gaussians (see spatial_order.h).
#include "flashgs/spatial_order.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace flashgs {
namespace {

// The order's grid: 128^3 cells. With 64^3, 200 shuffled copies of pc_playbot side by side
// (100M) kept cells of ~1/4 of a copy across, and their project stage took 0.44 ms against 0.31
// in PlayCanvas's own order (0.37 with 128^3; docs/PERFORMANCE.md).
constexpr int kCellBits = 7;
constexpr int kCellsPerAxis = 1 << kCellBits;
constexpr std::uint32_t kCells = 1u << (3 * kCellBits);
// The verdict's grid: 64^3 cells, every 2^3 of the order's cells one.
constexpr int kVerdictShift = kCellBits - 6;
constexpr std::uint32_t kVerdictCellsPerAxis = kCellsPerAxis >> kVerdictShift;
// Gaussians per thread at least: the passes are a few nanoseconds per Gaussian.
constexpr std::size_t kPerThread = 1 << 16;
// The verdict's unit: runs of this many consecutive Gaussians (the chunk cull's chunk, 8 warps
// of preprocess), kSampledRuns of them spread over the scene, measured by the most cells of the
// verdict grid that a run spans along an axis (the median over the sample).
constexpr std::size_t kRun = 256;
constexpr std::size_t kSampledRuns = 256;
// Runs that span at most this many cells need no order: those of the real scenes stored in
// spatial order span 2-7 at the median (pc_*), raw trainer output and shuffled scenes 54-63.
constexpr int kCompactSpan = 8;
// Otherwise the order is computed and kept where its runs span at most 1/kGainFactor of the
// stored ones. Small scenes (v3dg_donut, 45k Gaussians; kacytran_try, 9k) are sparse in the
// grid, so even ordered runs span 15-20 cells; comparing with random pairs' distance instead
// took shuffled scenes copied side by side for coherent once the copies were many (200 x
// pc_playbot: project 0.97 ms against 0.31, docs/PERFORMANCE.md).
constexpr int kGainFactor = 2;

bool finite_position(const Scene& scene, std::size_t i) {
  const float* p = &scene.positions[i * 3];
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

int host_threads(std::size_t n) {
#ifdef _OPENMP
  return static_cast<int>(std::clamp<std::size_t>(n / kPerThread, 1, omp_get_max_threads()));
#else
  (void)n;
  return 1;
#endif
}

// The low kCellBits bits of v, each moved to every third bit.
std::uint32_t spread(std::uint32_t v) {
  std::uint32_t out = 0;
  for (int b = 0; b < kCellBits; ++b) out |= ((v >> b) & 1u) << (3 * b);
  return out;
}

// The Morton cell of a position in the box [low, low + extent); non-finite positions: cell 0.
struct CellGrid {
  float low[3] = {0, 0, 0}, scale[3] = {0, 0, 0};

  CellGrid(const Scene& scene, int threads) {
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::numeric_limits<float>::max();
      hi[a] = std::numeric_limits<float>::lowest();
    }
    const std::int64_t n = static_cast<std::int64_t>(scene.size());
#pragma omp parallel for num_threads(threads) reduction(min : lo[:3]) reduction(max : hi[:3])
    for (std::int64_t i = 0; i < n; ++i) {
      if (!finite_position(scene, i)) continue;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], scene.positions[i * 3 + a]);
        hi[a] = std::max(hi[a], scene.positions[i * 3 + a]);
      }
    }
    for (int a = 0; a < 3; ++a) {
      if (!(lo[a] <= hi[a])) continue;  // no finite position
      low[a] = lo[a];
      const double extent = double(hi[a]) - lo[a];
      scale[a] = extent > 0 ? static_cast<float>(kCellsPerAxis / extent) : 0.0f;
    }
  }

  // The cell's coordinate along `axis` of a finite position.
  std::uint32_t coordinate(const Scene& scene, std::size_t i, int axis) const {
    const double q = (double(scene.positions[i * 3 + axis]) - low[axis]) * scale[axis];
    return static_cast<std::uint32_t>(std::clamp(q, 0.0, double(kCellsPerAxis - 1)));
  }

  std::uint32_t cell(const Scene& scene, std::size_t i) const {
    if (!finite_position(scene, i)) return 0;
    std::uint32_t code = 0;
    for (int a = 0; a < 3; ++a) code |= spread(coordinate(scene, i, a)) << a;
    return code;
  }
};

// The median over sampled runs of consecutive Gaussians (device order: scene Gaussian order[k],
// or k where `order` is empty) of the most cells a run spans along an axis.
int median_run_span(const Scene& scene, const CellGrid& grid, const std::vector<std::uint32_t>& order) {
  const std::size_t n = scene.size();
  std::vector<int> spans;
  for (std::size_t k = 0; k < kSampledRuns; ++k) {
    const std::size_t first = (n - kRun) * k / (kSampledRuns - 1);
    std::uint32_t low[3] = {kVerdictCellsPerAxis, kVerdictCellsPerAxis, kVerdictCellsPerAxis}, high[3] = {0, 0, 0};
    bool any = false;
    for (std::size_t place = first; place < first + kRun; ++place) {
      const std::size_t i = order.empty() ? place : order[place];
      if (!finite_position(scene, i)) continue;
      any = true;
      for (int a = 0; a < 3; ++a) {
        const std::uint32_t c = grid.coordinate(scene, i, a) >> kVerdictShift;
        low[a] = std::min(low[a], c);
        high[a] = std::max(high[a], c);
      }
    }
    if (any) spans.push_back(static_cast<int>(std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2]})));
  }
  if (spans.empty()) return 0;
  std::nth_element(spans.begin(), spans.begin() + spans.size() / 2, spans.end());
  return spans[spans.size() / 2];
}

std::vector<std::uint32_t> order_by_cells(const Scene& scene, const CellGrid& grid, int threads) {
  const std::size_t n = scene.size();
  // A counting sort by cell, each thread over a contiguous share: the places of a cell go to
  // the threads in share order, so the sort is stable and a cell keeps its scene order. Each
  // thread zeroes its own counts, and the places are summed over ranges of cells in parallel:
  // with 16 threads the counts take 128 MB.
  const std::unique_ptr<std::uint32_t[]> place(new std::uint32_t[static_cast<std::size_t>(threads) * kCells]);
  std::vector<std::uint32_t> range_total(static_cast<std::size_t>(threads) + 1, 0);
  std::vector<std::uint32_t> order(n);
#pragma omp parallel num_threads(threads)
  {
#ifdef _OPENMP
    const int t = omp_get_thread_num();
#else
    const int t = 0;
#endif
    const std::size_t lo = n * t / threads, hi = n * (t + 1) / threads;
    std::uint32_t* mine = &place[static_cast<std::size_t>(t) * kCells];
    std::fill(mine, mine + kCells, 0u);
    for (std::size_t i = lo; i < hi; ++i) ++mine[grid.cell(scene, i)];
#pragma omp barrier
    // This thread's range of cells: its Gaussians over every thread, then their places.
    const std::uint32_t c0 = static_cast<std::uint32_t>(std::uint64_t{kCells} * t / threads);
    const std::uint32_t c1 = static_cast<std::uint32_t>(std::uint64_t{kCells} * (t + 1) / threads);
    std::uint32_t total = 0;
    for (std::uint32_t c = c0; c < c1; ++c)
      for (int k = 0; k < threads; ++k) total += place[static_cast<std::size_t>(k) * kCells + c];
    range_total[t + 1] = total;
#pragma omp barrier
#pragma omp single
    for (int k = 0; k < threads; ++k) range_total[k + 1] += range_total[k];
    // (an implied barrier)
    std::uint32_t next = range_total[t];
    for (std::uint32_t c = c0; c < c1; ++c)
      for (int k = 0; k < threads; ++k) {
        std::uint32_t& slot = place[static_cast<std::size_t>(k) * kCells + c];
        const std::uint32_t count = slot;
        slot = next;
        next += count;
      }
#pragma omp barrier
    for (std::size_t i = lo; i < hi; ++i) order[mine[grid.cell(scene, i)]++] = static_cast<std::uint32_t>(i);
  }
  return order;
}

}  // namespace

std::vector<std::uint32_t> spatial_order(const Scene& scene) {
  const int threads = host_threads(scene.size());
  return order_by_cells(scene, CellGrid(scene, threads), threads);
}

std::vector<std::uint32_t> spatial_order_where_it_pays(const Scene& scene) {
  const std::size_t n = scene.size();
  if (n <= kRun) return {};  // one run: nothing to gain
  const int threads = host_threads(n);
  const CellGrid grid(scene, threads);
  const int stored = median_run_span(scene, grid, {});
  if (stored <= kCompactSpan) return {};
  std::vector<std::uint32_t> order = order_by_cells(scene, grid, threads);
  if (kGainFactor * median_run_span(scene, grid, order) > stored) return {};
  return order;
}

}  // namespace flashgs
