// SOG's streamed LOD set: lod-meta.json holds a tree of bounds whose leaves name, for each
// level, a range of Gaussians in one of its chunk files; a level is the union of its ranges.
#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "sog_meta.h"

namespace flashgs {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kMaxLevels = 32;
// Deeper trees than this are not a spatial hierarchy but a hostile file.
constexpr int kMaxTreeDepth = 64;
constexpr std::size_t kMaxFileNameBytes = 1024;

// The name may come from a file (a texture or chunk named in JSON) or a user's argument.
[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

// One leaf's share of a level: Gaussians [offset, offset + count) of chunk `file`.
struct Range {
  int file = 0;
  std::size_t offset = 0, count = 0;
};

struct LodMeta {
  fs::path folder;
  std::vector<std::string> files;          // chunk meta.json paths, relative to the folder
  std::vector<std::vector<Range>> levels;  // per level, in tree order
  std::array<float, 3> bounds_min{}, bounds_max{};
};

fs::path lod_meta_path(const std::string& path) {
  return path_kind(path) == PathKind::folder ? fs::path(path) / "lod-meta.json" : fs::path(path);
}

std::size_t whole(const json& value, std::size_t high, const std::string& where, const std::string& name) {
  if (!value.is_number_unsigned() || value.get<unsigned long long>() > high)
    fail(name, where + " must be a whole number in 0.." + std::to_string(high));
  return static_cast<std::size_t>(value.get<unsigned long long>());
}

// A relative path inside the set's folder: no absolute paths, no "..".
std::string chunk_file(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_string()) fail(name, where + " is not a file name");
  const std::string file = value.get<std::string>();
  const fs::path path(file);
  bool escapes = file.empty() || file.size() > kMaxFileNameBytes || path.is_absolute() ||
                 file.find('\0') != std::string::npos;
  for (const auto& part : path) escapes |= part == "..";
  if (escapes) fail(name, where + " \"" + printable_file_text(file) + "\" is not a path inside the set's folder");
  return file;
}

void read_bound(const json& node, LodMeta& meta, const std::string& name) {
  if (!node.contains("bound")) return;
  const json& bound = node.at("bound");
  for (const char* key : {"min", "max"}) {
    if (!bound.is_object() || !bound.contains(key) || !bound.at(key).is_array() || bound.at(key).size() != 3)
      fail(name, std::string("tree.bound.") + key + " must be an array of 3 numbers");
    for (int k = 0; k < 3; ++k) {
      const json& v = bound.at(key)[k];
      if (!v.is_number()) fail(name, std::string("tree.bound.") + key + " holds a value that is not a number");
      (key[1] == 'i' ? meta.bounds_min : meta.bounds_max)[k] = v.get<float>();
    }
  }
}

void walk(const json& node, int depth, LodMeta& meta, const std::string& name) {
  if (depth > kMaxTreeDepth) fail(name, "the tree is deeper than " + std::to_string(kMaxTreeDepth) + " levels");
  if (!node.is_object()) fail(name, "a tree node is not a JSON object");
  if (node.contains("children")) {
    const json& children = node.at("children");
    if (!children.is_array()) fail(name, "a tree node's \"children\" is not an array");
    for (const json& child : children) walk(child, depth + 1, meta, name);
    return;
  }
  if (!node.contains("lods") || !node.at("lods").is_object()) fail(name, "a tree leaf has no \"lods\" object");
  for (const auto& [key, entry] : node.at("lods").items()) {
    if (key.empty() || key.size() > 2 || key.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(key) >= static_cast<int>(meta.levels.size()))
      fail(name, "a tree leaf names level \"" + printable_file_text(key) + "\"; lodLevels is " +
                     std::to_string(meta.levels.size()));
    if (!entry.is_object() || !entry.contains("file") || !entry.contains("offset") || !entry.contains("count"))
      fail(name, "a tree leaf's level " + printable_file_text(key) + " lacks file, offset or count");
    Range range;
    range.file = static_cast<int>(whole(entry.at("file"), meta.files.size() - 1, "a leaf's file index", name));
    range.offset = whole(entry.at("offset"), kMaxSogCount, "a leaf's offset", name);
    range.count = whole(entry.at("count"), kMaxSogCount, "a leaf's count", name);
    meta.levels[std::stoi(key)].push_back(range);
  }
}

LodMeta read_lod_meta(const fs::path& path) {
  const std::string name = path.string();
  const std::vector<char> bytes = read_regular_file(name, kMaxSogJsonBytes);
  json root;
  try {
    root = json::parse(bytes.begin(), bytes.end());
  } catch (const json::exception& e) {
    fail(name, std::string("not valid JSON (") + printable_file_text(e.what()) + ")");
  }
  if (!root.is_object() || !root.contains("lodLevels") || !root.contains("filenames") || !root.contains("tree"))
    fail(name, "not a SOG lod-meta.json (it needs lodLevels, filenames and tree)");
  LodMeta meta;
  meta.folder = path.parent_path();
  const std::size_t levels = whole(root.at("lodLevels"), kMaxLevels, "lodLevels", name);
  if (levels == 0) fail(name, "lodLevels is 0: the set has no level");
  meta.levels.resize(levels);
  const json& filenames = root.at("filenames");
  if (!filenames.is_array() || filenames.empty()) fail(name, "filenames must be a non-empty array");
  for (std::size_t i = 0; i < filenames.size(); ++i)
    meta.files.push_back(chunk_file(filenames[i], "filenames[" + std::to_string(i) + "]", name));
  read_bound(root.at("tree"), meta, name);
  walk(root.at("tree"), 0, meta, name);
  for (std::size_t level = 0; level < levels; ++level)
    if (meta.levels[level].empty()) fail(name, "level " + std::to_string(level) + " has no Gaussians in the tree");
  return meta;
}

// The chunk files a level reads, by index, in first-use order.
std::vector<int> level_files(const std::vector<Range>& ranges) {
  std::vector<int> files;
  for (const Range& r : ranges)
    if (std::find(files.begin(), files.end(), r.file) == files.end()) files.push_back(r.file);
  return files;
}

void check_level(const LodMeta& meta, int level, const std::string& name) {
  if (level < 0 || level >= static_cast<int>(meta.levels.size()))
    fail(name, "level " + std::to_string(level) + " does not exist (the set has levels 0.." +
                   std::to_string(meta.levels.size() - 1) + ")");
}

}  // namespace

