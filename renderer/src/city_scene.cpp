// The city generator: real scenes copied onto a grid at distinct headings, streamed to one PLY.
#include "flashgs/city_scene.h"

#include <algorithm>
#include <cmath>

#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/rotation.h"
#include "ply_records.h"

namespace flashgs {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHeadingStep = 137.5;  // degrees: the golden angle, so that no two nearby blocks face alike
constexpr std::size_t kBatch = std::size_t{1} << 20;

// The rotation taking the source's up axis to +z.
void up_to_z(const std::string& up, const std::string& name, double m[9]) {
  static const struct {
    const char* axis;
    double m[9];
  } table[] = {{"+z", {1, 0, 0, 0, 1, 0, 0, 0, 1}},  {"-z", {1, 0, 0, 0, -1, 0, 0, 0, -1}},
               {"+y", {1, 0, 0, 0, 0, -1, 0, 1, 0}}, {"-y", {1, 0, 0, 0, 0, 1, 0, -1, 0}},
               {"+x", {0, 0, -1, 0, 1, 0, 1, 0, 0}}, {"-x", {0, 0, 1, 0, 1, 0, -1, 0, 0}}};
  for (const auto& entry : table)
    if (up == entry.axis) {
      std::copy(entry.m, entry.m + 9, m);
      return;
    }
  throw Error(name + ": up axis \"" + up + "\" is none of +x -x +y -y +z -z");
}

void apply(const double m[9], const double v[3], double out[3]) {
  for (int r = 0; r < 3; ++r) out[r] = m[r * 3] * v[0] + m[r * 3 + 1] * v[1] + m[r * 3 + 2] * v[2];
}

// The value below which `fraction` of the values lie.
float quantile(std::vector<float> values, double fraction) {
  const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(fraction * double(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// The camera at `eye` looking at `target`, world up +z (OpenCV axes: x right, y down, z forward).
Camera look_at(const double eye[3], const double target[3], int width, int height) {
  double f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  double n = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  for (double& v : f) v /= n;
  double r[3] = {f[1], -f[0], 0};  // forward x up(+z)
  n = std::sqrt(r[0] * r[0] + r[1] * r[1]);
  if (n < 1e-9) r[0] = 1, r[1] = 0, n = 1;  // looking straight down
  for (double& v : r) v /= n;
  const double d[3] = {f[1] * r[2] - f[2] * r[1], f[2] * r[0] - f[0] * r[2], f[0] * r[1] - f[1] * r[0]};  // forward x right
  const float to_world[9] = {float(r[0]), float(d[0]), float(f[0]), float(r[1]), float(d[1]), float(f[1]),
                             float(r[2]), float(d[2]), float(f[2])};
  const float centre[3] = {float(eye[0]), float(eye[1]), float(eye[2])};
  const float focal = static_cast<float>(width / (2 * std::tan(kPi / 6)));
  return Camera::from_pose(width, height, focal, focal, to_world, centre);
}

}  // namespace

CityPlacement place_city_source(const Scene& scene, const std::string& up, const std::string& name) {
  if (scene.size() == 0) throw Error(name + ": holds no Gaussians");
  CityPlacement p;
  up_to_z(up, name, p.align);
  std::vector<float> axis[3];
  for (auto& a : axis) a.reserve(scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const double v[3] = {scene.positions[i * 3], scene.positions[i * 3 + 1], scene.positions[i * 3 + 2]};
    double u[3];
    apply(p.align, v, u);
    for (int k = 0; k < 3; ++k) axis[k].push_back(static_cast<float>(u[k]));
  }
  double span2 = 0;
  for (int k = 0; k < 2; ++k) {
    const double lo = quantile(axis[k], 0.02), hi = quantile(axis[k], 0.98);
    p.centre[k] = 0.5 * (lo + hi);
    span2 += (hi - lo) * (hi - lo);
  }
  p.centre[2] = quantile(axis[2], 0.02);
  p.width = std::sqrt(span2);
  return p;
}

int city_side(int blocks) { return static_cast<int>(std::ceil(std::sqrt(static_cast<double>(std::max(1, blocks))))); }

void city_block_transform(const CityPlacement& placement, int block, int side, double block_size, double rotation[9],
                          double translation[3]) {
  const double heading = block * kHeadingStep * kPi / 180.0;
  const double turn[9] = {std::cos(heading), -std::sin(heading), 0, std::sin(heading), std::cos(heading), 0, 0, 0, 1};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      rotation[r * 3 + c] = turn[r * 3] * placement.align[c] + turn[r * 3 + 1] * placement.align[3 + c] +
                            turn[r * 3 + 2] * placement.align[6 + c];
  // turn (align p - centre) + cell = turn align p + (cell - turn centre)
  double turned_centre[3];
  apply(turn, placement.centre, turned_centre);
  const double cell[3] = {(block % side) * block_size, (block / side) * block_size, 0.0};
  for (int k = 0; k < 3; ++k) translation[k] = cell[k] - turned_centre[k];
}

std::vector<Camera> city_camera_path(int side, double block_size, int count, int width, int height) {
  // From eye height along the first row of blocks, then up and back to see the whole city.
  const double size = block_size, extent = side * size;
  const double eye_height = 0.02 * size;
  const int street = std::max(1, count / 2);
  std::vector<Camera> path;
  for (int i = 0; i < count; ++i) {
    double eye[3], target[3];
    if (i < street) {
      const double t = static_cast<double>(i) / street;
      eye[0] = -0.5 * size + t * extent, eye[1] = -0.5 * size, eye[2] = eye_height;
      target[0] = eye[0] + size, target[1] = -0.2 * size, target[2] = eye_height;  // along the street, towards the blocks
    } else {
      const double t = static_cast<double>(i - street + 1) / (count - street);
      eye[0] = (1 - t) * (extent - 0.5 * size) + t * (-0.5 * size);
      eye[1] = (1 - t) * (-0.5 * size) + t * (-0.7 * extent);
      eye[2] = (1 - t) * eye_height + t * 0.9 * extent;
      target[0] = 0.5 * (extent - size), target[1] = 0.5 * (extent - size), target[2] = 0.0;
    }
    path.push_back(look_at(eye, target, width, height));
  }
  return path;
}

CityReport write_city_scene(const std::vector<CitySource>& sources, int blocks, const std::string& ply_path,
                            int path_cameras, int width, int height, std::vector<Camera>* path) {
  if (sources.empty()) throw Error(ply_path + ": a city needs at least one source scene");
  if (blocks < 1) throw Error(ply_path + ": a city needs at least one block");
  std::vector<CityPlacement> placed;
  CityReport report;
  report.blocks = blocks;
  for (const CitySource& s : sources) {
    placed.push_back(place_city_source(s.scene, s.up, s.name));
    report.block_size = std::max(report.block_size, static_cast<float>(1.1 * placed.back().width));
    report.dropped_sh |= s.scene.sh_degree > 0;
  }
  const int side = city_side(blocks);
  for (int b = 0; b < blocks; ++b) report.gaussians += sources[static_cast<std::size_t>(b) % sources.size()].scene.size();

  Scene like;  // the header's layout: SH degree 0, no kernel mark unless every source has the same
  like.trained_kernel = sources.front().scene.trained_kernel;
  for (const CitySource& s : sources)
    if (!(s.scene.trained_kernel.kernel == like.trained_kernel.kernel)) like.trained_kernel = TrainedKernel{};
  write_file_atomically(ply_path, [&](OutputFile& file) {
    file.write(inria_ply_header(like, report.gaussians));
    for (int b = 0; b < blocks; ++b) {
      const CitySource& source = sources[static_cast<std::size_t>(b) % sources.size()];
      double m[9], t[3], qm[4];
      city_block_transform(placed[static_cast<std::size_t>(b) % sources.size()], b, side, report.block_size, m, t);
      quaternion_from_matrix(m, qm);
      const Scene& in = source.scene;
      for (std::size_t first = 0; first < in.size(); first += kBatch) {
        const std::size_t n = std::min(kBatch, in.size() - first);
        Scene out;
        out.reserve(n);
        for (std::size_t i = first; i < first + n; ++i) {
          double v[3], u[3];
          for (int k = 0; k < 3; ++k) v[k] = in.positions[i * 3 + k];
          apply(m, v, u);
          for (int k = 0; k < 3; ++k) out.positions.push_back(static_cast<float>(u[k] + t[k]));
          const double q[4] = {in.rotations[i * 4], in.rotations[i * 4 + 1], in.rotations[i * 4 + 2], in.rotations[i * 4 + 3]};
          double rotated[4];
          multiply_quaternions(qm, q, rotated);
          for (int k = 0; k < 4; ++k) out.rotations.push_back(static_cast<float>(rotated[k]));
          for (int k = 0; k < 3; ++k) out.scales.push_back(in.scales[i * 3 + k]);
          out.opacities.push_back(in.opacities[i]);
          for (int k = 0; k < 3; ++k) out.sh_dc.push_back(in.sh_dc[i * 3 + k]);
        }
        write_inria_records(out, file);
      }
    }
  });
  report.bytes = report.gaussians * 17 * sizeof(float);
  if (path && path_cameras > 0) *path = city_camera_path(side, report.block_size, path_cameras, width, height);
  return report;
}

}  // namespace flashgs
