// The checks every scene reader applies to a decoded Gaussian, and the progress of decoding.
#include "format_readers.h"

#include <algorithm>
#include <cmath>

#include "flashgs/error.h"

namespace flashgs {

void append_gaussian(Scene& scene, const DecodedGaussian& g, const float* sh_rest, LoadReport& report) {
  // Every value is checked as the float it is kept as: a double of 1e300 is finite, its float is not.
  float position[3], scale[3], dc[3];
  bool finite = std::isfinite(static_cast<float>(g.opacity));
  for (int k = 0; k < 3; ++k) {
    position[k] = static_cast<float>(g.position[k]);
    scale[k] = static_cast<float>(g.scale[k]);
    dc[k] = static_cast<float>(g.sh_dc[k]);
    finite &= std::isfinite(position[k]) && std::isfinite(scale[k]) && std::isfinite(dc[k]);
  }
  const int rest_n = scene.sh_rest_per_gaussian();
  for (int k = 0; k < rest_n; ++k) finite &= std::isfinite(sh_rest[k]);
  double quat[4];
  for (int k = 0; k < 4; ++k) {
    quat[k] = g.rotation[k];
    finite &= std::isfinite(quat[k]);
  }
  if (!finite) {  // NaN/Inf in the file, a double beyond float range, or a scale whose exp overflowed
    report.dropped_non_finite++;
    return;
  }
  // Scaled by the largest component first: rotations of 1e300 (double PLY) would square to
  // infinity, yet they are a rotation like any other.
  double largest = 0.0;
  for (const double q : quat) largest = std::max(largest, std::abs(q));
  double norm = 0.0;
  if (largest > 0.0) {
    for (double& q : quat) q /= largest;
    norm = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  }
  if (!(norm > 0.0)) {
    // A zero quaternion has no rotation; 3DGS would divide by zero. Identity keeps the scales.
    report.repaired_zero_quaternion++;
    quat[0] = 1;
    quat[1] = quat[2] = quat[3] = 0;
    norm = 1;
  }
  scene.positions.insert(scene.positions.end(), position, position + 3);
  scene.scales.insert(scene.scales.end(), scale, scale + 3);
  scene.sh_dc.insert(scene.sh_dc.end(), dc, dc + 3);
  for (int k = 0; k < 4; ++k) scene.rotations.push_back(static_cast<float>(quat[k] / norm));
  scene.opacities.push_back(static_cast<float>(g.opacity));
  scene.sh_rest.insert(scene.sh_rest.end(), sh_rest, sh_rest + rest_n);
}

DecodeProgress::DecodeProgress(LoadProgress* progress, const std::string& name, std::size_t total)
    : m_progress(progress), m_name(name) {
  if (!m_progress) return;
  m_progress->gaussians_done.store(0, std::memory_order_relaxed);
  m_progress->gaussians_total.store(total, std::memory_order_relaxed);
}

void DecodeProgress::publish(std::size_t done) {
  m_progress->gaussians_done.store(done, std::memory_order_relaxed);
  if (m_progress->cancel_requested.load(std::memory_order_relaxed)) throw LoadCancelled(m_name);
}

void DecodeProgress::done(std::size_t total) {
  if (m_progress) m_progress->gaussians_done.store(total, std::memory_order_relaxed);
}

}  // namespace flashgs
