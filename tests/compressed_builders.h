// Test files in the compressed formats, written byte by byte: SPZ (gzip v1-3, zstd v4) from
// attribute bytes, and SOG v2 chunks from texture pixels (lossless WebP), all in memory.
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <webp/encode.h>
#include <zlib.h>
#include <zstd.h>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"

namespace flashgs::test {

// ---- SPZ ----

struct SpzContent {
  std::uint32_t version = 3;
  std::uint32_t count = 0;
  std::uint8_t sh_degree = 0, fractional_bits = 12, flags = 0;
  // positions, alphas, colours, scales, rotations, SH: the file's attribute order.
  std::vector<std::uint8_t> attribute[6];
};

inline std::size_t spz_sh_bytes(int degree) { return static_cast<std::size_t>((degree + 1) * (degree + 1) - 1) * 3; }

inline void put_u32(std::string& s, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>(v >> (8 * i) & 0xff));
}
inline void put_u64(std::string& s, std::uint64_t v) {
  put_u32(s, static_cast<std::uint32_t>(v));
  put_u32(s, static_cast<std::uint32_t>(v >> 32));
}

// Random but valid attribute bytes for `count` Gaussians.
inline SpzContent random_spz(std::uint32_t count, int degree, std::uint32_t version, std::mt19937& rng) {
  SpzContent c;
  c.version = version;
  c.count = count;
  c.sh_degree = static_cast<std::uint8_t>(degree);
  const std::size_t sizes[6] = {version == 1 ? 6u : 9u, 1, 3, 3, version >= 3 ? 4u : 3u, spz_sh_bytes(degree)};
  for (int a = 0; a < 6; ++a)
    for (std::size_t i = 0; i < count * sizes[a]; ++i) c.attribute[a].push_back(static_cast<std::uint8_t>(rng()));
  if (version == 1)  // half floats: keep exponents below 31 (no Inf/NaN) so every Gaussian loads
    for (std::size_t i = 1; i < c.attribute[0].size(); i += 2) c.attribute[0][i] &= 0x3f;
  return c;
}

inline std::string spz_payload(const SpzContent& c) {
  std::string s;
  put_u32(s, 0x5053474e);
  put_u32(s, c.version);
  put_u32(s, c.count);
  s.push_back(static_cast<char>(c.sh_degree));
  s.push_back(static_cast<char>(c.fractional_bits));
  s.push_back(static_cast<char>(c.flags));
  s.push_back(0);
  for (const auto& a : c.attribute) s.append(a.begin(), a.end());
  return s;
}

