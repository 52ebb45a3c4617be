// What the scene-file readers share (the checks on every decoded Gaussian, progress and
// cancelling) and the parser of each format, for the registry in scene_formats.cpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs {

// One Gaussian as a reader decoded it, activations applied (linear scale, opacity in
// [0, 1]), in double so that every format rounds to float in the same one place.
struct DecodedGaussian {
  double position[3];
  double scale[3];
  double rotation[4];  // w x y z, any non-zero norm
  double opacity;
  double sh_dc[3];
};

// Appends `g` (and `sh_rest`, scene.sh_rest_per_gaussian() floats in [k][channel] order)
// after the checks every format shares: a Gaussian with a value that is not a finite float
// is dropped and counted, a zero quaternion becomes the identity and is counted, the
// quaternion is normalised.
void append_gaussian(Scene& scene, const DecodedGaussian& g, const float* sh_rest, LoadReport& report);

// Publishes the Gaussians decoded and checks for a cancel request every kStep Gaussians.
class DecodeProgress {
 public:
  static constexpr std::size_t kStep = 1 << 16;
  // `total` Gaussians are to be decoded from the file `name`.
  DecodeProgress(LoadProgress* progress, const std::string& name, std::size_t total);
  // Before decoding Gaussian `i` (in order): throws flashgs::LoadCancelled on a cancel request.
  void at(std::size_t i) {
    if (m_progress && i % kStep == 0) publish(i);
  }
  // All decoded.
  void done(std::size_t total);

 private:
  void publish(std::size_t done);
  LoadProgress* m_progress;
  const std::string& m_name;
};

// What a file's start declares before the whole file is read: the Gaussians it holds (0 when
// the start cannot say) and their SH degree; `extra_bytes_per_gaussian` is what decoding holds
// per Gaussian beside the file's bytes and the scene (SPZ's inflated attributes).
struct DeclaredScene {
  std::uint64_t gaussians = 0;
  int sh_degree = 0;
  std::uint64_t extra_bytes_per_gaussian = 0;
};
// From a PLY header held whole in `start` (the first bytes of a file of `file_size` bytes):
// throws flashgs::Error naming `name` when the header is invalid or a binary file's size is
// not what its elements declare. Unknown (0 Gaussians) when `start` ends inside the header.
DeclaredScene declare_ply(const char* start, std::size_t start_size, std::uint64_t file_size,
                          const std::string& name);
// A .splat file of `file_size` bytes: throws unless it is a whole number of records.
DeclaredScene declare_splat(std::uint64_t file_size, const std::string& name);
// An SPZ header, from the file's first bytes (inside the gzip stream for versions 1-3).
DeclaredScene declare_spz(const char* start, std::size_t start_size, const std::string& name);

// One parser per format, on the file's bytes (`name` is the path, used in messages), beside
// parse_ply (io.h). Each throws flashgs::Error naming the file and the problem, and fills
// `report` (reset first); `progress` may be null.
Scene parse_compressed_ply(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                           LoadProgress* progress);
Scene parse_splat(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                  LoadProgress* progress);
Scene parse_ksplat(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                   LoadProgress* progress);

}  // namespace flashgs