bool is_sog_lod_set(const std::string& path) {
  if (path_kind(path) != PathKind::regular_file) return false;
  const std::vector<char> head = read_recognition_start(path, 64 << 10);  // opened without blocking
  return looks_like_sog_lod_meta(std::string(head.begin(), head.end()));
}

SogLodSet describe_sog_lod(const std::string& path) {
  const fs::path meta_path = lod_meta_path(path);
  const LodMeta meta = read_lod_meta(meta_path);
  SogLodSet set;
  set.path = meta_path.string();
  set.bounds_min = meta.bounds_min;
  set.bounds_max = meta.bounds_max;
  for (std::size_t level = 0; level < meta.levels.size(); ++level) {
    SogLodLevel info;
    info.level = static_cast<int>(level);
    for (const Range& r : meta.levels[level]) info.gaussians += r.count;
    for (int file : level_files(meta.levels[level])) {
      info.files.push_back(meta.files[file]);
      const std::string chunk = (meta.folder / meta.files[file]).string();
      const std::vector<char> text = read_regular_file(chunk, kMaxSogJsonBytes);
      info.sh_degree = std::max(info.sh_degree, parse_sog_meta(std::string(text.begin(), text.end()), chunk).sh_bands);
    }
    set.levels.push_back(info);
  }
  return set;
}

Scene read_sog_lod(const std::string& path, int level, LoadReport* report, LoadProgress* progress) {
  const fs::path meta_path = lod_meta_path(path);
  const std::string name = meta_path.string();
  const LodMeta meta = read_lod_meta(meta_path);
  check_level(meta, level, name);
  const std::vector<Range>& ranges = meta.levels[level];
  if (progress) {
    std::uint64_t total = 0;
    for (int file : level_files(ranges)) total += sog_chunk_texture_bytes((meta.folder / meta.files[file]).string());
    progress->bytes_done.store(0, std::memory_order_relaxed);
    progress->bytes_total.store(total, std::memory_order_relaxed);
  }
  Scene scene;
  LoadReport total;
  total.path = name;
  bool first = true;
  for (int file : level_files(ranges)) {
    const std::string chunk_name = (meta.folder / meta.files[file]).string();
    LoadReport chunk_report;
    const Scene chunk = read_sog_chunk(chunk_name, &chunk_report, progress);
    if (chunk_report.dropped_non_finite)
      fail(chunk_name, "Gaussians with non-finite values: the level's ranges would no longer line up");
    if (!first && chunk.sh_degree != scene.sh_degree)
      fail(chunk_name, "SH degree " + std::to_string(chunk.sh_degree) + " differs from the level's other chunks (" +
                           std::to_string(scene.sh_degree) + ")");
    if (first) {
      scene.sh_degree = chunk.sh_degree;
      scene.trained_kernel = chunk.trained_kernel;
      first = false;
    }
    total.sh_degree_in_file = std::max(total.sh_degree_in_file, chunk_report.sh_degree_in_file);
    for (const Range& r : ranges) {
      if (r.file != file) continue;
      if (r.offset > chunk.size() || r.count > chunk.size() - r.offset)
        fail(name, "level " + std::to_string(level) + " takes Gaussians " + std::to_string(r.offset) + ".." +
                       std::to_string(r.offset + r.count) + " of " + meta.files[file] + ", which has " +
                       std::to_string(chunk.size()));
      Scene part;
      part.sh_degree = chunk.sh_degree;
      const auto take = [&r](const std::vector<float>& from, std::size_t per, std::vector<float>& to) {
        to.assign(from.begin() + r.offset * per, from.begin() + (r.offset + r.count) * per);
      };
      take(chunk.positions, 3, part.positions);
      take(chunk.scales, 3, part.scales);
      take(chunk.rotations, 4, part.rotations);
      take(chunk.opacities, 1, part.opacities);
      take(chunk.sh_dc, 3, part.sh_dc);
      take(chunk.sh_rest, static_cast<std::size_t>(chunk.sh_rest_per_gaussian()), part.sh_rest);
      scene.append(part);
    }
  }
  total.vertices_in_file = scene.size();
  if (report) *report = total;
  return scene;
}

std::uint64_t sog_lod_level_bytes(const SogLodLevel& level) {
  // The scene's floats, plus the six per-Gaussian RGBA textures held while decoding.
  const std::uint64_t scene_bytes = sizeof(float) * (14 + 3 * std::uint64_t(sh_coefficient_count(level.sh_degree) - 1));
  return level.gaussians * (scene_bytes + 6 * 4);
}

int choose_sog_lod_level(const SogLodSet& set, std::uint64_t available_bytes) {
  if (set.levels.empty()) return 0;
  if (available_bytes == 0) return 0;
  for (const SogLodLevel& level : set.levels)
    if (sog_lod_level_bytes(level) <= available_bytes / 2) return level.level;
  return set.levels.back().level;
}

}  // namespace flashgs