inline std::string gzip(const std::string& raw) {
  z_stream stream{};
  if (deflateInit2(&stream, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("deflateInit2");
  std::string out(deflateBound(&stream, raw.size()), '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
  stream.avail_in = static_cast<uInt>(raw.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  if (deflate(&stream, Z_FINISH) != Z_STREAM_END) throw std::runtime_error("deflate");
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

// Versions 1-3: the header and the attributes in one gzip stream.
inline std::string spz_gzip_file(const SpzContent& c) { return gzip(spz_payload(c)); }

inline std::string zstd(const std::vector<std::uint8_t>& raw) {
  std::string out(ZSTD_compressBound(raw.size()), '\0');
  const std::size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), 3);
  if (ZSTD_isError(n)) throw std::runtime_error("ZSTD_compress");
  out.resize(n);
  return out;
}

// Version 4: a 32-byte header, a table of contents (compressed, uncompressed sizes) and one
// zstd frame per attribute.
inline std::string spz_v4_file(const SpzContent& c) {
  const int streams = c.sh_degree > 0 ? 6 : 5;
  std::string s;
  put_u32(s, 0x5053474e);
  put_u32(s, 4);
  put_u32(s, c.count);
  s.push_back(static_cast<char>(c.sh_degree));
  s.push_back(static_cast<char>(c.fractional_bits));
  s.push_back(static_cast<char>(c.flags));
  s.push_back(static_cast<char>(streams));
  put_u32(s, 32);
  s.append(12, '\0');
  std::string frames;
  for (int a = 0; a < streams; ++a) {
    const std::string frame = zstd(c.attribute[a]);
    put_u64(s, frame.size());
    put_u64(s, c.attribute[a].size());
    frames += frame;
  }
  return s + frames;
}

// The attribute bytes of a version 4 file (the test's own reading of the layout).
inline SpzContent spz_v4_content(const std::vector<char>& file) {
  SpzContent c;
  const auto* b = reinterpret_cast<const unsigned char*>(file.data());
  auto u32 = [b](std::size_t at) { return std::uint32_t(b[at] | b[at + 1] << 8 | b[at + 2] << 16 | std::uint32_t(b[at + 3]) << 24); };
  c.version = u32(4);
  c.count = u32(8);
  c.sh_degree = b[12];
  c.fractional_bits = b[13];
  c.flags = b[14];
  const int streams = b[15];
  std::size_t offset = u32(16) + 16 * std::size_t(streams);
  for (int a = 0; a < streams && a < 6; ++a) {
    const std::size_t entry = u32(16) + 16 * std::size_t(a);
    const std::size_t compressed = u32(entry), uncompressed = u32(entry + 8);
    c.attribute[a].resize(uncompressed);
    ZSTD_decompress(c.attribute[a].data(), uncompressed, file.data() + offset, compressed);
    offset += compressed;
  }
  return c;
}

// ---- SOG v2 ----

struct SogTexture {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;
};

inline std::vector<char> lossless_webp(const SogTexture& t) {
  std::uint8_t* out = nullptr;
  const std::size_t n = WebPEncodeLosslessRGBA(t.rgba.data(), t.width, t.height, t.width * 4, &out);
  if (n == 0) throw std::runtime_error("WebPEncodeLosslessRGBA");
  std::vector<char> bytes(out, out + n);
  WebPFree(out);
  return bytes;
}

inline std::vector<char> lossy_webp(const SogTexture& t) {
  std::uint8_t* out = nullptr;
  const std::size_t n = WebPEncodeRGBA(t.rgba.data(), t.width, t.height, t.width * 4, 80, &out);
  if (n == 0) throw std::runtime_error("WebPEncodeRGBA");
  std::vector<char> bytes(out, out + n);
  WebPFree(out);
  return bytes;
}

// One chunk in memory: meta.json and its files, readable through a SogFileSource.
struct SogChunk {
  nlohmann::json meta;
  std::map<std::string, std::vector<char>> files;
  SogFileSource source() const {
    return [this](const std::string& file) {
      const auto it = files.find(file);
      if (it == files.end()) throw Error("chunk/" + file + ": cannot open: No such file or directory");
      return it->second;
    };
  }
  Scene parse(LoadReport* report = nullptr) const { return parse_sog(meta.dump(), source(), "chunk/meta.json", report); }
};

// A valid chunk of `count` Gaussians with random pixels (quaternion modes 252-255, labels
// inside the palette) on a `width`-wide square-ish texture, SH `bands` (0: no shN).
inline SogChunk random_sog_chunk(std::size_t count, int bands, std::mt19937& rng, int width = 0) {
  if (width == 0) {
    width = 4;
    while (static_cast<std::size_t>(width) * width < count) width += 4;
  }
  const int height = static_cast<int>((count + width - 1) / width);
  auto texture = [&](int w, int h) {
    SogTexture t{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h * 4)};
    for (auto& v : t.rgba) v = static_cast<std::uint8_t>(rng());
    return t;
  };
  SogChunk chunk;
  auto codebook = [&](double low, double high) {
    std::vector<double> values;
    for (int i = 0; i < 256; ++i) values.push_back(low + (high - low) * i / 255.0);
    return values;
  };
  chunk.meta = {{"version", 2},
                {"count", count},
                {"means", {{"mins", {-1.0, -2.0, -0.5}}, {"maxs", {1.0, 0.5, 2.0}}, {"files", {"means_l.webp", "means_u.webp"}}}},
                {"scales", {{"codebook", codebook(-8, -1)}, {"files", {"scales.webp"}}}},
                {"quats", {{"files", {"quats.webp"}}}},
                {"sh0", {{"codebook", codebook(-2, 3)}, {"files", {"sh0.webp"}}}}};
  for (const char* name : {"means_l.webp", "means_u.webp", "scales.webp", "sh0.webp"})
    chunk.files[name] = lossless_webp(texture(width, height));
  SogTexture quats = texture(width, height);
  for (std::size_t i = 0; i < quats.rgba.size(); i += 4) quats.rgba[i + 3] = static_cast<std::uint8_t>(252 + rng() % 4);
  chunk.files["quats.webp"] = lossless_webp(quats);
  if (bands > 0) {
    const int coefficients = (bands + 1) * (bands + 1) - 1;
    const std::size_t palette = 1 + rng() % 100;
    chunk.meta["shN"] = {{"count", palette}, {"bands", bands}, {"codebook", codebook(-1, 1)},
                         {"files", {"shN_centroids.webp", "shN_labels.webp"}}};
    chunk.files["shN_centroids.webp"] = lossless_webp(texture(64 * coefficients, static_cast<int>((palette + 63) / 64)));
    SogTexture labels = texture(width, height);
    for (std::size_t i = 0; i < labels.rgba.size(); i += 4) {
      const std::size_t label = rng() % palette;
      labels.rgba[i] = static_cast<std::uint8_t>(label & 0xff);
      labels.rgba[i + 1] = static_cast<std::uint8_t>(label >> 8);
    }
    chunk.files["shN_labels.webp"] = lossless_webp(labels);
  }
  return chunk;
}

// The same chunk as SOG version 1 (no "version"): the count in means.shape and ranges equal to
// the builder's linear codebooks, so it decodes alike but for the opacity (a logit range).
inline SogChunk sog_version_1(SogChunk chunk) {
  nlohmann::json& meta = chunk.meta;
  meta["means"]["shape"] = {meta["count"], 3};
  meta.erase("version");
  meta.erase("count");
  meta["scales"] = {{"mins", {-8, -8, -8}}, {"maxs", {-1, -1, -1}}, {"files", {"scales.webp"}}};
  meta["sh0"] = {{"mins", {-2, -2, -2, -5}}, {"maxs", {3, 3, 3, 5}}, {"files", {"sh0.webp"}}};
  if (meta.contains("shN"))
    meta["shN"] = {{"mins", -1}, {"maxs", 1}, {"files", {"shN_centroids.webp", "shN_labels.webp"}}};
  return chunk;
}

// A zip archive of the chunk (meta.json, then its textures), stored, as a .sog bundle is.
inline std::string sog_bundle(const SogChunk& chunk) {
  std::vector<std::pair<std::string, std::string>> entries = {{"meta.json", chunk.meta.dump()}};
  for (const auto& [name, bytes] : chunk.files) entries.push_back({name, std::string(bytes.begin(), bytes.end())});
  std::string out, directory;
  auto u16 = [](std::string& s, std::uint16_t v) { s.append(reinterpret_cast<const char*>(&v), 2); };
  for (const auto& [name, bytes] : entries) {
    const std::uint32_t crc = static_cast<std::uint32_t>(
        crc32(0, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
    const std::uint32_t offset = static_cast<std::uint32_t>(out.size()), size = static_cast<std::uint32_t>(bytes.size());
    auto common = [&](std::string& s) {
      u16(s, 20), u16(s, 0), u16(s, 0), u16(s, 0), u16(s, 0x21);
      put_u32(s, crc), put_u32(s, size), put_u32(s, size);
      u16(s, static_cast<std::uint16_t>(name.size())), u16(s, 0);
    };
    put_u32(out, 0x04034b50);
    common(out);
    out += name + bytes;
    put_u32(directory, 0x02014b50);
    u16(directory, 20);
    common(directory);
    u16(directory, 0), u16(directory, 0), u16(directory, 0);
    put_u32(directory, 0), put_u32(directory, offset);
    directory += name;
  }
  const std::uint32_t directory_offset = static_cast<std::uint32_t>(out.size());
  out += directory;
  put_u32(out, 0x06054b50);
  u16(out, 0), u16(out, 0), u16(out, static_cast<std::uint16_t>(entries.size())),
      u16(out, static_cast<std::uint16_t>(entries.size()));
  put_u32(out, static_cast<std::uint32_t>(directory.size()));
  put_u32(out, directory_offset);
  u16(out, 0);
  return out;
}

}  // namespace flashgs::test
