// Reads PlayCanvas / SuperSplat compressed PLY files: per 256 Gaussians a "chunk" record of
// float min/max bounds, per Gaussian four packed 32-bit words (position 11-10-11, rotation as
// smallest-three 2-10-10-10, log-scale 11-10-11, colour and opacity 8-8-8-8), and optionally
// an "sh" element of 8-bit f_rest values.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/model_constants.h"
#include "format_readers.h"
#include "kernel_marks.h"
#include "ply_header.h"

namespace flashgs {
namespace {

using ply::quoted;

constexpr std::size_t kChunkGaussians = 256;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(name + ": " + problem);
}

// The chunk's float properties: position bounds, log-scale bounds, then (optionally) colour bounds.
const char* const kChunkProperties[] = {"min_x",       "min_y",       "min_z",       "max_x",       "max_y",
                                        "max_z",       "min_scale_x", "min_scale_y", "min_scale_z", "max_scale_x",
                                        "max_scale_y", "max_scale_z", "min_r",       "min_g",       "min_b",
                                        "max_r",       "max_g",       "max_b"};
constexpr int kBoundsProperties = 12;
constexpr int kAllChunkProperties = 18;
const char* const kPackedProperties[] = {"packed_position", "packed_rotation", "packed_scale", "packed_color"};

// Byte offsets inside a record of the named properties, which must all be of `type` and be
// the element's only properties; `optional_from` and later may be missing (-1).
std::vector<long> property_offsets(const ply::Element& element, const char* const* names, int count,
                                   int optional_from, const std::string& type, const std::string& name) {
  std::vector<long> offsets(static_cast<std::size_t>(count), -1);
  for (const ply::Property& p : element.properties) {
    int index = -1;
    for (int k = 0; k < count; ++k)
      if (p.name == names[k]) index = k;
    if (index < 0)
      fail(name, "element " + quoted(element.name) + " has an unexpected property " + quoted(p.name) +
                     " for a compressed PLY");
    if (p.is_list() || p.type != type)
      fail(name, "property " + quoted(p.name) + " of element " + quoted(element.name) + " has type " +
                     quoted(p.type) + "; a compressed PLY stores it as " + type);
    if (offsets[static_cast<std::size_t>(index)] >= 0) fail(name, "property " + quoted(p.name) + " appears twice");
    offsets[static_cast<std::size_t>(index)] = static_cast<long>(p.offset);
  }
  for (int k = 0; k < count; ++k)
    if (offsets[static_cast<std::size_t>(k)] < 0 && k < optional_from)
      fail(name, "element " + quoted(element.name) + " has no property " + quoted(names[k]));
  return offsets;
}

float read_float(const unsigned char* at) {
  float v;
  std::memcpy(&v, at, 4);  // little endian, as the header said and as every host we build for
  return v;
}

std::uint32_t read_word(const unsigned char* at) {
  std::uint32_t v;
  std::memcpy(&v, at, 4);
  return v;
}

// The `bits`-bit field of `word` at bit `shift`, as a fraction of its largest value.
double unorm(std::uint32_t word, int shift, int bits) {
  const std::uint32_t mask = (1u << bits) - 1u;
  return static_cast<double>((word >> shift) & mask) / mask;
}

double lerp(double lo, double hi, double t) { return lo * (1 - t) + hi * t; }

// Smallest-three: the top 2 bits name the largest component (of rot_0..rot_3 = w x y z), the
// other three are stored in 10 bits each, scaled from [-1/sqrt 2, 1/sqrt 2]. Each component
// is rounded to float, as the format's own decompressor stores it.
void unpack_rotation(std::uint32_t word, double q[4]) {
  const double norm = std::sqrt(2.0);  // 1 / (sqrt(2) / 2)
  const double a = (unorm(word, 20, 10) - 0.5) * norm;
  const double b = (unorm(word, 10, 10) - 0.5) * norm;
  const double c = (unorm(word, 0, 10) - 0.5) * norm;
  const double largest = std::sqrt(std::max(0.0, 1.0 - (a * a + b * b + c * c)));
  const int which = static_cast<int>(word >> 30);
  const double small[3] = {a, b, c};
  for (int k = 0, s = 0; k < 4; ++k) q[k] = static_cast<float>(k == which ? largest : small[s++]);
}

// The stored SH value (uint8) back to a coefficient in [-4, 4].
float unpack_sh(unsigned char v) {
  const double n = v == 0 ? 0.0 : v == 255 ? 1.0 : (v + 0.5) / 256.0;
  return static_cast<float>((n - 0.5) * 8.0);
}

}  // namespace

