// Spatial order of a scene's Gaussians (see spatial_order.h).
#include "flashgs/spatial_order.h"

#include <algorithm>
#include <cmath>
#include <limits>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace flashgs {
namespace {

constexpr int kCellBits = 6;  // per axis: 64^3 cells
constexpr std::uint32_t kCells = 1u << (3 * kCellBits);
constexpr std::size_t kSamples = 4096;
// Gaussians per thread at least: the passes are a few nanoseconds per Gaussian.
constexpr std::size_t kPerThread = 1 << 16;
// Mean distances of consecutive Gaussians below this fraction of random pairs' mean distance
// make a scene coherent: pc_playbot's is 0.008, its random order's about 1.
constexpr double kCoherentRatio = 0.1;

bool finite_position(const Scene& scene, std::size_t i) {
  const float* p = &scene.positions[i * 3];
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

double distance(const Scene& scene, std::size_t a, std::size_t b) {
  const float* p = &scene.positions[a * 3];
  const float* q = &scene.positions[b * 3];
  const double dx = double(p[0]) - q[0], dy = double(p[1]) - q[1], dz = double(p[2]) - q[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
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
      scale[a] = extent > 0 ? static_cast<float>((1 << kCellBits) / extent) : 0.0f;
    }
  }

  std::uint32_t cell(const Scene& scene, std::size_t i) const {
    if (!finite_position(scene, i)) return 0;
    std::uint32_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double q = (double(scene.positions[i * 3 + a]) - low[a]) * scale[a];
      const auto c = static_cast<std::uint32_t>(std::clamp(q, 0.0, double((1 << kCellBits) - 1)));
      code |= spread(c) << a;
    }
    return code;
  }
};

}  // namespace

bool spatially_coherent(const Scene& scene) {
  const std::size_t n = scene.size();
  if (n < 2) return true;
  double near = 0, far = 0;
  std::size_t near_count = 0, far_count = 0;
  std::uint64_t state = 0x9e3779b97f4a7c15ull;  // a fixed sequence: the same verdict every time
  auto draw = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<std::size_t>((state >> 33) % n);
  };
  for (std::size_t k = 0; k < kSamples; ++k) {
    const std::size_t i = (n - 1) * k / kSamples;
    if (finite_position(scene, i) && finite_position(scene, i + 1)) {
      near += distance(scene, i, i + 1);
      ++near_count;
    }
    const std::size_t a = draw(), b = draw();
    if (finite_position(scene, a) && finite_position(scene, b)) {
      far += distance(scene, a, b);
      ++far_count;
    }
  }
  if (near_count == 0 || far_count == 0 || !(far > 0)) return true;
  return near / near_count < kCoherentRatio * (far / far_count);
}

std::vector<std::uint32_t> spatial_order(const Scene& scene) {
  const std::size_t n = scene.size();
#ifdef _OPENMP
  const int threads = static_cast<int>(std::clamp<std::size_t>(n / kPerThread, 1, omp_get_max_threads()));
#else
  const int threads = 1;
#endif
  const CellGrid grid(scene, threads);
  // A counting sort by cell, each thread over a contiguous share: the places of a cell go to
  // the threads in share order, so the sort is stable and a cell keeps its scene order.
  std::vector<std::uint32_t> place(static_cast<std::size_t>(threads) * kCells, 0);  // [thread][cell]
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
    for (std::size_t i = lo; i < hi; ++i) ++mine[grid.cell(scene, i)];
#pragma omp barrier
#pragma omp single
    {
      std::uint32_t next = 0;
      for (std::uint32_t c = 0; c < kCells; ++c)
        for (int k = 0; k < threads; ++k) {
          const std::uint32_t count = place[static_cast<std::size_t>(k) * kCells + c];
          place[static_cast<std::size_t>(k) * kCells + c] = next;
          next += count;
        }
    }  // (an implied barrier)
    for (std::size_t i = lo; i < hi; ++i) order[mine[grid.cell(scene, i)]++] = static_cast<std::uint32_t>(i);
  }
  return order;
}

}  // namespace flashgs
