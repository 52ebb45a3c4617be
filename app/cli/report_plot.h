// Error-against-run-time plot of a sweep as a hand-written SVG (no plotting dependency).
#pragma once

#include <string>
#include <vector>

#include "report_sweep.h"

namespace flashgs::cli {

// Indices of the results on the Pareto front: no other result is both faster (median) and
// more accurate (higher PSNR against the fp64 reference).
std::vector<std::size_t> pareto_front(const std::vector<SweepResult>& results);

// One point per configuration: x = median frame time (ms), y = PSNR against the fp64
// reference (dB); the Pareto front is drawn as a line through filled points.
std::string plot_svg(const std::vector<SweepResult>& results, const std::string& title, const std::string& subtitle);

}  // namespace flashgs::cli
