// Writes scenes in the INRIA 3DGS PLY layout (binary little endian, float32, raw parameters).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <vector>

#include "flashgs/file_write.h"
#include "flashgs/io.h"
#include "kernel_marks.h"
#include "ply_records.h"

namespace flashgs {

std::string inria_ply_header(const Scene& scene, std::uint64_t count) {
  const int rest_n = scene.sh_rest_per_gaussian();
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& comment : ply_comments_for(scene.trained_kernel)) header << "comment " << comment << "\n";
  header << "element vertex " << count << "\n";
  for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    header << "property float " << p << "\n";
  for (int k = 0; k < rest_n; ++k) header << "property float f_rest_" << k << "\n";
  header << "property float opacity\n";
  for (const char* p : {"scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    header << "property float " << p << "\n";
  header << "end_header\n";
  return header.str();
}

void write_inria_records(const Scene& scene, OutputFile& file) {
  const int rest_n = scene.sh_rest_per_gaussian();
  const int per_channel = rest_n / 3;
  std::vector<float> record(static_cast<std::size_t>(9 + rest_n + 8));
  for (std::size_t i = 0; i < scene.size(); ++i) {
    float* r = record.data();
    for (int k = 0; k < 3; ++k) *r++ = scene.positions[i * 3 + k];
    for (int k = 0; k < 3; ++k) *r++ = 0.0f;  // normals: unused by 3DGS
    for (int k = 0; k < 3; ++k) *r++ = scene.sh_dc[i * 3 + k];
    for (int ch = 0; ch < 3; ++ch)  // back to channel-major
      for (int k = 0; k < per_channel; ++k)
        *r++ = scene.sh_rest[i * rest_n + k * 3 + ch];
    // Logit of the opacity, clamped so that 0 and 1 stay finite.
    const double o = std::min(std::max(static_cast<double>(scene.opacities[i]), 1e-12), 1.0 - 1e-7);
    *r++ = static_cast<float>(std::log(o / (1.0 - o)));
    for (int k = 0; k < 3; ++k) *r++ = std::log(std::abs(scene.scales[i * 3 + k]));
    for (int k = 0; k < 4; ++k) *r++ = scene.rotations[i * 4 + k];
    // The file format is little endian; so are all hosts we build for (x86-64, arm64).
    file.write(record.data(), record.size() * sizeof(float));
  }
}

void save_ply(const Scene& scene, const std::string& path) {
  const std::string header = inria_ply_header(scene, scene.size());
  write_file_atomically(path, [&](OutputFile& file) {
    file.write(header);
    write_inria_records(scene, file);
  });
}

std::size_t count_negative_scales(const Scene& scene) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < scene.size(); ++i)
    count += std::signbit(scene.scales[i * 3]) || std::signbit(scene.scales[i * 3 + 1]) ||
             std::signbit(scene.scales[i * 3 + 2]);
  return count;
}

}  // namespace flashgs
