// Moving a chunk's Gaussians by an instance's rigid transform, SH bands included.
#include "flashgs/lod_instance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "flashgs/gaussian_math.h"
#include "flashgs/lod_set.h"
#include "flashgs/rotation.h"

namespace flashgs {
namespace {

constexpr int kMaxBandSize = 7;   // band 3
constexpr int kSampleDirections = 64;
// Beyond these, moved positions and scales would leave the float range a renderer works in.
constexpr double kMaxTranslation = 1e12, kMinScale = 1e-6, kMaxScale = 1e6;

// Band l's coefficients c (2l+1 of them) of a function f become X c for the function
// f'(d) = f(R^T d). Y_l(R^T d) = M Y_l(d) for one (2l+1)^2 matrix M, so X = M^T; it is fitted
// exactly from the basis at spread directions (least squares over more samples than unknowns,
// which any real SH convention satisfies without tables of Wigner matrices).
struct BandRotation {
  int size = 0;
  double x[kMaxBandSize][kMaxBandSize] = {};
};

void basis_at(const double d[3], float out[16]) {
  gm::sh_basis<3>(static_cast<float>(d[0]), static_cast<float>(d[1]), static_cast<float>(d[2]), out);
}

// Solves a x = b for x in place (a is n x n, b n x m; partial pivoting; a is well conditioned).
void solve(double a[kMaxBandSize][kMaxBandSize], double b[kMaxBandSize][kMaxBandSize], int n) {
  for (int c = 0; c < n; ++c) {
    int pivot = c;
    for (int r = c + 1; r < n; ++r)
      if (std::fabs(a[r][c]) > std::fabs(a[pivot][c])) pivot = r;
    for (int k = 0; k < n; ++k) std::swap(a[c][k], a[pivot][k]), std::swap(b[c][k], b[pivot][k]);
    for (int r = 0; r < n; ++r) {
      if (r == c) continue;
      const double f = a[r][c] / a[c][c];
      for (int k = 0; k < n; ++k) a[r][k] -= f * a[c][k], b[r][k] -= f * b[c][k];
    }
  }
  for (int r = 0; r < n; ++r)
    for (int k = 0; k < n; ++k) b[r][k] /= a[r][r];
}

BandRotation band_rotation(int band, const double m[9]) {
  BandRotation out;
  const int n = 2 * band + 1, first = band * band;
  out.size = n;
  double ata[kMaxBandSize][kMaxBandSize] = {}, atb[kMaxBandSize][kMaxBandSize] = {};
  for (int s = 0; s < kSampleDirections; ++s) {
    // Fibonacci points on the sphere.
    const double z = 1.0 - (2.0 * s + 1.0) / kSampleDirections, r = std::sqrt(1.0 - z * z);
    const double phi = s * 2.399963229728653;
    const double d[3] = {r * std::cos(phi), r * std::sin(phi), z};
    const double back[3] = {m[0] * d[0] + m[3] * d[1] + m[6] * d[2], m[1] * d[0] + m[4] * d[1] + m[7] * d[2],
                            m[2] * d[0] + m[5] * d[1] + m[8] * d[2]};  // R^T d
    float a[16], b[16];
    basis_at(d, a);
    basis_at(back, b);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        ata[i][j] += double(a[first + i]) * a[first + j];
        atb[i][j] += double(a[first + i]) * b[first + j];
      }
  }
  solve(ata, atb, n);  // atb = M^T
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) out.x[i][j] = atb[i][j];
  return out;
}

}  // namespace

void transform_gaussians(Scene& scene, const LodInstance& instance) {
  double m[9];
  matrix_from_quaternion(instance.rotation.data(), m);
  const double s = instance.scale;
  const float scale = static_cast<float>(s);
  BandRotation bands[3];
  for (int band = 1; band <= scene.sh_degree; ++band) bands[band - 1] = band_rotation(band, m);
  const std::size_t rest = static_cast<std::size_t>(scene.sh_rest_per_gaussian());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    float* p = &scene.positions[i * 3];
    const double v[3] = {p[0], p[1], p[2]};
    for (int r = 0; r < 3; ++r)
      p[r] = static_cast<float>(s * (m[r * 3] * v[0] + m[r * 3 + 1] * v[1] + m[r * 3 + 2] * v[2]) + instance.translation[r]);
    float* q = &scene.rotations[i * 4];
    const double g[4] = {q[0], q[1], q[2], q[3]};
    double turned[4];
    multiply_quaternions(instance.rotation.data(), g, turned);
    for (int k = 0; k < 4; ++k) q[k] = static_cast<float>(turned[k]);
    for (int k = 0; k < 3; ++k) scene.scales[i * 3 + k] *= scale;
    if (rest == 0) continue;
    float* c = &scene.sh_rest[i * rest];  // [k][channel], k = 1..K-1
    for (int band = 1; band <= scene.sh_degree; ++band) {
      const BandRotation& b = bands[band - 1];
      const int first = band * band - 1;  // the band's first coefficient in sh_rest
      for (int ch = 0; ch < 3; ++ch) {
        double in[kMaxBandSize];
        for (int j = 0; j < b.size; ++j) in[j] = c[(first + j) * 3 + ch];
        for (int a = 0; a < b.size; ++a) {
          double sum = 0;
          for (int j = 0; j < b.size; ++j) sum += b.x[a][j] * in[j];
          c[(first + a) * 3 + ch] = static_cast<float>(sum);
        }
      }
    }
  }
}

LodBox transformed_bound(const LodBox& box, const LodInstance& instance) {
  double m[9];
  matrix_from_quaternion(instance.rotation.data(), m);
  LodBox out;
  out.min.fill(std::numeric_limits<float>::max());
  out.max.fill(std::numeric_limits<float>::lowest());
  for (int corner = 0; corner < 8; ++corner) {
    const double v[3] = {corner & 1 ? box.max[0] : box.min[0], corner & 2 ? box.max[1] : box.min[1],
                         corner & 4 ? box.max[2] : box.min[2]};
    for (int r = 0; r < 3; ++r) {
      const float p = static_cast<float>(
          instance.scale * (m[r * 3] * v[0] + m[r * 3 + 1] * v[1] + m[r * 3 + 2] * v[2]) + instance.translation[r]);
      out.min[r] = std::min(out.min[r], p);
      out.max[r] = std::max(out.max[r], p);
    }
  }
  return out;
}

const char* lod_instance_problem(const LodInstance& instance) {
  double norm2 = 0;
  for (double v : instance.rotation) {
    if (!std::isfinite(v)) return "its rotation holds a value that is not a finite number";
    norm2 += v * v;
  }
  for (double v : instance.translation)
    if (!(std::fabs(v) <= kMaxTranslation)) return "its translation holds a value that is not a number within +-1e12";
  if (!(instance.scale >= kMinScale && instance.scale <= kMaxScale)) return "its scale is not a number in 1e-6..1e6";
  if (std::fabs(std::sqrt(norm2) - 1.0) > 1e-3) return "its rotation is not a unit quaternion (w, x, y, z)";
  return "";
}

}  // namespace flashgs
