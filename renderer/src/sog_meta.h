// SOG v2's meta.json, parsed and checked (counts, ranges, codebooks and texture names), and
// the chunk reading the LOD set builds on.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs {

// Real meta.json files are a few tens of KB (three 256-entry codebooks).
constexpr std::size_t kMaxSogJsonBytes = 16 << 20;
// The bytes format recognition looks at: the first `start_bytes` of the file, or, when those
// are whitespace and a JSON object's opening brace, up to kMaxSogJsonBytes of it: a valid
// meta.json or lod-meta.json may hold its keys past any fixed window (padding, a long
// filenames list), and anything else is still read no further than `start_bytes`.
std::vector<char> read_recognition_start(const std::string& path, std::size_t start_bytes);
// Whether `start` (a file's first bytes) may be a JSON object: whitespace, then '{' or nothing.
bool may_be_json_object(std::string_view start);
// A texture of 16384 x 16384 lossless pixels compresses to well under this.
constexpr std::size_t kMaxSogTextureBytes = std::size_t{1} << 30;
// The most Gaussians one chunk may declare (a 16384 x 16384 texture).
constexpr std::size_t kMaxSogCount = std::size_t{1} << 28;
// Entries per row of the SH palette texture (the format's fixed layout).
constexpr int kCentroidsPerRow = 64;

struct SogMeta {
  int version = 2;  // 1: no "version" key, per-channel ranges instead of codebooks
  std::size_t count = 0;
  std::array<double, 3> means_min{}, means_max{};
  std::array<std::string, 2> means_files;  // lower bytes, upper bytes
  std::string scales_file, quats_file, sh0_file;
  // What each byte of a texture decodes to, per channel (256 entries each): version 2's
  // codebook for all three, version 1's range lerped per channel. The log-scale, f_dc, and
  // (version 1 only; empty for version 2, whose byte is the opacity / 255) the opacity.
  std::array<std::vector<float>, 3> scales_tables, sh0_tables;
  std::vector<float> opacity_table;
  int sh_bands = 0;  // 0 when there is no shN; version 1: known only from the centroids' width
  bool sh_bands_from_texture = false;
  std::size_t sh_palette_size = 0;
  std::vector<float> sh_codebook;
  std::array<std::string, 2> sh_files;  // centroids, labels
  TrainedKernel kernel;  // from the optional "model" entry
};

// Version 1 (no "version" key) or 2. Throws flashgs::Error "<name>: ..." for invalid JSON, another version, a missing or
// mistyped field, a count out of range, a codebook that is not 256 finite floats, or a texture
// name that is not a plain file name.
SogMeta parse_sog_meta(const std::string& json_text, const std::string& name);
// The texture files meta.json names, in decoding order.
std::vector<std::string> sog_meta_files(const SogMeta& meta);

// Bytes on disk of the textures the chunk at `meta_path` names, for progress totals.
std::uint64_t sog_chunk_texture_bytes(const std::string& meta_path);
// Reads the chunk at `meta_path`, adding its texture bytes to progress's bytes_done but
// leaving the totals to the caller (a LOD level sums its chunks).
Scene read_sog_chunk(const std::string& meta_path, LoadReport* report, LoadProgress* progress);

}  // namespace flashgs
