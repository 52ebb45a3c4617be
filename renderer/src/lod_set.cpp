// lod-meta.json read into a LodSet (leaves with bounds and per-level ranges) and written from one.
#include "flashgs/lod_set.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/file_write.h"
#include "flashgs/scene_formats.h"
#include "ply_header.h"
#include "sog_meta.h"

namespace flashgs {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kMaxLevels = 32;
// Deeper trees than this are not a spatial hierarchy but a hostile file.
constexpr int kMaxTreeDepth = 64;
constexpr std::size_t kMaxFileNameBytes = 1024;
constexpr std::size_t kMaxInstances = 1 << 20;
// lod-meta.json grows with the leaves (about 500 bytes each with 7 levels): a city of 1,000
// blocks of 256 leaves (3 billion Gaussians) is about 130 MB, which parses into several times that.
constexpr std::size_t kMaxLodMetaBytes = std::size_t{256} << 20;

// The name may come from a file (a chunk named in JSON) or a user's argument.
[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

std::uint64_t whole(const json& value, std::uint64_t high, const std::string& where, const std::string& name) {
  if (!value.is_number_unsigned() || value.get<unsigned long long>() > high)
    fail(name, where + " must be a whole number in 0.." + std::to_string(high));
  return value.get<unsigned long long>();
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

LodBox read_bound(const json& node, const LodBox& inherited, const std::string& name) {
  if (!node.contains("bound")) return inherited;
  const json& bound = node.at("bound");
  LodBox box;
  for (const char* key : {"min", "max"}) {
    if (!bound.is_object() || !bound.contains(key) || !bound.at(key).is_array() || bound.at(key).size() != 3)
      fail(name, std::string("tree.bound.") + key + " must be an array of 3 numbers");
    for (int k = 0; k < 3; ++k) {
      const json& v = bound.at(key)[k];
      if (!v.is_number() || !std::isfinite(v.get<double>()))
        fail(name, std::string("tree.bound.") + key + " holds a value that is not a finite number");
      (key[1] == 'i' ? box.min : box.max)[k] = v.get<float>();
    }
  }
  return box;
}

void walk(const json& node, const LodBox& parent_bound, int depth, LodSet& set, const std::string& name) {
  if (depth > kMaxTreeDepth) fail(name, "the tree is deeper than " + std::to_string(kMaxTreeDepth) + " levels");
  if (!node.is_object()) fail(name, "a tree node is not a JSON object");
  const LodBox bound = read_bound(node, parent_bound, name);
  if (node.contains("children")) {
    const json& children = node.at("children");
    if (!children.is_array()) fail(name, "a tree node's \"children\" is not an array");
    for (const json& child : children) walk(child, bound, depth + 1, set, name);
    return;
  }
  if (!node.contains("lods") || !node.at("lods").is_object()) fail(name, "a tree leaf has no \"lods\" object");
  LodLeaf leaf;
  leaf.bound = bound;
  leaf.levels.resize(static_cast<std::size_t>(set.level_count));
  for (const auto& [key, entry] : node.at("lods").items()) {
    if (key.empty() || key.size() > 2 || key.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(key) >= set.level_count)
      fail(name, "a tree leaf names level \"" + printable_file_text(key) + "\"; lodLevels is " +
                     std::to_string(set.level_count));
    if (!entry.is_object() || !entry.contains("file") || !entry.contains("offset") || !entry.contains("count"))
      fail(name, "a tree leaf's level " + printable_file_text(key) + " lacks file, offset or count");
    LodRange& range = leaf.levels[static_cast<std::size_t>(std::stoi(key))];
    range.file = static_cast<int>(whole(entry.at("file"), set.files.size() - 1, "a leaf's file index", name));
    range.offset = whole(entry.at("offset"), kMaxSogCount, "a leaf's offset", name);
    range.count = whole(entry.at("count"), kMaxSogCount, "a leaf's count", name);
  }
  if (node.contains("instance")) {
    if (set.instances.empty()) fail(name, "a tree leaf names an instance but the set has no \"instances\"");
    leaf.instance = static_cast<int>(whole(node.at("instance"), set.instances.size() - 1, "a leaf's instance index", name));
  }
  set.leaves.push_back(std::move(leaf));
}

template <std::size_t N>
std::array<double, N> numbers(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_array() || value.size() != N) fail(name, where + " must be an array of " + std::to_string(N) + " numbers");
  std::array<double, N> out{};
  for (std::size_t k = 0; k < N; ++k) {
    if (!value[k].is_number() || !std::isfinite(value[k].get<double>()))
      fail(name, where + " holds a value that is not a finite number");
    out[k] = value[k].get<double>();
  }
  return out;
}

// "instances": [{"rotation": [w, x, y, z], "translation": [x, y, z], "scale": s}, ...]; the
// scale may be left out (1).
std::vector<LodInstance> read_instances(const json& list, const std::string& name) {
  if (!list.is_array() || list.empty() || list.size() > kMaxInstances)
    fail(name, "\"instances\" must be an array of 1.." + std::to_string(kMaxInstances) + " objects");
  std::vector<LodInstance> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = "instances[" + std::to_string(i) + "]";
    const json& entry = list[i];
    if (!entry.is_object() || !entry.contains("rotation") || !entry.contains("translation"))
      fail(name, where + " must be an object with rotation and translation");
    LodInstance instance;
    instance.rotation = numbers<4>(entry.at("rotation"), where + ".rotation", name);
    instance.translation = numbers<3>(entry.at("translation"), where + ".translation", name);
    if (entry.contains("scale")) {
      if (!entry.at("scale").is_number()) fail(name, where + ".scale is not a number");
      instance.scale = entry.at("scale").get<double>();
    }
    const std::string problem = lod_instance_problem(instance);
    if (!problem.empty()) fail(name, where + ": " + problem);
    double norm = 0;  // within 1e-3 of 1: made exact, so that the Gaussians' quaternions stay unit
    for (double v : instance.rotation) norm += v * v;
    for (double& v : instance.rotation) v /= std::sqrt(norm);
    out.push_back(instance);
  }
  return out;
}

// An instanced set's files become one entry per (file, instance) its leaves name, in order of
// first use, so that each instance's copy of a chunk is a chunk of its own downstream.
void split_files_by_instance(LodSet& set) {
  std::map<std::pair<int, int>, int> entry_of;
  std::vector<std::string> files;
  for (LodLeaf& leaf : set.leaves)
    for (LodRange& r : leaf.levels) {
      if (r.file < 0) continue;
      const auto [it, fresh] = entry_of.emplace(std::make_pair(r.file, leaf.instance), static_cast<int>(files.size()));
      if (fresh) {
        files.push_back(set.files[static_cast<std::size_t>(r.file)]);
        set.file_instance.push_back(leaf.instance);
      }
      r.file = it->second;
    }
  set.files = std::move(files);
}

// A set's chunks are SOG chunks (meta.json, as PlayCanvas writes them) or scene files of any
// format we read (PLY, as `flashgs lod build` writes them).
bool is_sog_chunk(const std::string& path) { return fs::path(path).extension() == ".json"; }

std::uint64_t chunk_bytes_internal(const std::string& path) {
  if (is_sog_chunk(path)) return sog_chunk_texture_bytes(path);
  std::error_code error;
  const std::uint64_t bytes = fs::file_size(path, error);
  return error ? 0 : bytes;
}

int chunk_sh_degree(const std::string& path) {
  if (is_sog_chunk(path)) {
    const std::vector<char> text = read_regular_file(path, kMaxSogJsonBytes);
    return parse_sog_meta(std::string(text.begin(), text.end()), path).sh_bands;
  }
  const std::vector<char> head = read_recognition_start(path, 64 << 10);
  const ply::Header header = ply::parse_header(head.data(), head.size(), path);
  int rest = 0;
  bool vertex = false;
  for (const ply::Element& e : header.elements)
    if (e.name == "vertex") {
      vertex = true;
      for (const ply::Property& p : e.properties) rest += p.name.rfind("f_rest_", 0) == 0;
    }
  if (!vertex) fail(path, "the header declares no vertex element");
  for (int degree = 3; degree > 0; --degree)
    if (rest >= 3 * (sh_coefficient_count(degree) - 1)) return degree;
  return 0;
}

std::uint64_t chunk_gaussians(const std::string& path) {
  if (is_sog_chunk(path)) {
    const std::vector<char> text = read_regular_file(path, kMaxSogJsonBytes);
    return parse_sog_meta(std::string(text.begin(), text.end()), path).count;
  }
  const std::vector<char> head = read_recognition_start(path, 64 << 10);
  const ply::Header header = ply::parse_header(head.data(), head.size(), path);
  for (const ply::Element& e : header.elements)
    if (e.name == "vertex") return e.count;
  fail(path, "the header declares no vertex element");
}

std::string gaussian_span(std::uint64_t begin, std::uint64_t end) {
  return "Gaussians " + std::to_string(begin) + ".." + std::to_string(end - 1);
}

Scene read_chunk_internal(const std::string& path, LoadReport* report, LoadProgress* progress) {
  if (!is_sog_chunk(path)) return load_scene_file(path, report, progress);
  Scene scene = read_sog_chunk(path, report, progress);
  if (report) {  // a SOG chunk's reader leaves the format to the file-type dispatch, which it skipped
    report->format = format_name(SceneFormat::sog);
    report->quantisation = format_quantisation(SceneFormat::sog);
  }
  return scene;
}

// The double whose shortest decimal is the float's (at most 9 digits, where the float widened
// to double prints 17): a city's tree holds tens of thousands of bounds. It reads back as `v`.
double short_decimal(float v) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof(text), v).ptr;
  return std::strtod(std::string(text, end).c_str(), nullptr);
}

