// Moment-matching merges of Gaussians (Hierarchical 3DGS's rule) for the coarser LOD levels.
#include "lod_merge.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "flashgs/rotation.h"

namespace flashgs {
namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

Mat3 rotation_of(const float* q_in) {
  const double q[4] = {q_in[0], q_in[1], q_in[2], q_in[3]};
  double m[9];
  matrix_from_quaternion(q, m);
  return Mat3{{{m[0], m[1], m[2]}, {m[3], m[4], m[5]}, {m[6], m[7], m[8]}}};
}

// Jacobi eigen-decomposition of a symmetric 3x3 matrix: a = V diag(values) V^T, V's columns
// the eigenvectors.
void symmetric_eigen(Mat3 a, std::array<double, 3>& values, Mat3& v) {
  v = Mat3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (int sweep = 0; sweep < 32; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double scale = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-30 * scale || off == 0.0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a = J^T a J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq;
          v[k][q] = s * vkp + c * vkq;
        }
      }
  }
  for (int k = 0; k < 3; ++k) values[k] = a[k][k];
}

double section_area(double s0, double s1, double s2) { return s0 * s1 + s1 * s2 + s2 * s0; }

// Orders `ids` so that each pair at an even index holds near neighbours: the group is split at
// an even count along its box's longest axis (ties by index, so the order is the same
// everywhere), and each half again, down to pairs. A Morton curve's neighbours, paired before,
// can lie on either side of one of its jumps.
void order_in_pairs(const Scene& scene, std::uint32_t* ids, std::size_t n) {
  if (n <= 2) return;
  const int axis = longest_axis(scene.positions, ids, n, nullptr);
  const std::size_t half = (n / 2 + 1) & ~std::size_t{1};  // even (pairs never straddle the split), 2..n-1
  std::nth_element(ids, ids + half, ids + n, [&](std::uint32_t a, std::uint32_t b) {
    const float pa = scene.positions[a * 3 + axis], pb = scene.positions[b * 3 + axis];
    return pa != pb ? pa < pb : a < b;
  });
  order_in_pairs(scene, ids, half);
  order_in_pairs(scene, ids + half, n - half);
}

}  // namespace

int longest_axis(const std::vector<float>& xyz, const std::uint32_t* ids, std::size_t n, float* length) {
  float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), std::numeric_limits<float>::max()};
  float hi[3] = {std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest()};
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], xyz[ids[i] * 3 + k]);
      hi[k] = std::max(hi[k], xyz[ids[i] * 3 + k]);
    }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  if (length) *length = hi[axis] - lo[axis];
  return axis;
}

double merge_weight(const Scene& scene, std::size_t i) {
  const float* s = &scene.scales[i * 3];
  return scene.opacities[i] * section_area(s[0], s[1], s[2]);
}

void append_merged(const Scene& scene, const std::uint32_t* indices, std::size_t count, Scene& out) {
  const int rest_n = scene.sh_rest_per_gaussian();
  std::vector<double> weights(count);
  double total = 0;
  for (std::size_t j = 0; j < count; ++j) total += weights[j] = merge_weight(scene, indices[j]);
  if (!(total > 0)) {  // all transparent or flat: plain means
    std::fill(weights.begin(), weights.end(), 1.0);
    total = static_cast<double>(count);
  }
  std::array<double, 3> mean{};
  for (std::size_t j = 0; j < count; ++j)
    for (int k = 0; k < 3; ++k) mean[k] += weights[j] * scene.positions[indices[j] * 3 + k];
  for (double& m : mean) m /= total;
  Mat3 cov{};
  std::vector<double> colour(static_cast<std::size_t>(3 + rest_n), 0.0);
  for (std::size_t j = 0; j < count; ++j) {
    const std::size_t i = indices[j];
    const Mat3 r = rotation_of(&scene.rotations[i * 4]);
    double d[3], s2[3];
    for (int k = 0; k < 3; ++k) {
      d[k] = scene.positions[i * 3 + k] - mean[k];
      s2[k] = double(scene.scales[i * 3 + k]) * scene.scales[i * 3 + k];
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double rsr = 0;  // (R S^2 R^T)[a][b]
        for (int k = 0; k < 3; ++k) rsr += r[a][k] * s2[k] * r[b][k];
        cov[a][b] += weights[j] * (rsr + d[a] * d[b]);
      }
    for (int k = 0; k < 3; ++k) colour[k] += weights[j] * scene.sh_dc[i * 3 + k];
    for (int k = 0; k < rest_n; ++k) colour[3 + k] += weights[j] * scene.sh_rest[i * rest_n + k];
  }
  for (auto& row : cov)
    for (double& c : row) c /= total;
  std::array<double, 3> values;
  Mat3 v;
  symmetric_eigen(cov, values, v);
  const double det = v[0][0] * (v[1][1] * v[2][2] - v[1][2] * v[2][1]) - v[0][1] * (v[1][0] * v[2][2] - v[1][2] * v[2][0]) +
                     v[0][2] * (v[1][0] * v[2][1] - v[1][1] * v[2][0]);
  if (det < 0)
    for (auto& row : v) row[2] = -row[2];
  std::array<double, 3> scale;
  for (int k = 0; k < 3; ++k) scale[k] = std::sqrt(std::max(values[k], 0.0));
  // A merge of flat Gaussians stays flat but not degenerate: the smallest axis keeps a sliver.
  const double largest = std::max({scale[0], scale[1], scale[2]});
  for (double& s : scale) s = std::max(s, largest * 1e-6);
  const double rows[9] = {v[0][0], v[0][1], v[0][2], v[1][0], v[1][1], v[1][2], v[2][0], v[2][1], v[2][2]};
  double q[4];
  quaternion_from_matrix(rows, q);
  double mass = 0;
  for (std::size_t j = 0; j < count; ++j) mass += merge_weight(scene, indices[j]);
  const double opacity = std::min(1.0, mass / section_area(scale[0], scale[1], scale[2]));

  for (int k = 0; k < 3; ++k) out.positions.push_back(static_cast<float>(mean[k]));
  for (int k = 0; k < 3; ++k) out.scales.push_back(static_cast<float>(scale[k]));
  for (int k = 0; k < 4; ++k) out.rotations.push_back(static_cast<float>(q[k]));
  out.opacities.push_back(static_cast<float>(opacity));
  for (int k = 0; k < 3; ++k) out.sh_dc.push_back(static_cast<float>(colour[k] / total));
  for (int k = 0; k < rest_n; ++k) out.sh_rest.push_back(static_cast<float>(colour[3 + k] / total));
}

Scene coarser_level(const Scene& level) {
  const std::size_t n = level.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  order_in_pairs(level, order.data(), n);
  Scene out;
  out.sh_degree = level.sh_degree;
  out.trained_kernel = level.trained_kernel;
  out.reserve((n + 1) / 2);
  for (std::size_t i = 0; i < n; i += 2) append_merged(level, &order[i], std::min<std::size_t>(2, n - i), out);
  return out;
}

}  // namespace flashgs
