// Parsing and checking SOG v2's meta.json, and telling SOG's JSON files apart by content.
#include "sog_meta.h"

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "kernel_marks.h"

namespace flashgs {
namespace {

using nlohmann::json;

constexpr std::size_t kCodebookSize = 256;
constexpr std::size_t kMaxPaletteSize = 65536;  // labels are 16 bits
constexpr std::size_t kMaxFileNameBytes = 255;

[[noreturn]] void fail(const std::string& name, const std::string& problem) { throw Error(name + ": " + problem); }

const json& field(const json& object, const char* key, const std::string& where, const std::string& name) {
  if (!object.is_object() || !object.contains(key)) fail(name, "meta.json has no \"" + where + key + "\"");
  return object.at(key);
}

double finite_number(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_number()) fail(name, "meta.json's " + where + " is not a number");
  const double v = value.get<double>();
  if (!(std::abs(v) <= std::numeric_limits<float>::max()))
    fail(name, "meta.json's " + where + " is not a finite float");
  return v;
}

std::size_t whole_number(const json& value, std::size_t low, std::size_t high, const std::string& where,
                         const std::string& name) {
  if (!value.is_number_integer() || (value.is_number_integer() && value.get<long long>() < 0) ||
      value.get<unsigned long long>() < low || value.get<unsigned long long>() > high)
    fail(name, "meta.json's " + where + " must be a whole number in " + std::to_string(low) + ".." +
                   std::to_string(high));
  return static_cast<std::size_t>(value.get<unsigned long long>());
}

std::vector<float> codebook(const json& property, const std::string& key, const std::string& name) {
  const json& book = field(property, "codebook", key + ".", name);
  if (!book.is_array() || book.size() != kCodebookSize)
    fail(name, "meta.json's " + key + ".codebook must be an array of " + std::to_string(kCodebookSize) + " numbers");
  std::vector<float> values;
  for (std::size_t i = 0; i < book.size(); ++i)
    values.push_back(static_cast<float>(finite_number(book[i], key + ".codebook[" + std::to_string(i) + "]", name)));
  return values;
}

std::string file_name(const json& value, const std::string& where, const std::string& name) {
  if (!value.is_string()) fail(name, "meta.json's " + where + " is not a file name");
  const std::string file = value.get<std::string>();
  if (file.empty() || file.size() > kMaxFileNameBytes || file == "." || file == ".." ||
      file.find_first_of("/\\") != std::string::npos || file.find('\0') != std::string::npos)
    fail(name, "meta.json's " + where + " \"" + printable_file_text(file) +
                   "\" is not a plain file name beside meta.json");
  return file;
}

// The property's "files" array, which must name exactly `n` files.
std::vector<std::string> files(const json& property, const std::string& key, std::size_t n, const std::string& name) {
  const json& list = field(property, "files", key + ".", name);
  if (!list.is_array() || list.size() != n)
    fail(name, "meta.json's " + key + ".files must name " + std::to_string(n) + (n == 1 ? " file" : " files"));
  std::vector<std::string> names;
  for (std::size_t i = 0; i < n; ++i) names.push_back(file_name(list[i], key + ".files[" + std::to_string(i) + "]", name));
  return names;
}

// The first part of a file, enough to see its top-level keys.
std::string head_of(const std::string& text) { return text.substr(0, 1 << 16); }

}  // namespace

SogMeta parse_sog_meta(const std::string& json_text, const std::string& name) {
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {
    fail(name, std::string("meta.json is not valid JSON (") + printable_file_text(e.what()) + ")");
  }
  if (!root.is_object()) fail(name, "meta.json is not a JSON object");
  const json& version = field(root, "version", "", name);
  if (!version.is_number_integer() || version.get<long long>() != 2)
    fail(name, "SOG version " + printable_file_text(version.dump()) + " is not supported (version 2 is)");
  SogMeta meta;
  meta.count = whole_number(field(root, "count", "", name), 1, kMaxSogCount, "count", name);

  const json& means = field(root, "means", "", name);
  const json& mins = field(means, "mins", "means.", name);
  const json& maxs = field(means, "maxs", "means.", name);
  if (!mins.is_array() || mins.size() != 3 || !maxs.is_array() || maxs.size() != 3)
    fail(name, "meta.json's means.mins and means.maxs must be arrays of 3 numbers");
  for (int k = 0; k < 3; ++k) {
    meta.means_min[k] = finite_number(mins[k], "means.mins[" + std::to_string(k) + "]", name);
    meta.means_max[k] = finite_number(maxs[k], "means.maxs[" + std::to_string(k) + "]", name);
  }
  const auto means_files = files(means, "means", 2, name);
  meta.means_files = {means_files[0], means_files[1]};

  const json& scales = field(root, "scales", "", name);
  meta.scales_codebook = codebook(scales, "scales", name);
  meta.scales_file = files(scales, "scales", 1, name)[0];
  meta.quats_file = files(field(root, "quats", "", name), "quats", 1, name)[0];
  const json& sh0 = field(root, "sh0", "", name);
  meta.sh0_codebook = codebook(sh0, "sh0", name);
  meta.sh0_file = files(sh0, "sh0", 1, name)[0];

  if (root.contains("model") && !root.at("model").is_null()) {
    const json& model = root.at("model");
    if (!model.is_string() || !kernel_from_sog_model(model.get<std::string>(), meta.kernel))
      fail(name, "meta.json's model " + printable_file_text(model.dump()) +
                     " is not one this renderer draws (antialiased, mip, default or classic)");
  }
  if (root.contains("shN") && !root.at("shN").is_null()) {
    const json& sh = root.at("shN");
    meta.sh_bands = static_cast<int>(whole_number(field(sh, "bands", "shN.", name), 1, 3, "shN.bands", name));
    meta.sh_palette_size = whole_number(field(sh, "count", "shN.", name), 1, kMaxPaletteSize, "shN.count", name);
    meta.sh_codebook = codebook(sh, "shN", name);
    const auto sh_files = files(sh, "shN", 2, name);
    meta.sh_files = {sh_files[0], sh_files[1]};
  }
  return meta;
}

std::vector<std::string> sog_meta_files(const SogMeta& meta) {
  std::vector<std::string> names = {meta.means_files[0], meta.means_files[1], meta.scales_file, meta.quats_file,
                                    meta.sh0_file};
  if (meta.sh_bands > 0) names.insert(names.end(), meta.sh_files.begin(), meta.sh_files.end());
  return names;
}

bool looks_like_sog_meta(const std::string& text) {
  const std::string head = head_of(text);
  const auto first = head.find_first_not_of(" \t\r\n");
  return first != std::string::npos && head[first] == '{' && head.find("\"means\"") != std::string::npos &&
         head.find("\"quats\"") != std::string::npos;
}

bool looks_like_sog_lod_meta(const std::string& text) {
  const std::string head = head_of(text);
  const auto first = head.find_first_not_of(" \t\r\n");
  return first != std::string::npos && head[first] == '{' && head.find("\"lodLevels\"") != std::string::npos &&
         head.find("\"tree\"") != std::string::npos;
}

}  // namespace flashgs