Scene parse_compressed_ply(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                           LoadProgress* progress) {
  report = LoadReport{};
  report.path = name;
  const ply::Header header = ply::parse_header(data, size, name);
  if (header.format != ply::Format::binary_little_endian)
    fail(name, "a compressed PLY must be binary_little_endian");
  const std::size_t n_elements = header.elements.size();
  if (n_elements < 2 || n_elements > 3 || header.elements[0].name != "chunk" || header.elements[1].name != "vertex" ||
      (n_elements == 3 && header.elements[2].name != "sh"))
    fail(name, "a compressed PLY has the elements \"chunk\", \"vertex\" and optionally \"sh\", in that order");
  const ply::Element& chunk = header.elements[0];
  const ply::Element& vertex = header.elements[1];
  const std::vector<long> bounds = property_offsets(chunk, kChunkProperties, kAllChunkProperties, kBoundsProperties,
                                                    "float", name);
  const bool chunk_colours = bounds[kBoundsProperties] >= 0;
  for (int k = kBoundsProperties; k < kAllChunkProperties; ++k)
    if ((bounds[static_cast<std::size_t>(k)] >= 0) != chunk_colours)
      fail(name, "the chunk element has some colour bounds (min_r .. max_b) but not all six");
  const std::vector<long> packed = property_offsets(vertex, kPackedProperties, 4, 4, "uint", name);

  const std::size_t count = vertex.count;
  if (count == 0) fail(name, "the header declares 0 vertices: there are no Gaussians");
  const std::size_t chunks_needed = count / kChunkGaussians + (count % kChunkGaussians != 0);
  if (chunk.count != chunks_needed)
    fail(name, "the header declares " + std::to_string(chunk.count) + " chunks for " + std::to_string(count) +
                   " vertices; 256 vertices per chunk need " + std::to_string(chunks_needed));

  int sh_degree = 0;
  std::size_t sh_values = 0;
  if (n_elements == 3) {
    const ply::Element& sh = header.elements[2];
    sh_values = sh.properties.size();
    for (int d = 1; d <= 3; ++d)
      if (sh_values == static_cast<std::size_t>((sh_coefficient_count(d) - 1) * 3)) sh_degree = d;
    if (sh_degree == 0)
      fail(name, "the sh element has " + std::to_string(sh_values) + " properties; SH degrees 1-3 need 9, 24 or 45");
    for (std::size_t k = 0; k < sh_values; ++k) {
      const ply::Property& p = sh.properties[k];
      if (p.name != "f_rest_" + std::to_string(k) || p.is_list() || p.type != "uchar")
        fail(name, "property " + std::to_string(k) + " of the sh element is " + quoted(p.name) + " of type " +
                       quoted(p.type) + "; expected f_rest_" + std::to_string(k) + " of type uchar");
    }
    if (sh.count != count)
      fail(name, "the sh element has " + std::to_string(sh.count) + " records for " + std::to_string(count) +
                     " vertices");
  }

  // Sizes checked against the bytes present before anything is read (counts first: no overflow).
  const std::size_t available = size - header.data_offset;
  const std::size_t vertex_bytes = 16 + sh_values;
  if (chunk.count > available / chunk.record_size || count > available / vertex_bytes)
    fail(name, "the header declares " + std::to_string(count) + " vertices (" + std::to_string(chunk.count) +
                   " chunks) but the file holds only " + std::to_string(available) +
                   " bytes after the header: truncated file or wrong vertex count");
  const std::size_t chunk_bytes = chunk.count * chunk.record_size;
  const std::size_t expected = chunk_bytes + count * vertex_bytes;
  if (expected != available)
    fail(name, "the header declares " + std::to_string(count) + " vertices and " + std::to_string(chunk.count) +
                   " chunks (" + std::to_string(expected) + " bytes of data) but the file has " +
                   std::to_string(available) + " bytes after the header: " +
                   (expected > available ? "truncated file or wrong count" : "extra data or wrong count"));

  const auto* chunk_data = reinterpret_cast<const unsigned char*>(data + header.data_offset);
  const unsigned char* vertex_data = chunk_data + chunk_bytes;
  const unsigned char* sh_data = vertex_data + count * 16;
  Scene scene;
  scene.sh_degree = sh_degree;
  scene.trained_kernel = kernel_from_ply_comments(header.comments);
  report.sh_degree_in_file = sh_degree;
  report.vertices_in_file = count;
  scene.reserve(count);
  const int per_channel = static_cast<int>(sh_values / 3);
  std::vector<float> rest(sh_values);
  DecodeProgress decoding(progress, name, count);
  float b[kAllChunkProperties] = {};
  for (std::size_t i = 0; i < count; ++i) {
    decoding.at(i);
    if (i % kChunkGaussians == 0) {
      const unsigned char* record = chunk_data + (i / kChunkGaussians) * chunk.record_size;
      for (int k = 0; k < kAllChunkProperties; ++k)
        if (bounds[static_cast<std::size_t>(k)] >= 0) b[k] = read_float(record + bounds[static_cast<std::size_t>(k)]);
    }
    const unsigned char* record = vertex_data + i * vertex.record_size;
    const std::uint32_t position = read_word(record + packed[0]);
    const std::uint32_t rotation = read_word(record + packed[1]);
    const std::uint32_t scale = read_word(record + packed[2]);
    const std::uint32_t colour = read_word(record + packed[3]);
    const double p[3] = {unorm(position, 21, 11), unorm(position, 11, 10), unorm(position, 0, 11)};
    const double s[3] = {unorm(scale, 21, 11), unorm(scale, 11, 10), unorm(scale, 0, 11)};
    DecodedGaussian g;
    for (int k = 0; k < 3; ++k) {
      g.position[k] = lerp(b[k], b[3 + k], p[k]);
      // The log-scale rounded to float before exp, as the format's own decompressor stores it.
      g.scale[k] = std::exp(static_cast<double>(static_cast<float>(lerp(b[6 + k], b[9 + k], s[k]))));
      const double c = unorm(colour, 24 - 8 * k, 8);
      g.sh_dc[k] = ((chunk_colours ? lerp(b[12 + k], b[15 + k], c) : c) - 0.5) / model::kShC0;
    }
    unpack_rotation(rotation, g.rotation);
    g.opacity = unorm(colour, 0, 8);
    // f_rest is channel-major in the file (all R, then G, then B); we keep [k][channel].
    const unsigned char* sh = sh_data + i * sh_values;
    for (int k = 0; k < per_channel; ++k)
      for (int ch = 0; ch < 3; ++ch) rest[static_cast<std::size_t>(k * 3 + ch)] = unpack_sh(sh[ch * per_channel + k]);
    append_gaussian(scene, g, rest.data(), report);
  }
  decoding.done(count);
  if (scene.size() == 0) fail(name, "all " + std::to_string(count) + " Gaussians have NaN or Inf attributes");
  return scene;
}

}  // namespace flashgs