json box_json(const LodBox& box) {
  json out = json::object();
  for (const char* key : {"min", "max"}) {
    const std::array<float, 3>& corner = key[1] == 'i' ? box.min : box.max;
    out[key] = {short_decimal(corner[0]), short_decimal(corner[1]), short_decimal(corner[2])};
  }
  return out;
}

LodBox union_of(const LodSet& set, int first, int count) {
  LodBox box;
  box.min.fill(std::numeric_limits<float>::max());
  box.max.fill(std::numeric_limits<float>::lowest());
  for (int i = first; i < first + count; ++i)
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], set.leaves[static_cast<std::size_t>(i)].bound.min[k]);
      box.max[k] = std::max(box.max[k], set.leaves[static_cast<std::size_t>(i)].bound.max[k]);
    }
  return box;
}

// `file_names`: per entry of set.files, its index in the written filenames.
json node_json(const LodSet& set, const std::vector<int>& file_names, const std::vector<LodTreeNode>& nodes, int index) {
  const LodTreeNode& node = nodes.at(static_cast<std::size_t>(index));
  json out{{"bound", box_json(union_of(set, node.first_leaf, node.leaf_count))}};
  if (node.children[0] >= 0) {
    out["children"] = json::array(
        {node_json(set, file_names, nodes, node.children[0]), node_json(set, file_names, nodes, node.children[1])});
    return out;
  }
  json lods = json::object();
  const LodLeaf& leaf = set.leaves.at(static_cast<std::size_t>(node.first_leaf));
  for (std::size_t level = 0; level < leaf.levels.size(); ++level) {
    const LodRange& r = leaf.levels[level];
    if (r.file >= 0)
      lods[std::to_string(level)] = {{"file", file_names.at(static_cast<std::size_t>(r.file))}, {"offset", r.offset}, {"count", r.count}};
  }
  out["lods"] = lods;
  if (leaf.instance >= 0) out["instance"] = leaf.instance;
  return out;
}

}  // namespace

