// Scene statistics for `flashgs info` and the viewer.
#include "flashgs/scene_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/generators.h"

namespace flashgs {
namespace {

std::string quantiles(std::vector<float> values) {
  if (values.empty()) return "-";
  std::sort(values.begin(), values.end());
  auto at = [&](double q) { return values[static_cast<std::size_t>(q * (values.size() - 1))]; };
  char text[160];
  std::snprintf(text, sizeof text, "min %.3g  p10 %.3g  median %.3g  p90 %.3g  max %.3g", at(0), at(0.1),
                at(0.5), at(0.9), at(1.0));
  return text;
}

}  // namespace

std::string kernel_summary(const TrainedKernel& kernel) {
  return kernel.kernel.description() + " (" + (kernel.marked() ? "from the " + kernel.source : "no mark in the file") + ")";
}

std::string summarize_scene(const Scene& scene, const LoadReport* report) {
  std::ostringstream out;
  const std::size_t n = scene.size();
  if (report) out << "file:            " << printable_file_text(report->path, kMaxPrintedPathBytes) << "\n";
  if (report && !report->format.empty()) {
    char times[120];
    std::snprintf(times, sizeof times, "read %.3f s, decoded in %.3f s\n", report->read_seconds,
                  report->decode_seconds);
    out << "format:          " << report->format << "\n";
    out << "quantisation:    " << report->quantisation << "\n";
    out << "load time:       " << times;
  }
  out << "gaussians:       " << n << "\n";
  out << "sh degree:       " << scene.sh_degree << " (" << sh_coefficient_count(scene.sh_degree)
      << " coefficients per channel)\n";
  out << "kernel:          " << kernel_summary(scene.trained_kernel) << "\n";
  out << "memory:          " << scene.byte_size() / 1e6 << " MB (" << scene.byte_size() / std::max<std::size_t>(n, 1)
      << " bytes per Gaussian)\n";
  float lo[3], hi[3];
  scene_bounds(scene, lo, hi);
  char line[200];
  std::snprintf(line, sizeof line, "bounds:          [%.3g, %.3g, %.3g] .. [%.3g, %.3g, %.3g]\n", lo[0], lo[1], lo[2],
                hi[0], hi[1], hi[2]);
  out << line;
  std::vector<float> largest(n), anisotropy(n), smallest(n);
  std::size_t low_opacity = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const float* s = &scene.scales[i * 3];
    const float mx = std::max({s[0], s[1], s[2]}), mn = std::min({s[0], s[1], s[2]});
    largest[i] = mx;
    smallest[i] = mn;
    anisotropy[i] = mn > 0 ? mx / mn : INFINITY;
    low_opacity += scene.opacities[i] < 0.35f;
  }
  out << "opacity:         " << quantiles(scene.opacities) << "\n";
  std::snprintf(line, sizeof line, "                 %.1f%% below 0.35\n", 100.0 * low_opacity / std::max<std::size_t>(n, 1));
  out << line;
  out << "largest scale:   " << quantiles(largest) << "\n";
  out << "smallest scale:  " << quantiles(smallest) << "\n";
  out << "anisotropy:      " << quantiles(anisotropy) << "\n";
  if (report) {
    out << "in file:         " << report->vertices_in_file << " vertices\n";
    out << "dropped:         " << report->dropped_non_finite << " with NaN/Inf attributes (or exp(scale) overflow)\n";
    out << "repaired:        " << report->repaired_zero_quaternion << " zero quaternions set to identity\n";
    out << "ignored:         " << report->ignored_properties << " properties";
    for (std::size_t i = 0; i < report->ignored_property_names.size() && i < 8; ++i)
      out << (i ? ", " : " (") << printable_file_text(report->ignored_property_names[i]);  // names from the header
    if (!report->ignored_property_names.empty()) out << (report->ignored_property_names.size() > 8 ? ", ...)" : ")");
    out << "\n";
  }
  return out.str();
}

}  // namespace flashgs
