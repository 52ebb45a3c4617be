// Reads one SOG chunk (PlayCanvas, version 1 or 2): meta.json names lossless WebP textures whose pixel i
// holds Gaussian i's quantised attributes; each texture's size is checked against meta.json
// before it is decoded.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "sog_meta.h"

#ifdef FLASHGS_HAVE_WEBP
#include <webp/decode.h>
#endif

namespace flashgs {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr double kInvSqrt2 = 0.70710678118654752440;
// Writers round textures up to a square of a multiple of 4 (a few spare rows); more spare
// pixels than this many rows is not a SOG writer's slack but a size that would waste memory.
constexpr std::uint64_t kMaxSpareRows = 16;
// Progress is published and cancellation checked every this many Gaussians.
constexpr std::size_t kProgressStep = 1 << 16;

// The name may come from a file (a texture or chunk named in JSON) or a user's argument.
[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

void check_cancel(LoadProgress* progress, const std::string& name) {
  if (progress && progress->cancel_requested.load(std::memory_order_relaxed)) throw LoadCancelled(name);
}

// A decoded texture: 4 bytes (RGBA) per pixel, row-major from the top left.
struct Texture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
  const std::uint8_t* pixel(std::size_t i) const { return &rgba[i * 4]; }
};

// The size WebP gives in its header, before anything is decoded.
struct TextureSize {
  int width = 0, height = 0;
};

TextureSize webp_size(const std::vector<char>& bytes, const std::string& file) {
#ifdef FLASHGS_HAVE_WEBP
  WebPBitstreamFeatures features;
  if (WebPGetFeatures(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), &features) != VP8_STATUS_OK)
    fail(file, "not a WebP image (SOG textures are lossless WebP)");
  if (features.has_animation) fail(file, "an animated WebP; SOG textures are single images");
  if (features.format == 1) fail(file, "a lossy WebP; SOG textures must be lossless (lossy data corrupts the values)");
  return {features.width, features.height};
#else
  (void)bytes;
  fail(file, "this build has no libwebp, so SOG textures cannot be decoded (install libwebp-dev and rebuild)");
#endif
}

Texture decode_webp(const std::vector<char>& bytes, TextureSize size, const std::string& file) {
  Texture texture;
  texture.width = size.width;
  texture.height = size.height;
  texture.rgba.resize(static_cast<std::size_t>(size.width) * size.height * 4);
#ifdef FLASHGS_HAVE_WEBP
  const int stride = size.width * 4;
  if (!WebPDecodeRGBAInto(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), texture.rgba.data(),
                          texture.rgba.size(), stride))
    fail(file, "the WebP data is corrupt or truncated");
#else
  (void)bytes;
  (void)file;
#endif
  return texture;
}

std::string size_text(TextureSize s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

// Reads and decodes one texture after checking its size: per-Gaussian textures must have room
// for `count` pixels and few to spare; the SH palette must be exactly its size.
Texture load_texture(const SogFileSource& files, const std::string& file_name, const std::string& name,
                     std::size_t count, const TextureSize* exact, LoadProgress* progress) {
  const std::string file = name + " -> " + file_name;
  const std::vector<char> bytes = files(file_name);
  const TextureSize size = webp_size(bytes, file);
  if (size.width <= 0 || size.height <= 0) fail(file, "the image has no pixels");
  const std::uint64_t pixels = std::uint64_t(size.width) * std::uint64_t(size.height);
  if (exact) {
    if (size.width != exact->width || size.height != exact->height)
      fail(file, "the image is " + size_text(size) + " but meta.json's SH palette needs " + size_text(*exact));
  } else if (pixels < count || pixels - count > kMaxSpareRows * std::uint64_t(std::max(size.width, size.height))) {
    fail(file, "the image is " + size_text(size) + " (" + std::to_string(pixels) + " pixels) but meta.json says " +
                   std::to_string(count) + " Gaussians: " +
                   (pixels < count ? "too small" : "far larger than they need"));
  }
  Texture texture = decode_webp(bytes, size, file);
  if (progress) progress->bytes_done.fetch_add(bytes.size(), std::memory_order_relaxed);
  check_cancel(progress, name);
  return texture;
}

// SOG version 1 names no band count: the centroids texture is 64 entries of 3, 8 or 15
// pixels wide, and 64 entries per row give the palette's size.
void find_sh_bands(SogMeta& meta, const SogFileSource& files, const std::string& name) {
  const std::string file = name + " -> " + meta.sh_files[0];
  const TextureSize size = webp_size(files(meta.sh_files[0]), file);
  for (int bands = 1; bands <= 3; ++bands)
    if (size.width == kCentroidsPerRow * (sh_coefficient_count(bands) - 1)) meta.sh_bands = bands;
  if (meta.sh_bands == 0)
    fail(file, "the SH palette is " + std::to_string(size.width) +
                   " pixels wide; SOG version 1 palettes are 192, 512 or 960 (SH degree 1, 2 or 3)");
  meta.sh_palette_size = std::size_t(kCentroidsPerRow) * std::size_t(std::max(0, size.height));
}

// Symmetric log transform undone: sign(n) (e^|n| - 1).
double unlog(double n) { return n < 0 ? -(std::exp(-n) - 1.0) : std::exp(n) - 1.0; }

}  // namespace

