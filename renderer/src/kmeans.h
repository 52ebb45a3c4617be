// k-means quantisation for SOG's writers: 256-entry codebooks of scalars, and palettes of
// SH coefficient vectors.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace flashgs {

// Up to `entries` values (sorted, distinct) that minimise the squared error of `values`
// rounded to the nearest of them, after `iterations` Lloyd passes from the quantiles (1D
// k-means is exact per pass on sorted data). Fewer when `values` has fewer distinct values.
std::vector<float> kmeans_1d(std::vector<float> values, std::size_t entries, int iterations);
// The index of the entry of `codebook` (sorted ascending) nearest to `v`.
std::uint8_t nearest_entry(const std::vector<float>& codebook, float v);

// A palette of vectors: `centroids` (`count` x `dimension`) and each point's label.
struct Palette {
  std::size_t count = 0;
  std::vector<float> centroids;
  std::vector<std::uint32_t> labels;
};
// Clusters `n` points of `dimension` floats (row-major) into at most `entries` clusters by
// splitting the cluster of largest squared error in two (2-means, `iterations` passes) until
// there are `entries`: n·dimension·iterations·log(entries) work, deterministic.
Palette kmeans_palette(const float* points, std::size_t n, int dimension, std::size_t entries, int iterations);

}  // namespace flashgs
