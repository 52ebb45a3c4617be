// The one order-statistics rule of every timing summary (bench, report, the viewer).
#pragma once

#include <utility>
#include <vector>

namespace flashgs {

// The tail every timing summary reports next to the median ("p95").
constexpr double kTailPercentile = 0.95;

// The p-quantile (0 <= p <= 1) of `samples`, interpolated linearly between the two nearest
// ranks (so the median of an even count is the mean of the middle two); 0 when empty.
double percentile(std::vector<double> samples, double p);
inline double median(std::vector<double> samples) { return percentile(std::move(samples), 0.5); }

}  // namespace flashgs