Scene parse_sog(const std::string& meta_json, const SogFileSource& files, const std::string& name, LoadReport* report,
                LoadProgress* progress) {
  LoadReport local_report;
  if (!report) report = &local_report;
  *report = LoadReport{};
  report->path = name;
  SogMeta meta = parse_sog_meta(meta_json, name);
  if (meta.sh_bands_from_texture) find_sh_bands(meta, files, name);
  const std::size_t n = meta.count;
  report->vertices_in_file = n;
  // The scene and the decoded textures, refused before any is allocated when they cannot fit
  // (a tiny lossless WebP may claim 16384 x 16384 pixels).
  const std::uint64_t need = n * (sizeof(float) * (14 + 3 * std::uint64_t(sh_coefficient_count(meta.sh_bands) - 1)) +
                                  4 * sog_meta_files(meta).size());
  const AvailableMemory available = available_host_memory();
  if (available.bytes > 0 && need > available.bytes)
    fail(name, "meta.json declares " + std::to_string(n) + " Gaussians, " + format_bytes(need) +
                   " to decode, but only " + format_bytes(available.bytes) + " of memory is available");

  report->sh_degree_in_file = meta.sh_bands;
  const Texture means_l = load_texture(files, meta.means_files[0], name, n, nullptr, progress);
  const Texture means_u = load_texture(files, meta.means_files[1], name, n, nullptr, progress);
  const Texture scales = load_texture(files, meta.scales_file, name, n, nullptr, progress);
  const Texture quats = load_texture(files, meta.quats_file, name, n, nullptr, progress);
  const Texture sh0 = load_texture(files, meta.sh0_file, name, n, nullptr, progress);
  const int coefficients = sh_coefficient_count(meta.sh_bands) - 1;
  Texture centroids, labels;
  if (meta.sh_bands > 0) {
    const TextureSize palette{kCentroidsPerRow * coefficients,
                              static_cast<int>((meta.sh_palette_size + kCentroidsPerRow - 1) / kCentroidsPerRow)};
    centroids = load_texture(files, meta.sh_files[0], name, n, &palette, progress);
    labels = load_texture(files, meta.sh_files[1], name, n, nullptr, progress);
  }

  Scene scene;
  scene.sh_degree = meta.sh_bands;
  scene.trained_kernel = meta.kernel;
  scene.reserve(n);
  if (progress) progress->gaussians_total.store(n, std::memory_order_relaxed);
  const int rest = scene.sh_rest_per_gaussian();
  std::vector<float> sh_rest(static_cast<std::size_t>(rest));
  for (std::size_t i = 0; i < n; ++i) {
    if (i % kProgressStep == 0) {
      if (progress) progress->gaussians_done.store(i, std::memory_order_relaxed);
      check_cancel(progress, name);
    }
    const std::uint8_t* lo = means_l.pixel(i);
    const std::uint8_t* hi = means_u.pixel(i);
    float position[3];
    for (int k = 0; k < 3; ++k) {
      const double t = (hi[k] << 8 | lo[k]) / 65535.0;
      position[k] = static_cast<float>(unlog(meta.means_min[k] + (meta.means_max[k] - meta.means_min[k]) * t));
    }
    const std::uint8_t* q = quats.pixel(i);
    if (q[3] < 252)
      fail(name + " -> " + meta.quats_file, "Gaussian " + std::to_string(i) + " has quaternion mode " +
                                                std::to_string(q[3]) + " in alpha (252-255 are valid)");
    // The three stored components in [-1/sqrt 2, 1/sqrt 2]; the omitted (largest) one rebuilt
    // non-negative. The mode indexes rot_0..rot_3, which are w x y z.
    const int omitted = q[3] - 252;
    double rotation[4], sum = 0;
    for (int k = 0, c = 0; k < 4; ++k) {
      if (k == omitted) continue;
      rotation[k] = (q[c++] / 255.0 - 0.5) * 2.0 * kInvSqrt2;
      sum += rotation[k] * rotation[k];
    }
    rotation[omitted] = std::sqrt(std::max(0.0, 1.0 - sum));
    const double norm = std::sqrt(rotation[0] * rotation[0] + rotation[1] * rotation[1] + rotation[2] * rotation[2] +
                                  rotation[3] * rotation[3]);
    const std::uint8_t* s = scales.pixel(i);
    const std::uint8_t* c0 = sh0.pixel(i);
    float scale[3], dc[3];
    for (int k = 0; k < 3; ++k) {
      scale[k] = static_cast<float>(std::exp(double(meta.scales_tables[k][s[k]])));
      dc[k] = meta.sh0_tables[k][c0[k]];
    }
    if (meta.sh_bands > 0) {
      const std::uint8_t* l = labels.pixel(i);
      const std::size_t label = l[0] | l[1] << 8;
      if (label >= meta.sh_palette_size)
        fail(name + " -> " + meta.sh_files[1], "Gaussian " + std::to_string(i) + " has SH palette label " +
                                                  std::to_string(label) + " but the palette has " +
                                                  std::to_string(meta.sh_palette_size) + " entries");
      const std::size_t row = label / kCentroidsPerRow, column = label % kCentroidsPerRow * coefficients;
      for (int c = 0; c < coefficients; ++c) {
        const std::uint8_t* p = centroids.pixel(row * centroids.width + column + c);
        for (int ch = 0; ch < 3; ++ch) sh_rest[c * 3 + ch] = meta.sh_codebook[p[ch]];
      }
    }
    bool finite = std::isfinite(position[0]) && std::isfinite(position[1]) && std::isfinite(position[2]) &&
                  std::isfinite(scale[0]) && std::isfinite(scale[1]) && std::isfinite(scale[2]) && norm > 0;
    if (!finite) {  // a log-domain range or a codebook whose exp overflows a float
      report->dropped_non_finite++;
      continue;
    }
    scene.positions.insert(scene.positions.end(), position, position + 3);
    scene.scales.insert(scene.scales.end(), scale, scale + 3);
    for (int k = 0; k < 4; ++k) scene.rotations.push_back(static_cast<float>(rotation[k] / norm));
    scene.opacities.push_back(meta.opacity_table.empty() ? static_cast<float>(c0[3] / 255.0) : meta.opacity_table[c0[3]]);
    scene.sh_dc.insert(scene.sh_dc.end(), dc, dc + 3);
    scene.sh_rest.insert(scene.sh_rest.end(), sh_rest.begin(), sh_rest.end());
  }
  if (progress) progress->gaussians_done.store(n, std::memory_order_relaxed);
  if (scene.size() == 0) fail(name, "all " + std::to_string(n) + " Gaussians have non-finite positions or scales");
  return scene;
}

