// The .splat format of antimatter15's WebGL viewer: 32-byte records (float position and linear
// scale, 8-bit RGBA, 8-bit quaternion), no header; read and written here.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/model_constants.h"
#include "flashgs/scene_formats.h"
#include "format_readers.h"

namespace flashgs {
namespace {

// x y z, scale x y z (float32 little endian), r g b a, quaternion w x y z (uint8).
constexpr std::size_t kRecordBytes = 32;
constexpr std::size_t kColourOffset = 24;
constexpr std::size_t kRotationOffset = 28;

// A value in [0, 1] to the nearest byte, clamped (colours beyond the displayable range clip).
std::uint8_t unit_to_byte(double v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

// A quaternion component in [-1, 1] as c * 128 + 128, to the nearest byte (1 clamps to 255).
std::uint8_t component_to_byte(double c) {
  return static_cast<std::uint8_t>(std::clamp<long>(std::lround(c * 128.0 + 128.0), 0, 255));
}

}  // namespace

DeclaredScene declare_splat(std::uint64_t size, const std::string& name) {
  if (size == 0) throw Error(name + ": the .splat file is empty: there are no Gaussians");
  if (size % kRecordBytes != 0)
    throw Error(name + ": a .splat file is a sequence of 32-byte records, but its " + std::to_string(size) +
                " bytes are not a multiple of 32 (" + std::to_string(size % kRecordBytes) +
                " bytes left over): truncated, or not a .splat file");
  DeclaredScene declared;
  declared.gaussians = size / kRecordBytes;
  return declared;
}

Scene parse_splat(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                  LoadProgress* progress) {
  report = LoadReport{};
  report.path = name;
  const std::size_t count = declare_splat(size, name).gaussians;
  report.vertices_in_file = count;
  Scene scene;
  scene.reserve(count);
  DecodeProgress decoding(progress, name, count);
  const auto* bytes = reinterpret_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < count; ++i) {
    decoding.at(i);
    const unsigned char* record = bytes + i * kRecordBytes;
    float floats[6];
    std::memcpy(floats, record, sizeof floats);  // little endian, as every host we build for
    DecodedGaussian g;
    for (int k = 0; k < 3; ++k) {
      g.position[k] = floats[k];
      g.scale[k] = floats[3 + k];
      g.sh_dc[k] = (record[kColourOffset + k] / 255.0 - 0.5) / model::kShC0;
      g.rotation[k + 1] = (record[kRotationOffset + k + 1] - 128.0) / 128.0;
    }
    g.rotation[0] = (record[kRotationOffset] - 128.0) / 128.0;
    g.opacity = record[kColourOffset + 3] / 255.0;
    append_gaussian(scene, g, nullptr, report);
  }
  decoding.done(count);
  if (scene.size() == 0) throw Error(name + ": all " + std::to_string(count) + " Gaussians have NaN or Inf values");
  return scene;
}

void save_splat(const Scene& scene, const std::string& path) {
  std::vector<unsigned char> records(scene.size() * kRecordBytes);
  for (std::size_t i = 0; i < scene.size(); ++i) {
    unsigned char* record = records.data() + i * kRecordBytes;
    float floats[6];
    for (int k = 0; k < 3; ++k) {
      floats[k] = scene.positions[i * 3 + k];
      floats[3 + k] = scene.scales[i * 3 + k];
      record[kColourOffset + k] = unit_to_byte(0.5 + model::kShC0 * scene.sh_dc[i * 3 + k]);
    }
    std::memcpy(record, floats, sizeof floats);
    record[kColourOffset + 3] = unit_to_byte(scene.opacities[i]);
    for (int k = 0; k < 4; ++k) record[kRotationOffset + k] = component_to_byte(scene.rotations[i * 4 + k]);
  }
  write_file_atomically(path, [&](OutputFile& file) { file.write(records.data(), records.size()); });
}

}  // namespace flashgs
