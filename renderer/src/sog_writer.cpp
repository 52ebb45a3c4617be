// Writes SOG v2 (PlayCanvas), the inverse of sog_reader.cpp: meta.json and lossless WebP
// textures whose pixel i holds Gaussian i; as a folder or as one zip archive (.sog).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/file_write.h"
#include "format_writers.h"
#include "kernel_marks.h"
#include "kmeans.h"
#include "sog_meta.h"
#include "zip_archive.h"

#ifdef FLASHGS_HAVE_WEBP
#include <webp/encode.h>
#endif

namespace flashgs {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr std::size_t kCodebookSize = 256;
constexpr std::size_t kMaxPalette = 65536;  // labels are 16 bits
// Gaussians per palette entry: the palette stays a fraction of the scene, as SOG intends.
constexpr std::size_t kGaussiansPerEntry = 4;
const char* const kTextureFiles[] = {"means_l.webp", "means_u.webp", "quats.webp",        "scales.webp",
                                     "sh0.webp",     "shN_centroids.webp", "shN_labels.webp"};

// RGBA pixels, row-major.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
  Image(int w, int h) : width(w), height(h), rgba(std::size_t(w) * h * 4, 0) {}
  std::uint8_t* pixel(std::size_t i) { return &rgba[i * 4]; }
};

// Per-Gaussian textures: a width that is a multiple of 4 near sqrt(n), rows for all of them.
Image gaussian_image(std::size_t n) {
  const int width = static_cast<int>(std::ceil(std::sqrt(double(n)) / 4.0)) * 4;
  const int height = static_cast<int>((n + width - 1) / width + 3) / 4 * 4;
  return Image(width, height);
}

std::vector<std::uint8_t> encode_webp(const Image& image, const std::string& name) {
#ifdef FLASHGS_HAVE_WEBP
  WebPConfig config;
  WebPPicture picture;
  if (!WebPConfigInit(&config) || !WebPPictureInit(&picture)) throw Error(name + ": libwebp could not start");
  config.lossless = 1;
  config.exact = 1;  // keep the RGB of transparent pixels: they are data, not colour
  config.quality = 75;
  config.method = 4;
  picture.use_argb = 1;
  picture.width = image.width;
  picture.height = image.height;
  WebPMemoryWriter writer;
  WebPMemoryWriterInit(&writer);
  picture.writer = WebPMemoryWrite;
  picture.custom_ptr = &writer;
  const bool ok = WebPPictureImportRGBA(&picture, image.rgba.data(), image.width * 4) && WebPEncode(&config, &picture);
  std::vector<std::uint8_t> bytes(writer.mem, writer.mem + (ok ? writer.size : 0));
  WebPPictureFree(&picture);
  WebPMemoryWriterClear(&writer);
  if (!ok) throw Error(name + ": libwebp failed to encode a texture");
  return bytes;
#else
  (void)image;
  throw Error(name + ": this build has no libwebp, so SOG cannot be written (install libwebp-dev and rebuild)");
#endif
}

// SOG's position transform: sign(x) ln(|x| + 1), so that far Gaussians take fewer steps.
double log_transform(double x) { return x < 0 ? -std::log1p(-x) : std::log1p(x); }

// Smallest-three of w x y z: the largest component made positive and named by alpha 252-255.
void pack_quaternion(const float* q, std::uint8_t* pixel) {
  int largest = 0;
  for (int k = 1; k < 4; ++k)
    if (std::abs(q[k]) > std::abs(q[largest])) largest = k;
  const double sign = q[largest] < 0 ? -1.0 : 1.0;
  for (int k = 0, c = 0; k < 4; ++k)
    if (k != largest) pixel[c++] = static_cast<std::uint8_t>(quantise_unit(sign * q[k] / std::sqrt(2.0) + 0.5, 8));
  pixel[3] = static_cast<std::uint8_t>(252 + largest);
}

json codebook_json(const std::vector<float>& codebook) {
  json values = json::array();
  for (std::size_t i = 0; i < kCodebookSize; ++i) values.push_back(codebook[std::min(i, codebook.size() - 1)]);
  return values;
}

struct Sog {
  json meta;
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> files;  // textures
};