std::uint64_t lod_chunk_bytes(const std::string& path) { return chunk_bytes_internal(path); }
int lod_chunk_sh_degree(const std::string& path) { return chunk_sh_degree(path); }
Scene read_lod_chunk(const std::string& path, LoadReport* report, LoadProgress* progress) {
  return read_chunk_internal(path, report, progress);
}

std::uint64_t lod_chunk_gaussians(const std::string& path) { return chunk_gaussians(path); }

Scene read_lod_set_chunk(const LodSet& set, int file, LoadReport* report, LoadProgress* progress) {
  Scene scene = read_chunk_internal(set.file_path(file), report, progress);
  const int instance = set.file_instance.empty() ? -1 : set.file_instance.at(static_cast<std::size_t>(file));
  if (instance >= 0) transform_gaussians(scene, set.instances.at(static_cast<std::size_t>(instance)));
  return scene;
}

void check_lod_ranges(const LodSet& set, int level) {
  std::map<int, std::vector<LodRange>> by_file;
  for (const LodLeaf& leaf : set.leaves) {
    const LodRange& r = leaf.levels[static_cast<std::size_t>(level)];
    if (r.file >= 0 && r.count > 0) by_file[r.file].push_back(r);
  }
  const std::string prefix = "level " + std::to_string(level) + " ";
  for (auto& [file, ranges] : by_file) {
    const std::uint64_t count = chunk_gaussians(set.file_path(file));
    const std::string of_file = " of " + printable_file_text(set.files[static_cast<std::size_t>(file)]);
    const std::string uncovered = " Gaussians) in no leaf: the leaves' ranges must cover each chunk";
    std::sort(ranges.begin(), ranges.end(), [](const LodRange& a, const LodRange& b) { return a.offset < b.offset; });
    std::uint64_t covered = 0;  // the ranges so far cover [0, covered)
    for (const LodRange& r : ranges) {
      if (r.offset > count || r.count > count - r.offset)
        fail(set.meta_path, prefix + "takes " + gaussian_span(r.offset, r.offset + r.count) + of_file +
                                ", which has " + std::to_string(count) + " Gaussians");
      if (r.offset < covered)
        fail(set.meta_path, prefix + "takes " + gaussian_span(r.offset, std::min(covered, r.offset + r.count)) +
                                of_file + " in two leaves: the leaves' ranges overlap");
      if (r.offset > covered)
        fail(set.meta_path, prefix + "leaves " + gaussian_span(covered, r.offset) + of_file + " (" +
                                std::to_string(count) + uncovered);
      covered = r.offset + r.count;
    }
    if (covered < count)
      fail(set.meta_path, prefix + "leaves " + gaussian_span(covered, count) + of_file + " (" +
                              std::to_string(count) + uncovered);
  }
}

