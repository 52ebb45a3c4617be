// Parsing and checking SOG v2's meta.json, and telling SOG's JSON files apart by content.
#include "sog_meta.h"

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "kernel_marks.h"

namespace flashgs {
namespace {

using nlohmann::json;

constexpr std::size_t kCodebookSize = 256;
constexpr std::size_t kMaxPaletteSize = 65536;  // labels are 16 bits
constexpr std::size_t kMaxFileNameBytes = 255;

// The name may come from a file (a texture or chunk named in JSON) or a user's argument.
[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

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

constexpr const char* kJsonSpace = " \t\r\n";

}  // namespace

namespace {

// `count` numbers of meta.json's `key`.
std::vector<double> numbers(const json& object, const char* key, std::size_t count, const std::string& where,
                            const std::string& name) {
  const json& list = field(object, key, where + ".", name);
  if (!list.is_array() || list.size() != count)
    fail(name, "meta.json's " + where + "." + key + " must be an array of " + std::to_string(count) + " numbers");
  std::vector<double> values;
  for (std::size_t i = 0; i < count; ++i)
    values.push_back(finite_number(list[i], where + "." + key + "[" + std::to_string(i) + "]", name));
  return values;
}

// Version 1's byte b stands for lo + (hi - lo) b / 255.
std::vector<float> lerp_table(double lo, double hi) {
  std::vector<float> table;
  for (std::size_t b = 0; b < kCodebookSize; ++b) table.push_back(static_cast<float>(lo + (hi - lo) * double(b) / 255.0));
  return table;
}

// What both versions share: the positions' range and files, the rotations, the kernel mark.
void parse_common(const json& root, SogMeta& meta, const std::string& name) {
  const json& means = field(root, "means", "", name);
  const std::vector<double> mins = numbers(means, "mins", 3, "means", name), maxs = numbers(means, "maxs", 3, "means", name);
  for (int k = 0; k < 3; ++k) {
    meta.means_min[k] = mins[k];
    meta.means_max[k] = maxs[k];
  }
  const auto means_files = files(means, "means", 2, name);
  meta.means_files = {means_files[0], means_files[1]};
  meta.quats_file = files(field(root, "quats", "", name), "quats", 1, name)[0];
  if (root.contains("model") && !root.at("model").is_null()) {
    const json& model = root.at("model");
    if (!model.is_string() || !kernel_from_sog_model(model.get<std::string>(), meta.kernel))
      fail(name, "meta.json's model " + printable_file_text(model.dump()) +
                     " is not one this renderer draws (antialiased, mip, default or classic)");
  }
}

// Version 1 (meta.json without "version"): the count in means.shape, per-channel ranges for
// scales (log) and sh0 (f_dc, then the opacity's logit), one range for the SH palette, whose
// band count the centroids texture's width gives.
SogMeta parse_version_1(const json& root, const std::string& name) {
  SogMeta meta;
  meta.version = 1;
  const json& shape = field(field(root, "means", "", name), "shape", "means.", name);
  if (!shape.is_array() || shape.size() != 2)
    fail(name, "meta.json (SOG version 1: no \"version\") has no means.shape [count, 3]");
  meta.count = whole_number(shape[0], 1, kMaxSogCount, "means.shape[0]", name);
  parse_common(root, meta, name);
  const json& scales = field(root, "scales", "", name);
  const std::vector<double> s_lo = numbers(scales, "mins", 3, "scales", name), s_hi = numbers(scales, "maxs", 3, "scales", name);
  meta.scales_file = files(scales, "scales", 1, name)[0];
  const json& sh0 = field(root, "sh0", "", name);
  const std::vector<double> c_lo = numbers(sh0, "mins", 4, "sh0", name), c_hi = numbers(sh0, "maxs", 4, "sh0", name);
  meta.sh0_file = files(sh0, "sh0", 1, name)[0];
  for (int k = 0; k < 3; ++k) {
    meta.scales_tables[k] = lerp_table(s_lo[k], s_hi[k]);
    meta.sh0_tables[k] = lerp_table(c_lo[k], c_hi[k]);
  }
  for (float logit : lerp_table(c_lo[3], c_hi[3]))
    meta.opacity_table.push_back(static_cast<float>(1.0 / (1.0 + std::exp(-double(logit)))));
  if (root.contains("shN") && !root.at("shN").is_null()) {
    const json& sh = root.at("shN");
    meta.sh_codebook = lerp_table(finite_number(field(sh, "mins", "shN.", name), "shN.mins", name),
                                  finite_number(field(sh, "maxs", "shN.", name), "shN.maxs", name));
    const auto sh_files = files(sh, "shN", 2, name);
    meta.sh_files = {sh_files[0], sh_files[1]};
    meta.sh_bands_from_texture = true;
  }
  return meta;
}

}  // namespace

SogMeta parse_sog_meta(const std::string& json_text, const std::string& name) {
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {
    fail(name, std::string("meta.json is not valid JSON (") + printable_file_text(e.what()) + ")");
  }
  if (!root.is_object()) fail(name, "meta.json is not a JSON object");
  if (!root.contains("version")) return parse_version_1(root, name);
  const json& version = root.at("version");
  if (!version.is_number_integer() || version.get<long long>() != 2)
    fail(name, "SOG version " + printable_file_text(version.dump()) + " is not supported (versions 1 and 2 are)");
  SogMeta meta;
  meta.count = whole_number(field(root, "count", "", name), 1, kMaxSogCount, "count", name);
  parse_common(root, meta, name);
  const json& scales = field(root, "scales", "", name);
  const std::vector<float> scales_codebook = codebook(scales, "scales", name);
  meta.scales_file = files(scales, "scales", 1, name)[0];
  const json& sh0 = field(root, "sh0", "", name);
  const std::vector<float> sh0_codebook = codebook(sh0, "sh0", name);
  meta.sh0_file = files(sh0, "sh0", 1, name)[0];
  meta.scales_tables = {scales_codebook, scales_codebook, scales_codebook};
  meta.sh0_tables = {sh0_codebook, sh0_codebook, sh0_codebook};
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
  if (meta.sh_bands > 0 || meta.sh_bands_from_texture)
    names.insert(names.end(), meta.sh_files.begin(), meta.sh_files.end());
  return names;
}

// Both look at all of `text`: callers pass a bounded start (read_recognition_start) or a
// file already read within kMaxSogJsonBytes, and keys may come after any fixed prefix.
bool looks_like_sog_meta(const std::string& text) {
  const auto first = text.find_first_not_of(kJsonSpace);
  return first != std::string::npos && text[first] == '{' && text.find("\"means\"") != std::string::npos &&
         text.find("\"quats\"") != std::string::npos;
}

bool looks_like_sog_lod_meta(const std::string& text) {
  const auto first = text.find_first_not_of(kJsonSpace);
  return first != std::string::npos && text[first] == '{' && text.find("\"lodLevels\"") != std::string::npos &&
         text.find("\"tree\"") != std::string::npos;
}

bool may_be_json_object(std::string_view start) {
  const auto first = start.find_first_not_of(kJsonSpace);
  return first == std::string_view::npos || start[first] == '{';
}

std::vector<char> read_recognition_start(const std::string& path, std::size_t start_bytes) {
  std::vector<char> start = read_file_start(path, start_bytes);
  // A shorter start is the whole file; only a JSON object earns the longer look.
  if (start.size() == start_bytes && start_bytes < kMaxSogJsonBytes &&
      may_be_json_object(std::string_view(start.data(), start.size())))
    start = read_file_start(path, kMaxSogJsonBytes);
  return start;
}

}  // namespace flashgs
