// Percentiles of timing samples (see percentile.h).
#include "flashgs/percentile.h"

#include <algorithm>
#include <cmath>

namespace flashgs {

double percentile(std::vector<double> samples, double p) {
  if (samples.empty()) return 0.0;
  std::sort(samples.begin(), samples.end());
  const double position = std::clamp(p, 0.0, 1.0) * static_cast<double>(samples.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(position));
  const std::size_t hi = std::min(lo + 1, samples.size() - 1);
  return samples[lo] + (samples[hi] - samples[lo]) * (position - static_cast<double>(lo));
}

}  // namespace flashgs
