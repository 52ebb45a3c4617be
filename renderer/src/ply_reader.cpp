// Reads 3DGS PLY files: the layout comes from the header, every count is checked against the
// bytes actually present, and nothing is read that the header did not promise.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/io.h"

namespace flashgs {
namespace {

enum class Format { binary_little_endian, binary_big_endian, ascii };

struct Property {
  std::string name;
  std::string type;  // canonical: char uchar short ushort int uint float double
  int size = 0;      // bytes in binary formats
  int kind = 0;      // index into kTypeNames, so the per-value read does no string compares
  std::size_t offset = 0;  // byte offset inside one binary record
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
  std::size_t record_size = 0;
};

// Largest header we accept; real headers are about 2 KB.
constexpr std::size_t kMaxHeaderBytes = 1 << 20;

const char* const kTypeNames[] = {"char", "uchar", "short", "ushort", "int", "uint", "float", "double"};

int type_kind(const std::string& type) {
  for (int i = 0; i < 8; ++i)
    if (type == kTypeNames[i]) return i;
  return -1;
}

int type_size(const std::string& type) {
  if (type == "char" || type == "uchar") return 1;
  if (type == "short" || type == "ushort") return 2;
  if (type == "int" || type == "uint" || type == "float") return 4;
  if (type == "double") return 8;
  return 0;
}

// PLY allows both the classic and the sized type names.
std::string canonical_type(const std::string& type) {
  static const std::map<std::string, std::string> aliases = {
      {"int8", "char"},   {"uint8", "uchar"},  {"int16", "short"},   {"uint16", "ushort"},
      {"int32", "int"},   {"uint32", "uint"},  {"float32", "float"}, {"float64", "double"}};
  const auto it = aliases.find(type);
  return it == aliases.end() ? type : it->second;
}

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(name + ": " + problem);
}

struct Header {
  Format format = Format::binary_little_endian;
  std::vector<Element> elements;
  std::size_t data_offset = 0;  // first byte after "end_header\n"
};

Header parse_header(const char* data, std::size_t size, const std::string& name) {
  Header header;
  if (size < 4 || std::memcmp(data, "ply", 3) != 0 || (data[3] != '\n' && data[3] != '\r'))
    fail(name, "not a PLY file (it does not start with \"ply\")");
  const std::size_t limit = std::min(size, kMaxHeaderBytes);
  std::size_t pos = 0;
  bool saw_format = false, saw_end = false;
  int line_number = 0;
  while (pos < limit) {
    std::size_t eol = pos;
    while (eol < limit && data[eol] != '\n') ++eol;
    if (eol == limit) break;
    std::string line(data + pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    ++line_number;
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (line_number == 1) continue;  // "ply"
    if (keyword == "format") {
      std::string format, version;
      words >> format >> version;
      if (format == "binary_little_endian") header.format = Format::binary_little_endian;
      else if (format == "binary_big_endian") header.format = Format::binary_big_endian;
      else if (format == "ascii") header.format = Format::ascii;
      else fail(name, "unknown PLY format \"" + format + "\"");
      saw_format = true;
    } else if (keyword == "comment" || keyword == "obj_info" || keyword.empty()) {
      continue;
    } else if (keyword == "element") {
      Element element;
      std::string count_text;
      words >> element.name >> count_text;
      if (element.name.empty() || count_text.empty() ||
          count_text.find_first_not_of("0123456789") != std::string::npos ||
          count_text.size() > 19)
        fail(name, "header line " + std::to_string(line_number) + ": bad element line \"" + line +
                       "\"");
      element.count = std::stoull(count_text);
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty())
        fail(name, "header line " + std::to_string(line_number) + ": property before any element");
      std::string type, prop_name;
      words >> type;
      Property property;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> prop_name;
        property.type = "list";
      } else {
        words >> prop_name;
        property.type = canonical_type(type);
        property.size = type_size(property.type);
        property.kind = type_kind(property.type);
        if (property.size == 0)
          fail(name, "header line " + std::to_string(line_number) + ": unknown property type \"" +
                         type + "\"");
      }
      if (prop_name.empty())
        fail(name, "header line " + std::to_string(line_number) + ": property without a name");
      property.name = prop_name;
      Element& element = header.elements.back();
      property.offset = element.record_size;
      element.record_size += static_cast<std::size_t>(property.size);
      element.properties.push_back(property);
    } else if (keyword == "end_header") {
      saw_end = true;
      break;
    } else {
      fail(name, "header line " + std::to_string(line_number) + ": unexpected \"" + keyword + "\"");
    }
  }
  if (!saw_end) fail(name, "the header has no end_header line (truncated or not a PLY file)");
  if (!saw_format) fail(name, "the header has no format line");
  header.data_offset = pos;
  return header;
}

