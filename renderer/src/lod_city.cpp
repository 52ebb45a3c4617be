// The instanced city: a base LOD set placed block by block on the city grid, by reference.
#include "flashgs/lod_city.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "flashgs/city_scene.h"
#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"
#include "flashgs/lod_build.h"
#include "flashgs/rotation.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

constexpr const char* kBaseLink = "base";  // the city folder's link to the base set's folder
constexpr int kMaxBlocks = 1 << 16;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

// Nodes over leaves [first, first + count) halved until one leaf each, the root last: leaves
// in spatial order stay spatial neighbours in the tree.
int add_nodes(int first, int count, std::vector<LodTreeNode>& nodes) {
  LodTreeNode node;
  node.first_leaf = first;
  node.leaf_count = count;
  if (count > 1) {
    const int half = count / 2;
    node.children[0] = add_nodes(first, half, nodes);
    node.children[1] = add_nodes(first + half, count - half, nodes);
  }
  nodes.push_back(node);
  return static_cast<int>(nodes.size()) - 1;
}

std::vector<LodTreeNode> balanced_tree(const LodSet& set) {
  std::vector<LodTreeNode> nodes;
  add_nodes(0, static_cast<int>(set.leaves.size()), nodes);
  return nodes;
}

LodBox union_bound(const std::vector<LodLeaf>& leaves) {
  LodBox box;
  box.min.fill(std::numeric_limits<float>::max());
  box.max.fill(std::numeric_limits<float>::lowest());
  for (const LodLeaf& leaf : leaves)
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], leaf.bound.min[k]);
      box.max[k] = std::max(box.max[k], leaf.bound.max[k]);
    }
  return box;
}

std::uint64_t file_bytes(const std::string& path) {
  std::error_code error;
  const std::uintmax_t bytes = fs::file_size(path, error);
  return error ? 0 : bytes;
}

}  // namespace

std::uint64_t materialize_lod_set(const LodSet& set, const std::string& out_folder, LodChunkFormat format) {
  prepare_lod_folder(out_folder);
  LodSet plain = set;
  plain.folder = out_folder;
  plain.instances.clear();
  plain.file_instance.clear();
  std::uint64_t written = 0;
  for (std::size_t f = 0; f < set.files.size(); ++f) {
    plain.files[f] = lod_chunk_name("chunk-" + std::to_string(f), format);
    written += write_lod_chunk(read_lod_set_chunk(set, static_cast<int>(f)), (fs::path(out_folder) / plain.files[f]).string(), format);
  }
  for (LodLeaf& leaf : plain.leaves) leaf.instance = -1;
  const std::string meta = (fs::path(out_folder) / "lod-meta.json").string();
  write_lod_meta(plain, balanced_tree(plain), meta);
  return written + file_bytes(meta);
}

LodCityReport write_lod_city(const std::string& base, const std::string& out_folder, const LodCityOptions& options) {
  if (options.blocks < 1 || options.blocks > kMaxBlocks)
    fail(out_folder, "--blocks must be 1.." + std::to_string(kMaxBlocks));
  if (!(options.spacing >= 0) || !std::isfinite(options.spacing)) fail(out_folder, "--spacing must be a finite number >= 0");
  const LodSet set = read_lod_set(base);
  if (!set.instances.empty())
    fail(set.meta_path, "is already an instanced set: make the city from the plain set it draws");
  // The coarsest level is small and spread like the whole: it places the base.
  const Scene coarse = read_sog_lod(set.meta_path, set.level_count - 1);
  const CityPlacement placement = place_city_source(coarse, options.up, set.meta_path);

  LodCityReport report;
  report.blocks = options.blocks;
  report.side = city_side(options.blocks);
  report.spacing = options.spacing > 0 ? options.spacing : 1.1 * placement.width;
  LodSet city;
  city.level_count = set.level_count;
  city.folder = set.folder;  // read_lod_set_chunk reads the base's files until the city is written
  for (int b = 0; b < options.blocks; ++b) {
    double m[9], q[4];
    LodInstance instance;
    city_block_transform(placement, b, report.side, report.spacing, m, instance.translation.data());
    quaternion_from_matrix(m, q);
    std::copy(q, q + 4, instance.rotation.begin());
    city.instances.push_back(instance);
    for (const LodLeaf& leaf : set.leaves) {
      LodLeaf placed = leaf;
      placed.instance = b;
      placed.bound = transformed_bound(leaf.bound, instance);
      for (LodRange& r : placed.levels)
        if (r.file >= 0) r.file += b * static_cast<int>(set.files.size());
      city.leaves.push_back(std::move(placed));
    }
    for (const std::string& file : set.files) {
      city.files.push_back(file);
      city.file_instance.push_back(b);
    }
  }
  city.bound = union_bound(city.leaves);
  report.bound = city.bound;
  for (int level = 0; level < city.level_count; ++level) report.level_gaussians.push_back(city.gaussians(level));
  for (int f = 0; f < static_cast<int>(set.files.size()); ++f) report.chunk_bytes += lod_chunk_bytes(set.file_path(f));
  report.chunk_bytes *= static_cast<std::uint64_t>(options.blocks);
  report.files = static_cast<int>(set.files.size());

  const fs::path out(out_folder);
  if (options.materialize) {
    report.written_bytes = materialize_lod_set(city, out_folder, options.chunk_format);
    report.files = static_cast<int>(city.files.size());
  } else {
    std::error_code error;
    const fs::path base_folder = fs::absolute(set.folder.empty() ? fs::path(".") : fs::path(set.folder), error);
    const fs::path target = error ? fs::path() : fs::relative(base_folder, fs::absolute(out, error), error);
    if (error || target.empty()) fail(set.meta_path, "its folder cannot be reached from " + out_folder + " by a relative path");
    prepare_lod_folder(out_folder);
    fs::create_directory_symlink(target, out / kBaseLink, error);
    if (error) fail((out / kBaseLink).string(), "cannot create the link to the base set: " + error.message());
    for (std::string& file : city.files) file = (fs::path(kBaseLink) / file).string();
    city.folder = out_folder;
    const std::string meta = (out / "lod-meta.json").string();
    write_lod_meta(city, balanced_tree(city), meta);
    report.written_bytes = file_bytes(meta);
  }
  const std::string cameras = (out / "cameras.json").string();
  save_cameras(city_camera_path(report.side, report.spacing, options.path_cameras, options.width, options.height), cameras);
  report.written_bytes += file_bytes(cameras);
  return report;
}

}  // namespace flashgs
