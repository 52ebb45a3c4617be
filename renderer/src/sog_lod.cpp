// SOG's streamed LOD set: lod-meta.json holds a tree of bounds whose leaves name, for each
// level, a range of Gaussians in one of its chunk files; a level is the union of its ranges.
#include <algorithm>
#include <filesystem>
#include <new>
#include <set>
#include <string>
#include <vector>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "flashgs/lod_set.h"
#include "sog_meta.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

// One level of the set: its leaves' ranges, in tree order.
std::vector<LodRange> level_ranges(const LodSet& set, int level) {
  std::vector<LodRange> ranges;
  for (const LodLeaf& leaf : set.leaves) {
    const LodRange& r = leaf.levels[static_cast<std::size_t>(level)];
    if (r.file >= 0 && r.count > 0) ranges.push_back(r);
  }
  return ranges;
}

// The chunk files a level reads, by index, in first-use order.
std::vector<int> level_files(const std::vector<LodRange>& ranges) {
  std::vector<int> files;
  std::set<int> seen;  // a hostile tree may name thousands of files
  for (const LodRange& r : ranges)
    if (seen.insert(r.file).second) files.push_back(r.file);
  return files;
}

// Host memory for decoding `gaussians` Gaussians of SH degree `sh_degree`: the scene's floats,
// plus the six per-Gaussian RGBA textures held while a chunk decodes.
std::uint64_t level_bytes(std::uint64_t gaussians, int sh_degree) {
  const std::uint64_t scene_bytes = sizeof(float) * (14 + 3 * std::uint64_t(sh_coefficient_count(sh_degree) - 1));
  return gaussians * (scene_bytes + 6 * 4);
}

void check_level(const LodSet& set, int level, const std::string& name) {
  if (level < 0 || level >= set.level_count)
    fail(name, "level " + std::to_string(level) + " does not exist (the set has levels 0.." +
                   std::to_string(set.level_count - 1) + ")");
}

}  // namespace

bool is_sog_lod_set(const std::string& path) {
  if (path_kind(path) != PathKind::regular_file) return false;
  const std::vector<char> head = read_recognition_start(path, 64 << 10);  // opened without blocking
  return looks_like_sog_lod_meta(std::string(head.begin(), head.end()));
}

SogLodSet describe_sog_lod(const std::string& path) {
  const LodSet lod = read_lod_set(path);
  SogLodSet set;
  set.path = lod.meta_path;
  set.bounds_min = lod.bound.min;
  set.bounds_max = lod.bound.max;
  for (int level = 0; level < lod.level_count; ++level) {
    check_lod_ranges(lod, level);
    SogLodLevel info;
    info.level = level;
    info.gaussians = lod.gaussians(level);
    for (int file : level_files(level_ranges(lod, level))) {
      info.files.push_back(lod.files[static_cast<std::size_t>(file)]);
      info.sh_degree = std::max(info.sh_degree, lod_chunk_sh_degree(lod.file_path(file)));
    }
    set.levels.push_back(info);
  }
  return set;
}

Scene read_sog_lod(const std::string& path, int level, LoadReport* report, LoadProgress* progress) {
  const LodSet meta = read_lod_set(path);
  const std::string name = meta.meta_path;
  check_level(meta, level, name);
  check_lod_ranges(meta, level);
  const std::vector<LodRange> ranges = level_ranges(meta, level);
  const std::uint64_t gaussians = meta.gaussians(level);
  int sh_degree = 0;
  for (int file : level_files(ranges)) sh_degree = std::max(sh_degree, lod_chunk_sh_degree(meta.file_path(file)));
  const std::uint64_t need = level_bytes(gaussians, sh_degree);
  const AvailableMemory available = available_host_memory();
  if (available.bytes > 0 && need > available.bytes)
    fail(name, "level " + std::to_string(level) + " holds " + std::to_string(gaussians) + " Gaussians, " +
                   format_bytes(need) + " to decode, but only " + format_bytes(available.bytes) +
                   " of memory is available");
  if (progress) {
    std::uint64_t total = 0;
    for (int file : level_files(ranges)) total += lod_chunk_bytes(meta.file_path(file));
    progress->bytes_done.store(0, std::memory_order_relaxed);
    progress->bytes_total.store(total, std::memory_order_relaxed);
  }
  Scene scene;
  LoadReport total;
  try {
    scene.reserve(gaussians);
    total.path = name;
    bool first = true;
    for (int file : level_files(ranges)) {
      const std::string chunk_name = meta.file_path(file);
      LoadReport chunk_report;
      const Scene chunk = read_lod_set_chunk(meta, file, &chunk_report, progress);
      if (chunk_report.dropped_non_finite)
        fail(chunk_name, "Gaussians with non-finite values: the level's ranges would no longer line up");
      if (!first && chunk.sh_degree != scene.sh_degree)
        fail(chunk_name, "SH degree " + std::to_string(chunk.sh_degree) + " differs from the level's other chunks (" +
                             std::to_string(scene.sh_degree) + ")");
      if (first) {
        scene.sh_degree = chunk.sh_degree;
        scene.trained_kernel = chunk.trained_kernel;
        total.format = chunk_report.format;  // the chunks' own format: SOG from PlayCanvas, PLY from lod build
        total.quantisation = chunk_report.quantisation;
        first = false;
      }
      total.sh_degree_in_file = std::max(total.sh_degree_in_file, chunk_report.sh_degree_in_file);
      for (const LodRange& r : ranges) {
        if (r.file != file) continue;
        if (r.offset > chunk.size() || r.count > chunk.size() - r.offset)  // a chunk that changed since its header was read
          fail(chunk_name, "holds " + std::to_string(chunk.size()) + " Gaussians once decoded, fewer than level " +
                               std::to_string(level) + "'s ranges take");
        scene.append_range(chunk, r.offset, r.count);
      }
    }
  } catch (const std::bad_alloc&) {  // the estimate above fell short of what decoding took
    fail(name, "out of memory while decoding level " + std::to_string(level) + " (" + std::to_string(gaussians) +
                   " Gaussians, about " + format_bytes(need) + "; " + format_bytes(available.bytes) + " was available)");
  }
  total.vertices_in_file = scene.size();
  if (report) *report = total;
  return scene;
}

std::uint64_t sog_lod_level_bytes(const SogLodLevel& level) { return level_bytes(level.gaussians, level.sh_degree); }

int choose_sog_lod_level(const SogLodSet& set, std::uint64_t available_bytes) {
  if (set.levels.empty()) return 0;
  if (available_bytes == 0) return 0;
  for (const SogLodLevel& level : set.levels)
    if (sog_lod_level_bytes(level) <= available_bytes / 2) return level.level;
  const SogLodLevel& coarsest = set.levels.back();
  fail(set.path, "no level fits: the coarsest, level " + std::to_string(coarsest.level) + ", holds " +
                     std::to_string(coarsest.gaussians) + " Gaussians, " +
                     format_bytes(sog_lod_level_bytes(coarsest)) + " to decode, more than half of the " +
                     format_bytes(available_bytes) + " of memory available");
}

}  // namespace flashgs