// The properties of the vertex element that a Gaussian needs, by index into properties.
struct Layout {
  int x = -1, y = -1, z = -1, opacity = -1;
  int scale[3] = {-1, -1, -1};
  int rot[4] = {-1, -1, -1, -1};
  int dc[3] = {-1, -1, -1};
  std::vector<int> rest;  // f_rest_0 .. f_rest_{n-1}
  int sh_degree = 0;
};

Layout find_layout(const Element& vertex, const std::string& name, LoadReport* report) {
  Layout layout;
  std::map<int, int> rest_by_index;
  for (std::size_t i = 0; i < vertex.properties.size(); ++i) {
    const Property& p = vertex.properties[i];
    const int index = static_cast<int>(i);
    int* slot = nullptr;
    if (p.name == "x") slot = &layout.x;
    else if (p.name == "y") slot = &layout.y;
    else if (p.name == "z") slot = &layout.z;
    else if (p.name == "opacity") slot = &layout.opacity;
    else if (p.name.size() == 7 && p.name.compare(0, 6, "scale_") == 0 && p.name[6] >= '0' && p.name[6] <= '2')
      slot = &layout.scale[p.name[6] - '0'];
    else if (p.name.size() == 5 && p.name.compare(0, 4, "rot_") == 0 && p.name[4] >= '0' && p.name[4] <= '3')
      slot = &layout.rot[p.name[4] - '0'];
    else if (p.name.size() == 6 && p.name.compare(0, 5, "f_dc_") == 0 && p.name[5] >= '0' && p.name[5] <= '2')
      slot = &layout.dc[p.name[5] - '0'];
    else if (p.name.compare(0, 7, "f_rest_") == 0 && p.name.size() > 7 && p.name.size() < 11 &&
             p.name.find_first_not_of("0123456789", 7) == std::string::npos) {
      const int k = std::stoi(p.name.substr(7));
      if (rest_by_index.count(k)) fail(name, "property " + p.name + " appears twice");
      rest_by_index[k] = index;
    }
    if (slot) {
      if (*slot != -1) fail(name, "property " + p.name + " appears twice");
      *slot = index;
    } else if (p.name.compare(0, 7, "f_rest_") != 0 && report) {
      report->ignored_properties++;
      report->ignored_property_names.push_back(p.name);
    }
    if ((slot || p.name.compare(0, 7, "f_rest_") == 0) && p.type != "float" && p.type != "double")
      fail(name, "property " + p.name + " has type " + p.type +
                     "; 3DGS attributes must be float or double");
  }
  const std::pair<const char*, int> required[] = {
      {"x", layout.x},          {"y", layout.y},          {"z", layout.z},
      {"opacity", layout.opacity}, {"scale_0", layout.scale[0]}, {"scale_1", layout.scale[1]},
      {"scale_2", layout.scale[2]}, {"rot_0", layout.rot[0]},   {"rot_1", layout.rot[1]},
      {"rot_2", layout.rot[2]},  {"rot_3", layout.rot[3]},   {"f_dc_0", layout.dc[0]},
      {"f_dc_1", layout.dc[1]},  {"f_dc_2", layout.dc[2]}};
  for (const auto& [prop, index] : required)
    if (index < 0) fail(name, std::string("the vertex element has no property \"") + prop + "\"");

  const int rest_count = static_cast<int>(rest_by_index.size());
  int degree = -1;
  for (int d = 0; d <= 3; ++d)
    if (rest_count == (sh_coefficient_count(d) - 1) * 3) degree = d;
  if (degree < 0)
    fail(name, "it has " + std::to_string(rest_count) +
                   " f_rest properties; SH degrees 0-3 need 0, 9, 24 or 45");
  for (int k = 0; k < rest_count; ++k) {
    const auto it = rest_by_index.find(k);
    if (it == rest_by_index.end())
      fail(name, "f_rest properties are not numbered 0.." + std::to_string(rest_count - 1) +
                     " (f_rest_" + std::to_string(k) + " is missing)");
    layout.rest.push_back(it->second);
  }
  layout.sh_degree = degree;
  return layout;
}