namespace {

// Progress in bytes counts the textures; their sizes on disk (missing files count 0 here and
// are reported when read).
std::uint64_t texture_bytes(const SogMeta& meta, const fs::path& folder) {
  std::uint64_t total = 0;
  std::error_code error;
  for (const std::string& file : sog_meta_files(meta)) {
    const auto bytes = fs::file_size(folder / file, error);
    if (!error) total += bytes;
  }
  return total;
}

// A chunk whose meta.json text was read from `meta_name`: its textures lie beside it.
Scene read_chunk_text(const std::string& text, const std::string& meta_name, LoadReport* report,
                      LoadProgress* progress) {
  const fs::path folder = fs::path(meta_name).parent_path();
  const SogFileSource files = [&folder](const std::string& file) {
    return read_regular_file((folder / file).string(), kMaxSogTextureBytes);
  };
  return parse_sog(text, files, meta_name, report, progress);
}

std::string read_meta_text(const std::string& meta_path) {
  const std::vector<char> text = read_regular_file(meta_path, kMaxSogJsonBytes);
  return std::string(text.begin(), text.end());
}

void start_progress(LoadProgress* progress, std::uint64_t total_bytes) {
  if (!progress) return;
  progress->bytes_done.store(0, std::memory_order_relaxed);
  progress->bytes_total.store(total_bytes, std::memory_order_relaxed);
}

}  // namespace

std::uint64_t sog_chunk_texture_bytes(const std::string& meta_path) {
  return texture_bytes(parse_sog_meta(read_meta_text(meta_path), meta_path), fs::path(meta_path).parent_path());
}

Scene read_sog_chunk(const std::string& meta_path, LoadReport* report, LoadProgress* progress) {
  return read_chunk_text(read_meta_text(meta_path), meta_path, report, progress);
}

Scene read_sog(const std::string& path, LoadReport* report, LoadProgress* progress) {
  const std::string meta_path =
      path_kind(path) == PathKind::folder ? (fs::path(path) / "meta.json").string() : path;
  const std::string text = read_meta_text(meta_path);
  if (progress) start_progress(progress, texture_bytes(parse_sog_meta(text, meta_path), fs::path(meta_path).parent_path()));
  return read_chunk_text(text, meta_path, report, progress);
}

Scene parse_sog_file(const char* data, std::size_t size, const std::string& path, LoadReport* report,
                     LoadProgress* progress) {
  if (size > kMaxSogJsonBytes)
    throw Error(path + ": " + std::to_string(size) + " bytes is more than a SOG JSON file may have");
  const std::string text(data, size);
  if (looks_like_sog_lod_meta(text))
    return read_sog_lod(path, choose_sog_lod_level(describe_sog_lod(path), available_host_memory().bytes), report,
                        progress);
  if (progress) start_progress(progress, texture_bytes(parse_sog_meta(text, path), fs::path(path).parent_path()));
  return read_chunk_text(text, path, report, progress);
}

}  // namespace flashgs
