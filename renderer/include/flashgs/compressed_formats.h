// Readers for the compressed splat formats SPZ (Niantic) and SOG v2 (PlayCanvas), including
// SOG's streamed level-of-detail set.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "flashgs/load_progress.h"
#include "flashgs/scene.h"
#include "flashgs/scene_formats.h"

namespace flashgs {

// ---- SPZ ----

// Whether `data` is an SPZ file: a gzip stream that inflates to the "NGSP" magic (versions
// 1-3), or that magic bare (version 4).
bool looks_like_spz(const char* data, std::size_t size);
// Reads an SPZ file (versions 1-4: gzip, or zstd streams with a table of contents). Every
// count is checked against what the file can hold before memory is taken. Throws
// flashgs::Error naming the file and the problem, flashgs::LoadCancelled on request.
// `axes`: whether the file is in Niantic's axes (turned to PLY's) or already in PLY's.
Scene read_spz(const std::string& path, LoadReport* report = nullptr, LoadProgress* progress = nullptr,
               SpzAxes axes = SpzAxes::niantic);
// Same, from bytes in memory (`name` is used in messages). The fuzz test drives this.
Scene parse_spz(const char* data, std::size_t size, const std::string& name, LoadReport* report = nullptr,
                LoadProgress* progress = nullptr, SpzAxes axes = SpzAxes::niantic);

// ---- SOG v2 (one chunk: meta.json and its WebP textures) ----

// Whether `text` (the start of a JSON file) is a SOG meta.json / a SOG lod-meta.json.
bool looks_like_sog_meta(const std::string& text);
bool looks_like_sog_lod_meta(const std::string& text);
// Reads one SOG chunk: `path` is its meta.json or the folder holding it.
Scene read_sog(const std::string& path, LoadReport* report = nullptr, LoadProgress* progress = nullptr);
// The texture files of a chunk, by the name meta.json gives them; throws flashgs::Error.
using SogFileSource = std::function<std::vector<char>(const std::string& file_name)>;
// Same, from meta.json's text and a source of its files (`name` is used in messages). The
// fuzz test drives this with files in memory.
Scene parse_sog(const std::string& meta_json, const SogFileSource& files, const std::string& name,
                LoadReport* report = nullptr, LoadProgress* progress = nullptr);

// A SOG meta.json or lod-meta.json whose bytes the caller read from `path` (the textures and
// chunks are found beside it); a LOD set loads the finest level that fits in memory.
Scene parse_sog_file(const char* data, std::size_t size, const std::string& path, LoadReport* report = nullptr,
                     LoadProgress* progress = nullptr);

// ---- SOG LOD set (lod-meta.json: a tree of bounds whose leaves name chunk ranges per level) ----

struct SogLodLevel {
  int level = 0;              // 0 is the finest
  std::size_t gaussians = 0;  // what loading this level gives
  int sh_degree = 0;          // of the level's chunks (from their meta.json)
  std::vector<std::string> files;  // the chunk meta.json files it reads, relative to the set
};
struct SogLodSet {
  std::string path;  // the lod-meta.json
  std::vector<SogLodLevel> levels;
  std::array<float, 3> bounds_min{}, bounds_max{};
};
// Whether `path` is a regular file that starts like a SOG lod-meta.json (64 KB are read).
bool is_sog_lod_set(const std::string& path);
// Reads lod-meta.json (`path`: the file, or the folder holding it) and each level's chunk
// meta.json (for the count and SH degree); decodes no texture. Throws flashgs::Error unless
// each level's leaves split its chunk files between them (ranges inside the file, disjoint,
// covering it).
SogLodSet describe_sog_lod(const std::string& path);
// Decodes level `level` of the set (every leaf's range of that level, in tree order), after
// the checks above and one of its memory against what is available.
Scene read_sog_lod(const std::string& path, int level, LoadReport* report = nullptr,
                   LoadProgress* progress = nullptr);
// Host memory that decoding and keeping level `level` takes (the scene and its textures).
std::uint64_t sog_lod_level_bytes(const SogLodLevel& level);
// The finest level whose bytes fit in half of `available_bytes` (the rest is left to the
// renderer); the finest when `available_bytes` is 0 (unknown). Throws flashgs::Error naming
// the set and the figures when not even the coarsest fits.
int choose_sog_lod_level(const SogLodSet& set, std::uint64_t available_bytes);

}  // namespace flashgs