std::uint64_t LodSet::gaussians(int level) const {
  std::uint64_t total = 0;
  for (const LodLeaf& leaf : leaves) total += leaf.levels[static_cast<std::size_t>(level)].count;
  return total;
}

std::string LodSet::file_path(int file) const {
  return (fs::path(folder) / files.at(static_cast<std::size_t>(file))).string();
}

LodSet read_lod_set(const std::string& path) {
  const fs::path meta_path = path_kind(path) == PathKind::folder ? fs::path(path) / "lod-meta.json" : fs::path(path);
  const std::string name = meta_path.string();
  const std::vector<char> bytes = read_regular_file(name, kMaxLodMetaBytes);
  json root;
  try {
    root = json::parse(bytes.begin(), bytes.end());
  } catch (const json::exception& e) {
    fail(name, std::string("not valid JSON (") + printable_file_text(e.what()) + ")");
  }
  if (!root.is_object() || !root.contains("lodLevels") || !root.contains("filenames") || !root.contains("tree"))
    fail(name, "not a SOG lod-meta.json (it needs lodLevels, filenames and tree)");
  LodSet set;
  set.meta_path = name;
  set.folder = meta_path.parent_path().string();
  set.level_count = static_cast<int>(whole(root.at("lodLevels"), kMaxLevels, "lodLevels", name));
  if (set.level_count == 0) fail(name, "lodLevels is 0: the set has no level");
  const json& filenames = root.at("filenames");
  if (!filenames.is_array() || filenames.empty()) fail(name, "filenames must be a non-empty array");
  for (std::size_t i = 0; i < filenames.size(); ++i)
    set.files.push_back(chunk_file(filenames[i], "filenames[" + std::to_string(i) + "]", name));
  if (root.contains("instances")) set.instances = read_instances(root.at("instances"), name);
  set.bound = read_bound(root.at("tree"), LodBox{}, name);
  walk(root.at("tree"), set.bound, 0, set, name);
  if (!set.instances.empty()) split_files_by_instance(set);
  for (int level = 0; level < set.level_count; ++level)
    if (set.gaussians(level) == 0) fail(name, "level " + std::to_string(level) + " has no Gaussians in the tree");
  return set;
}

void write_lod_meta(const LodSet& set, const std::vector<LodTreeNode>& nodes, const std::string& path) {
  // An instanced set names a file once however many instances draw it.
  std::vector<std::string> names;
  std::vector<int> file_names;
  std::map<std::string, int> index_of;
  for (const std::string& file : set.files) {
    const auto [it, fresh] = index_of.emplace(file, static_cast<int>(names.size()));
    if (fresh) names.push_back(file);
    file_names.push_back(it->second);
  }
  json root{{"lodLevels", set.level_count}, {"environment", nullptr}, {"filenames", names},
            {"tree", node_json(set, file_names, nodes, static_cast<int>(nodes.size()) - 1)}};
  if (!set.instances.empty()) {
    json list = json::array();
    for (const LodInstance& i : set.instances) {
      json entry{{"rotation", i.rotation}, {"translation", i.translation}};
      if (i.scale != 1) entry["scale"] = i.scale;
      list.push_back(entry);
    }
    root["instances"] = list;
  }
  const std::string text = root.dump();
  write_file_atomically(path, [&](OutputFile& file) { file.write(text); });
}

}  // namespace flashgs