bool host_is_little_endian() {
  const std::uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

// Reads one binary value as double, swapping bytes when the file's order differs.
double read_binary(const unsigned char* at, const Property& property, bool swap) {
  unsigned char bytes[8];
  const int n = property.size;
  for (int i = 0; i < n; ++i) bytes[i] = swap ? at[n - 1 - i] : at[i];
  switch (property.kind) {
    case 0: { std::int8_t v; std::memcpy(&v, bytes, 1); return v; }
    case 1: { std::uint8_t v; std::memcpy(&v, bytes, 1); return v; }
    case 2: { std::int16_t v; std::memcpy(&v, bytes, 2); return v; }
    case 3: { std::uint16_t v; std::memcpy(&v, bytes, 2); return v; }
    case 4: { std::int32_t v; std::memcpy(&v, bytes, 4); return v; }
    case 5: { std::uint32_t v; std::memcpy(&v, bytes, 4); return v; }
    case 6: { float v; std::memcpy(&v, bytes, 4); return v; }
    default: { double v; std::memcpy(&v, bytes, 8); return v; }
  }
}

// Per Gaussian raw attribute values in file order, for one vertex record.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  // Fills `values` (one per vertex property) for record i; records are read in order.
  virtual void read(std::size_t i, std::vector<double>& values) = 0;
};

class BinarySource : public RecordSource {
 public:
  BinarySource(const unsigned char* records, const Element& vertex, bool swap)
      : records_(records), vertex_(vertex), swap_(swap) {}
  void read(std::size_t i, std::vector<double>& values) override {
    const unsigned char* record = records_ + i * vertex_.record_size;
    for (std::size_t p = 0; p < vertex_.properties.size(); ++p)
      values[p] = read_binary(record + vertex_.properties[p].offset, vertex_.properties[p], swap_);
  }

 private:
  const unsigned char* records_;
  const Element& vertex_;
  bool swap_;
};

class AsciiSource : public RecordSource {
 public:
  AsciiSource(const char* begin, const char* end, const std::string& name)
      : cursor_(begin), end_(end), name_(name) {}
  void read(std::size_t i, std::vector<double>& values) override {
    for (double& v : values) {
      while (cursor_ < end_ && (*cursor_ == ' ' || *cursor_ == '\t' || *cursor_ == '\n' || *cursor_ == '\r'))
        ++cursor_;
      const char* start = cursor_;
      while (cursor_ < end_ && !(*cursor_ == ' ' || *cursor_ == '\t' || *cursor_ == '\n' || *cursor_ == '\r'))
        ++cursor_;
      if (start == cursor_)
        fail(name_, "ASCII data ends in vertex " + std::to_string(i) + " (truncated file)");
      const std::string token(start, cursor_);
      char* parsed_end = nullptr;
      v = std::strtod(token.c_str(), &parsed_end);
      if (parsed_end != token.c_str() + token.size())
        fail(name_, "vertex " + std::to_string(i) + ": \"" + token + "\" is not a number");
    }
  }

 private:
  const char* cursor_;
  const char* end_;
  std::string name_;
};

float sigmoid(double logit) { return static_cast<float>(1.0 / (1.0 + std::exp(-logit))); }

}  // namespace