Sog encode(const Scene& scene, const SceneWriteOptions& options, const std::string& name) {
  const std::size_t n = scene.size();
  Sog sog;
  json& meta = sog.meta;
  meta["version"] = 2;
  meta["count"] = n;
  const std::string model = sog_model_for(scene.trained_kernel);
  if (!model.empty()) meta["model"] = model;

  // Positions: 16 bits per axis between the log-transformed bounds, low and high bytes apart.
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double t = log_transform(scene.positions[i * 3 + k]);
      lo[k] = std::min(lo[k], t);
      hi[k] = std::max(hi[k], t);
    }
  Image means_l = gaussian_image(n), means_u = gaussian_image(n), quats = gaussian_image(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const unsigned q = quantise_range(log_transform(scene.positions[i * 3 + k]), lo[k], hi[k], 16);
      means_l.pixel(i)[k] = static_cast<std::uint8_t>(q & 0xff);
      means_u.pixel(i)[k] = static_cast<std::uint8_t>(q >> 8);
    }
    means_l.pixel(i)[3] = means_u.pixel(i)[3] = 255;
    pack_quaternion(&scene.rotations[i * 4], quats.pixel(i));
  }
  meta["means"] = {{"mins", {lo[0], lo[1], lo[2]}}, {"maxs", {hi[0], hi[1], hi[2]}},
                   {"files", {"means_l.webp", "means_u.webp"}}};
  meta["quats"] = {{"files", {"quats.webp"}}};
  sog.files.push_back({"means_l.webp", encode_webp(means_l, name)});
  sog.files.push_back({"means_u.webp", encode_webp(means_u, name)});
  sog.files.push_back({"quats.webp", encode_webp(quats, name)});

  // Log-scales and base colours: one 256-entry codebook each, shared by the three axes/channels.
  std::vector<float> log_scales(scene.scales.size());
  for (std::size_t i = 0; i < log_scales.size(); ++i) log_scales[i] = std::log(scene.scales[i]);
  const std::vector<float> scale_book = kmeans_1d(log_scales, kCodebookSize, options.sog_iterations);
  const std::vector<float> colour_book = kmeans_1d(scene.sh_dc, kCodebookSize, options.sog_iterations);
  Image scales = gaussian_image(n), sh0 = gaussian_image(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      scales.pixel(i)[k] = nearest_entry(scale_book, log_scales[i * 3 + k]);
      sh0.pixel(i)[k] = nearest_entry(colour_book, scene.sh_dc[i * 3 + k]);
    }
    scales.pixel(i)[3] = 255;
    sh0.pixel(i)[3] = static_cast<std::uint8_t>(quantise_unit(scene.opacities[i], 8));
  }
  meta["scales"] = {{"codebook", codebook_json(scale_book)}, {"files", {"scales.webp"}}};
  meta["sh0"] = {{"codebook", codebook_json(colour_book)}, {"files", {"sh0.webp"}}};
  sog.files.push_back({"scales.webp", encode_webp(scales, name)});
  sog.files.push_back({"sh0.webp", encode_webp(sh0, name)});

  // Higher bands: a palette of whole SH vectors by k-means, its values through one codebook.
  if (scene.sh_degree > 0) {
    const int dimension = scene.sh_rest_per_gaussian();
    const int coefficients = dimension / 3;
    const std::size_t entries = std::min(kMaxPalette, std::max<std::size_t>(1, (n + kGaussiansPerEntry - 1) / kGaussiansPerEntry));
    const Palette palette = kmeans_palette(scene.sh_rest.data(), n, dimension, entries, options.sog_iterations);
    const std::vector<float> sh_book = kmeans_1d(palette.centroids, kCodebookSize, options.sog_iterations);
    Image centroids(kCentroidsPerRow * coefficients, static_cast<int>((palette.count + kCentroidsPerRow - 1) / kCentroidsPerRow));
    for (std::size_t e = 0; e < palette.count; ++e)
      for (int c = 0; c < coefficients; ++c) {
        std::uint8_t* p = centroids.pixel((e / kCentroidsPerRow) * centroids.width + (e % kCentroidsPerRow) * coefficients + c);
        for (int ch = 0; ch < 3; ++ch) p[ch] = nearest_entry(sh_book, palette.centroids[e * dimension + c * 3 + ch]);
        p[3] = 255;
      }
    Image labels = gaussian_image(n);
    for (std::size_t i = 0; i < n; ++i) {
      labels.pixel(i)[0] = static_cast<std::uint8_t>(palette.labels[i] & 0xff);
      labels.pixel(i)[1] = static_cast<std::uint8_t>(palette.labels[i] >> 8);
      labels.pixel(i)[3] = 255;
    }
    meta["shN"] = {{"count", palette.count},
                   {"bands", scene.sh_degree},
                   {"codebook", codebook_json(sh_book)},
                   {"files", {"shN_centroids.webp", "shN_labels.webp"}}};
    sog.files.push_back({"shN_centroids.webp", encode_webp(centroids, name)});
    sog.files.push_back({"shN_labels.webp", encode_webp(labels, name)});
  }
  return sog;
}

}  // namespace

void save_sog_folder(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  // Every output is checked before the encoding: a bad folder costs no k-means.
  const fs::path folder = fs::path(path).parent_path();
  check_output_file(path);
  for (const char* file : kTextureFiles) check_output_file((folder / file).string());
  const Sog sog = encode(scene, options, path);
  for (const auto& [file, bytes] : sog.files)
    write_file_atomically((folder / file).string(),
                          [&](OutputFile& out) { out.write(bytes.data(), bytes.size()); });
  // meta.json last: a reader finds a complete set or none.
  write_file_atomically(path, sog.meta.dump() + "\n");
}

void save_sog_bundle(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  check_output_file(path);
  const Sog sog = encode(scene, options, path);
  std::vector<ZipEntry> entries;
  const std::string meta = sog.meta.dump() + "\n";
  entries.push_back({"meta.json", std::vector<std::uint8_t>(meta.begin(), meta.end())});
  for (const auto& [file, bytes] : sog.files) entries.push_back({file, bytes});
  write_file_atomically(path, [&](OutputFile& out) { write_zip(out, entries, path); });
}

}  // namespace flashgs
