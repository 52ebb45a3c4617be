// k-means for SOG's codebooks and SH palette (see kmeans.h).
#include "kmeans.h"

#include <algorithm>
#include <cmath>
#include <queue>

namespace flashgs {

std::vector<float> kmeans_1d(std::vector<float> values, std::size_t entries, int iterations) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return {0.0f};
  // Prefix sums make each cluster's mean O(1) once its bounds are found by binary search.
  std::vector<double> prefix(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + values[i];
  std::vector<double> centres;
  // The quantiles, and the two extremes: a few outliers (a saturated colour, a huge Gaussian)
  // keep entries of their own instead of taking the nearest of the bulk's.
  centres.push_back(values.front());
  for (std::size_t e = 0; e + 2 < entries; ++e) centres.push_back(values[std::min(n - 1, (2 * e + 1) * n / (2 * (entries - 2)))]);
  centres.push_back(values.back());
  for (int pass = 0; pass < iterations; ++pass) {
    centres.erase(std::unique(centres.begin(), centres.end()), centres.end());
    std::vector<double> next;
    std::size_t first = 0;
    for (std::size_t c = 0; c < centres.size(); ++c) {
      std::size_t last = n;
      if (c + 1 < centres.size()) {
        const double boundary = 0.5 * (centres[c] + centres[c + 1]);
        last = static_cast<std::size_t>(std::upper_bound(values.begin(), values.end(), boundary) - values.begin());
      }
      if (last > first) next.push_back((prefix[last] - prefix[first]) / double(last - first));
      first = std::max(first, last);
    }
    centres.swap(next);
  }
  centres.erase(std::unique(centres.begin(), centres.end()), centres.end());
  std::vector<float> codebook;
  for (double c : centres) codebook.push_back(static_cast<float>(c));
  std::sort(codebook.begin(), codebook.end());
  codebook.erase(std::unique(codebook.begin(), codebook.end()), codebook.end());
  return codebook;
}

std::uint8_t nearest_entry(const std::vector<float>& codebook, float v) {
  const auto above = std::lower_bound(codebook.begin(), codebook.end(), v);
  if (above == codebook.begin()) return 0;
  if (above == codebook.end()) return static_cast<std::uint8_t>(codebook.size() - 1);
  const auto below = above - 1;
  return static_cast<std::uint8_t>((v - *below <= *above - v ? below : above) - codebook.begin());
}

namespace {

struct Cluster {
  std::vector<std::uint32_t> members;
  std::vector<double> mean;
  double error = 0;  // sum of squared distances to the mean
};

double distance2(const float* p, const double* c, int dimension) {
  double d = 0;
  for (int k = 0; k < dimension; ++k) {
    const double t = p[k] - c[k];
    d += t * t;
  }
  return d;
}

void finish(Cluster& cluster, const float* points, int dimension) {
  cluster.mean.assign(static_cast<std::size_t>(dimension), 0.0);
  for (std::uint32_t i : cluster.members)
    for (int k = 0; k < dimension; ++k) cluster.mean[k] += points[std::size_t(i) * dimension + k];
  for (double& m : cluster.mean) m /= double(cluster.members.size());
  cluster.error = 0;
  for (std::uint32_t i : cluster.members) cluster.error += distance2(points + std::size_t(i) * dimension, cluster.mean.data(), dimension);
}

// 2-means seeded with the member farthest from the mean and the member farthest from that one.
bool split(const Cluster& cluster, const float* points, int dimension, int iterations, Cluster& a, Cluster& b) {
  auto farthest_from = [&](const double* c) {
    std::uint32_t best = cluster.members[0];
    double best_d = -1;
    for (std::uint32_t i : cluster.members) {
      const double d = distance2(points + std::size_t(i) * dimension, c, dimension);
      if (d > best_d) best_d = d, best = i;
    }
    return best;
  };
  const std::uint32_t s1 = farthest_from(cluster.mean.data());
  std::vector<double> c1(points + std::size_t(s1) * dimension, points + std::size_t(s1 + 1) * dimension);
  const std::uint32_t s2 = farthest_from(c1.data());
  std::vector<double> c2(points + std::size_t(s2) * dimension, points + std::size_t(s2 + 1) * dimension);
  for (int pass = 0; pass < std::max(1, iterations); ++pass) {
    a.members.clear();
    b.members.clear();
    for (std::uint32_t i : cluster.members) {
      const float* p = points + std::size_t(i) * dimension;
      (distance2(p, c1.data(), dimension) <= distance2(p, c2.data(), dimension) ? a : b).members.push_back(i);
    }
    if (a.members.empty() || b.members.empty()) return false;
    finish(a, points, dimension);
    finish(b, points, dimension);
    c1 = a.mean;
    c2 = b.mean;
  }
  return true;
}

}  // namespace

Palette kmeans_palette(const float* points, std::size_t n, int dimension, std::size_t entries, int iterations) {
  auto larger_error = [](const Cluster& x, const Cluster& y) { return x.error < y.error; };
  std::priority_queue<Cluster, std::vector<Cluster>, decltype(larger_error)> open(larger_error);
  std::vector<Cluster> done;
  Cluster all;
  for (std::size_t i = 0; i < n; ++i) all.members.push_back(static_cast<std::uint32_t>(i));
  finish(all, points, dimension);
  open.push(std::move(all));
  while (!open.empty() && open.size() + done.size() < entries) {
    Cluster top = open.top();
    open.pop();
    Cluster a, b;
    if (top.error <= 0 || !split(top, points, dimension, iterations, a, b)) {
      done.push_back(std::move(top));  // all its members are equal
      continue;
    }
    open.push(std::move(a));
    open.push(std::move(b));
  }
  while (!open.empty()) {
    done.push_back(open.top());
    open.pop();
  }
  Palette palette;
  palette.count = done.size();
  palette.labels.assign(n, 0);
  for (std::size_t c = 0; c < done.size(); ++c) {
    for (double m : done[c].mean) palette.centroids.push_back(static_cast<float>(m));
    for (std::uint32_t i : done[c].members) palette.labels[i] = static_cast<std::uint32_t>(c);
  }
  return palette;
}

}  // namespace flashgs