Scene parse_ply(const char* data, std::size_t size, const std::string& name, LoadReport* report) {
  LoadReport local_report;
  if (!report) report = &local_report;
  *report = LoadReport{};
  report->path = name;

  const Header header = parse_header(data, size, name);
  std::size_t vertex_index = header.elements.size();
  for (std::size_t i = 0; i < header.elements.size(); ++i)
    if (header.elements[i].name == "vertex") vertex_index = i;
  if (vertex_index == header.elements.size()) fail(name, "the header declares no vertex element");
  const Element& vertex = header.elements[vertex_index];
  for (const Property& p : vertex.properties)
    if (p.type == "list") fail(name, "the vertex element has a list property (" + p.name + ")");
  const Layout layout = find_layout(vertex, name, report);
  if (vertex.count == 0) fail(name, "the header declares 0 vertices: there are no Gaussians");

  const std::size_t available = size - header.data_offset;
  std::unique_ptr<RecordSource> source;
  if (header.format == Format::ascii) {
    if (vertex_index != 0) fail(name, "ASCII files with elements before the vertex element are not supported");
    // Each ASCII value takes at least two bytes (a digit and a separator).
    if (vertex.count > available / (2 * vertex.properties.size()))
      fail(name, "the header declares " + std::to_string(vertex.count) + " vertices but the file has only " +
                     std::to_string(available) + " bytes of ASCII data");
    source = std::make_unique<AsciiSource>(data + header.data_offset, data + size, name);
  } else {
    std::size_t offset = 0;  // bytes of elements before the vertex element
    for (std::size_t i = 0; i < vertex_index; ++i) {
      const Element& e = header.elements[i];
      for (const Property& p : e.properties)
        if (p.type == "list")
          fail(name, "element \"" + e.name + "\" before the vertices has a list property; cannot locate the vertex data");
      if (e.record_size && e.count > available / e.record_size) fail(name, "element \"" + e.name + "\" is larger than the file");
      offset += e.count * e.record_size;
    }
    if (vertex.count > (available - std::min(offset, available)) / vertex.record_size)
      fail(name, "the header declares " + std::to_string(vertex.count) + " vertices of " +
                     std::to_string(vertex.record_size) + " bytes (" +
                     std::to_string(static_cast<double>(vertex.count) * vertex.record_size / 1e6) +
                     " MB) but the file holds only " + std::to_string(available - std::min(offset, available)) +
                     " bytes after the header: truncated file or wrong vertex count");
    const bool trailing_elements = vertex_index + 1 < header.elements.size();
    const std::size_t expected = offset + vertex.count * vertex.record_size;
    if (!trailing_elements && expected != available)
      fail(name, "the header declares " + std::to_string(vertex.count) + " vertices (" + std::to_string(expected) +
                     " bytes of data) but the file has " + std::to_string(available) +
                     " bytes after the header: the vertex count does not match the file size");
    const bool file_little = header.format == Format::binary_little_endian;
    source = std::make_unique<BinarySource>(
        reinterpret_cast<const unsigned char*>(data + header.data_offset + offset), vertex,
        file_little != host_is_little_endian());
  }

  Scene scene;
  scene.sh_degree = layout.sh_degree;
  report->sh_degree_in_file = layout.sh_degree;
  report->vertices_in_file = vertex.count;
  scene.reserve(vertex.count);
  const int rest_n = scene.sh_rest_per_gaussian();
  const int per_channel = rest_n / 3;
  std::vector<double> values(vertex.properties.size());
  std::vector<float> rest(static_cast<std::size_t>(rest_n));
  for (std::size_t i = 0; i < vertex.count; ++i) {
    source->read(i, values);
    const double pos[3] = {values[layout.x], values[layout.y], values[layout.z]};
    double scale[3], quat[4], dc[3];
    for (int k = 0; k < 3; ++k) scale[k] = std::exp(values[layout.scale[k]]);
    for (int k = 0; k < 4; ++k) quat[k] = values[layout.rot[k]];
    for (int k = 0; k < 3; ++k) dc[k] = values[layout.dc[k]];
    const double opacity_logit = values[layout.opacity];
    // INRIA stores f_rest channel-major (all R, then G, then B); we keep [k][channel].
    bool finite = std::isfinite(opacity_logit);
    for (int k = 0; k < per_channel; ++k)
      for (int ch = 0; ch < 3; ++ch) {
        const double v = values[layout.rest[ch * per_channel + k]];
        finite = finite && std::isfinite(v);
        rest[k * 3 + ch] = static_cast<float>(v);
      }
    for (int k = 0; k < 3; ++k)
      finite = finite && std::isfinite(pos[k]) && std::isfinite(dc[k]) &&
               std::isfinite(static_cast<float>(scale[k])) && std::abs(pos[k]) < 3.0e38 &&
               std::abs(dc[k]) < 3.0e38;
    for (int k = 0; k < 4; ++k) finite = finite && std::isfinite(quat[k]);
    if (!finite) {  // NaN/Inf in the file, or a log-scale whose exp overflows float
      report->dropped_non_finite++;
      continue;
    }
    double norm = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
    if (!(norm > 0.0) || !std::isfinite(norm)) {
      // A zero quaternion has no rotation; 3DGS would divide by zero. Identity keeps the scales.
      report->repaired_zero_quaternion++;
      quat[0] = 1; quat[1] = quat[2] = quat[3] = 0;
      norm = 1;
    }
    for (int k = 0; k < 3; ++k) {
      scene.positions.push_back(static_cast<float>(pos[k]));
      scene.scales.push_back(static_cast<float>(scale[k]));
      scene.sh_dc.push_back(static_cast<float>(dc[k]));
    }
    for (int k = 0; k < 4; ++k) scene.rotations.push_back(static_cast<float>(quat[k] / norm));
    scene.opacities.push_back(sigmoid(opacity_logit));
    scene.sh_rest.insert(scene.sh_rest.end(), rest.begin(), rest.end());
  }
  if (scene.size() == 0)
    fail(name, "all " + std::to_string(vertex.count) + " Gaussians have NaN or Inf attributes");
  return scene;
}

Scene load_ply(const std::string& path, LoadReport* report) {
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) fail(path, "cannot open the file (missing or not readable)");
  const std::streamoff size = file.tellg();
  if (size < 0) fail(path, "cannot determine the file size");
  std::vector<char> bytes(static_cast<std::size_t>(size));
  file.seekg(0);
  if (size > 0 && !file.read(bytes.data(), size)) fail(path, "read error");
  return parse_ply(bytes.data(), bytes.size(), path, report);
}

}  // namespace flashgs
