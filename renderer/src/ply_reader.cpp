// Reads 3DGS PLY files: the layout comes from the header, every count is checked against the
// bytes actually present, and nothing is read that the header did not promise.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "flashgs/io.h"
#include "format_readers.h"
#include "kernel_marks.h"
#include "ply_header.h"

namespace flashgs {
namespace {

using namespace ply;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(name + ": " + problem);
}

// The properties of the vertex element that a Gaussian needs, by index into properties.
struct Layout {
  int x = -1, y = -1, z = -1, opacity = -1;
  int scale[3] = {-1, -1, -1};
  int rot[4] = {-1, -1, -1, -1};
  int dc[3] = {-1, -1, -1};
  int filter_3d = -1;     // Mip-Splatting's 3D filter (a standard deviation per Gaussian), if present
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
    else if (p.name == "filter_3D") slot = &layout.filter_3d;
    else if (p.name.size() == 7 && p.name.compare(0, 6, "scale_") == 0 && p.name[6] >= '0' && p.name[6] <= '2')
      slot = &layout.scale[p.name[6] - '0'];
    else if (p.name.size() == 5 && p.name.compare(0, 4, "rot_") == 0 && p.name[4] >= '0' && p.name[4] <= '3')
      slot = &layout.rot[p.name[4] - '0'];
    else if (p.name.size() == 6 && p.name.compare(0, 5, "f_dc_") == 0 && p.name[5] >= '0' && p.name[5] <= '2')
      slot = &layout.dc[p.name[5] - '0'];
    else if (p.name.compare(0, 7, "f_rest_") == 0 && p.name.size() > 7 && p.name.size() < 11 &&
             p.name.find_first_not_of("0123456789", 7) == std::string::npos) {
      const int k = std::stoi(p.name.substr(7));
      if (rest_by_index.count(k)) fail(name, "property " + quoted(p.name) + " appears twice");
      rest_by_index[k] = index;
    }
    if (slot) {
      if (*slot != -1) fail(name, "property " + quoted(p.name) + " appears twice");
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

// Reads one binary value of type `kind` (`size` bytes) as double, swapping bytes when the
// file's order differs. Forced inline: in the per-value loop it is most of the load time.
__attribute__((always_inline)) inline double read_binary(const unsigned char* at, int kind, int size, bool swap) {
  unsigned char bytes[8];
  for (int i = 0; i < size; ++i) bytes[i] = swap ? at[size - 1 - i] : at[i];
  switch (kind) {
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

// "10 vertices", or "10 vertices, then 4 \"face\"" when other elements follow.
std::string declared_counts(const Header& header) {
  std::string text;
  for (const Element& e : header.elements) {
    if (!text.empty()) text += ", then ";
    text += e.name == "vertex" ? std::to_string(e.count) + " vertices" : std::to_string(e.count) + " " + quoted(e.name);
  }
  return text;
}

// Bytes an element takes in binary data starting at `at` (`available` bytes there), walking
// the item counts of list properties; throws when the element runs past the end of the file.
std::size_t binary_element_size(const Element& e, const unsigned char* at, std::size_t available, bool swap,
                                const std::string& name) {
  const std::string too_large = "element " + quoted(e.name) + " (" + std::to_string(e.count) +
                                " records) runs past the end of the file: truncated file or wrong count";
  std::size_t min_record = e.record_size;
  for (const Property& p : e.properties) min_record += static_cast<std::size_t>(p.count_size);
  if (min_record == 0) return 0;
  if (e.count > available / min_record) fail(name, too_large);
  if (!e.has_list()) return e.count * e.record_size;
  std::size_t pos = 0;
  for (std::size_t r = 0; r < e.count; ++r)
    for (const Property& p : e.properties) {
      if (!p.is_list()) {
        if (static_cast<std::size_t>(p.size) > available - pos) fail(name, too_large);
        pos += static_cast<std::size_t>(p.size);
        continue;
      }
      if (static_cast<std::size_t>(p.count_size) > available - pos) fail(name, too_large);
      const double items = read_binary(at + pos, p.count_kind, p.count_size, swap);
      pos += static_cast<std::size_t>(p.count_size);
      if (items < 0) fail(name, "element " + quoted(e.name) + ", record " + std::to_string(r) + ": list " +
                                    quoted(p.name) + " has a negative length");
      if (items > static_cast<double>((available - pos) / static_cast<std::size_t>(p.size))) fail(name, too_large);
      pos += static_cast<std::size_t>(items) * static_cast<std::size_t>(p.size);
    }
  return pos;
}

// Whitespace-separated tokens of ASCII PLY data.
class AsciiTokens {
 public:
  AsciiTokens(const char* begin, const char* end) : cursor_(begin), begin_(begin), end_(end) {}
  // The next token; empty at the end of the data.
  std::string_view next() {
    skip_space();
    const char* start = cursor_;
    while (cursor_ < end_ && !is_space(*cursor_)) ++cursor_;
    return std::string_view(start, static_cast<std::size_t>(cursor_ - start));
  }
  // What is left after the whitespace at the cursor (empty when only whitespace is left).
  std::string_view rest() {
    skip_space();
    return std::string_view(cursor_, static_cast<std::size_t>(end_ - cursor_));
  }
  std::size_t offset() const { return static_cast<std::size_t>(cursor_ - begin_); }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  void skip_space() {
    while (cursor_ < end_ && is_space(*cursor_)) ++cursor_;
  }
  const char* cursor_;
  const char* begin_;
  const char* end_;
};

// Moves the tokens past every record of an element that is not read (lists included).
void skip_ascii_element(const Element& e, AsciiTokens& tokens, const std::string& name) {
  if (e.properties.empty()) return;
  const std::string truncated = "ASCII data ends inside element " + quoted(e.name) + " (truncated file)";
  for (std::size_t r = 0; r < e.count; ++r)
    for (const Property& p : e.properties) {
      const std::string_view token = tokens.next();
      if (token.empty()) fail(name, truncated);
      if (!p.is_list()) continue;
      if (token.find_first_not_of("0123456789") != std::string_view::npos || token.size() > 19)
        fail(name, "element " + quoted(e.name) + ", record " + std::to_string(r) + ": list length " + quoted(token) +
                       " is not a whole number");
      for (std::size_t items = std::stoull(std::string(token)); items > 0; --items)
        if (tokens.next().empty()) fail(name, truncated);
    }
}

// Per Gaussian raw attribute values in file order, for one vertex record.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  // Fills `values` (one per vertex property) for record i; records are read in order.
  virtual void read(std::size_t i, std::vector<double>& values) = 0;
  // After the last vertex: checks that what follows is what the header declared.
  virtual void finish() {}
};

class BinarySource : public RecordSource {
 public:
  BinarySource(const unsigned char* records, const Element& vertex, bool swap)
      : records_(records), vertex_(vertex), swap_(swap) {}
  void read(std::size_t i, std::vector<double>& values) override {
    const unsigned char* record = records_ + i * vertex_.record_size;
    for (std::size_t p = 0; p < vertex_.properties.size(); ++p) {
      const Property& property = vertex_.properties[p];
      values[p] = read_binary(record + property.offset, property.kind, property.size, swap_);
    }
  }

 private:
  const unsigned char* records_;
  const Element& vertex_;
  bool swap_;
};

class AsciiSource : public RecordSource {
 public:
  // `tokens` is at the first vertex; the elements after the vertex element are skipped by finish().
  AsciiSource(AsciiTokens tokens, const Header& header, std::size_t vertex_index, const std::string& name)
      : tokens_(tokens), header_(header), vertex_index_(vertex_index), name_(name) {}
  void read(std::size_t i, std::vector<double>& values) override {
    for (double& v : values) {
      const std::string_view token_view = tokens_.next();
      if (token_view.empty())
        fail(name_, "ASCII data ends in vertex " + std::to_string(i) + " (truncated file)");
      const std::string token(token_view);
      char* parsed_end = nullptr;
      v = std::strtod(token.c_str(), &parsed_end);
      if (parsed_end != token.c_str() + token.size())
        fail(name_, "vertex " + std::to_string(i) + ": " + quoted(token) + " is not a number");
    }
  }
  void finish() override {
    for (std::size_t e = vertex_index_ + 1; e < header_.elements.size(); ++e)
      skip_ascii_element(header_.elements[e], tokens_, name_);
    const std::size_t at = tokens_.offset();
    const std::string_view rest = tokens_.rest();
    if (!rest.empty())
      fail(name_, "the header declares " + declared_counts(header_) + " but more data follows, " +
                      quoted(rest.substr(0, 40)) + " at byte " + std::to_string(header_.data_offset + at) +
                      " after the header: a wrong count, or extra data");
  }

 private:
  AsciiTokens tokens_;
  const Header& header_;
  std::size_t vertex_index_;
  std::string name_;
};

// Binary data: the vertex records located, and the total size of all elements checked
// against the file before anything is read.
std::unique_ptr<RecordSource> binary_source(const Header& header, std::size_t vertex_index, const char* data,
                                            std::size_t size, const std::string& name) {
  const Element& vertex = header.elements[vertex_index];
  const bool swap = (header.format == Format::binary_little_endian) != host_is_little_endian();
  const auto* start = reinterpret_cast<const unsigned char*>(data + header.data_offset);
  const std::size_t available = size - header.data_offset;
  std::size_t offset = 0;  // bytes of the elements before the vertex element
  for (std::size_t i = 0; i < vertex_index; ++i)
    offset += binary_element_size(header.elements[i], start + offset, available - offset, swap, name);
  if (vertex.count > (available - offset) / vertex.record_size)
    fail(name, "the header declares " + std::to_string(vertex.count) + " vertices of " +
                   std::to_string(vertex.record_size) + " bytes (" +
                   format_bytes(byte_count(static_cast<double>(vertex.count) * vertex.record_size)) +
                   ") but the file holds only " + std::to_string(available - offset) +
                   " bytes after the header: truncated file or wrong vertex count");
  std::size_t expected = offset + vertex.count * vertex.record_size;
  for (std::size_t i = vertex_index + 1; i < header.elements.size(); ++i)
    expected += binary_element_size(header.elements[i], start + expected, available - expected, swap, name);
  if (expected != available) {
    const bool vertex_only = header.elements.size() == 1;
    fail(name, "the header declares " + declared_counts(header) + " (" + std::to_string(expected) +
                   " bytes of data) but the file has " + std::to_string(available) + " bytes after the header, " +
                   quoted(std::string_view(data + header.data_offset + expected, std::min<std::size_t>(available - expected, 16))) +
                   " following: " + (vertex_only ? "the vertex count does not match the file size"
                                                 : "the element counts do not match the file size"));
  }
  return std::make_unique<BinarySource>(start + offset, vertex, swap);
}

// Mip-Splatting's 3D filter fused into the Gaussian, as its exporter does: each scale becomes
// sqrt(s^2 + f^2), and the opacity is scaled by sqrt(prod s^2 / prod(s^2 + f^2)) so that the
// Gaussian keeps its integral.
void apply_3d_filter(double filter, DecodedGaussian& g) {
  const double f2 = filter * filter;
  if (f2 == 0.0) return;  // no filter (and a zero scale keeps its opacity)
  double ratio = 1.0;
  for (double& scale : g.scale) {
    const double s2 = scale * scale;
    ratio *= s2 / (s2 + f2);
    scale = std::sqrt(s2 + f2);
  }
  g.opacity *= std::sqrt(ratio);
}

}  // namespace

Scene parse_ply(const char* data, std::size_t size, const std::string& name, LoadReport* report,
                LoadProgress* progress) {
  LoadReport local_report;
  if (!report) report = &local_report;
  *report = LoadReport{};
  report->path = name;

  const Header header = parse_header(data, size, name);
  std::size_t vertex_index = header.elements.size();
  for (std::size_t i = 0; i < header.elements.size(); ++i)
    if (header.elements[i].name == "vertex") {
      if (vertex_index != header.elements.size()) fail(name, "the header declares two vertex elements");
      vertex_index = i;
    }
  if (vertex_index == header.elements.size()) fail(name, "the header declares no vertex element");
  const Element& vertex = header.elements[vertex_index];
  for (const Property& p : vertex.properties)
    if (p.is_list()) fail(name, "the vertex element has a list property (" + quoted(p.name) + ")");
  const Layout layout = find_layout(vertex, name, report);
  if (vertex.count == 0) fail(name, "the header declares 0 vertices: there are no Gaussians");

  std::unique_ptr<RecordSource> source;
  if (header.format == Format::ascii) {
    const std::size_t available = size - header.data_offset;
    // Each ASCII value takes at least two bytes (a digit and a separator).
    if (vertex.count > available / (2 * vertex.properties.size()))
      fail(name, "the header declares " + std::to_string(vertex.count) + " vertices but the file has only " +
                     std::to_string(available) + " bytes of ASCII data");
    AsciiTokens tokens(data + header.data_offset, data + size);
    for (std::size_t i = 0; i < vertex_index; ++i) skip_ascii_element(header.elements[i], tokens, name);
    source = std::make_unique<AsciiSource>(tokens, header, vertex_index, name);
  } else {
    source = binary_source(header, vertex_index, data, size, name);
  }

  Scene scene;
  scene.sh_degree = layout.sh_degree;
  scene.trained_kernel = layout.filter_3d >= 0 ? mip_splatting_kernel() : kernel_from_ply_comments(header.comments);
  report->sh_degree_in_file = layout.sh_degree;
  report->vertices_in_file = vertex.count;
  scene.reserve(vertex.count);
  const int rest_n = scene.sh_rest_per_gaussian();
  const int per_channel = rest_n / 3;
  std::vector<double> values(vertex.properties.size());
  std::vector<float> rest(static_cast<std::size_t>(rest_n));
  const int xyz[3] = {layout.x, layout.y, layout.z};
  DecodeProgress decoding(progress, name, vertex.count);
  for (std::size_t i = 0; i < vertex.count; ++i) {
    decoding.at(i);
    source->read(i, values);
    DecodedGaussian g;
    for (int k = 0; k < 3; ++k) {
      g.position[k] = values[xyz[k]];
      g.scale[k] = std::exp(values[layout.scale[k]]);
      g.sh_dc[k] = values[layout.dc[k]];
    }
    for (int k = 0; k < 4; ++k) g.rotation[k] = values[layout.rot[k]];
    // A logit of +inf or -inf is opacity 1 or 0 (splat-transform writes +inf for a quantised 255);
    // NaN stays NaN and the Gaussian is dropped.
    const double opacity_logit = values[layout.opacity];
    g.opacity = std::isnan(opacity_logit) ? NAN : 1.0 / (1.0 + std::exp(-opacity_logit));
    if (layout.filter_3d >= 0) apply_3d_filter(values[layout.filter_3d], g);
    // INRIA stores f_rest channel-major (all R, then G, then B); we keep [k][channel].
    for (int k = 0; k < per_channel; ++k)
      for (int ch = 0; ch < 3; ++ch) rest[k * 3 + ch] = static_cast<float>(values[layout.rest[ch * per_channel + k]]);
    append_gaussian(scene, g, rest.data(), *report);
  }
  decoding.done(vertex.count);
  source->finish();
  if (scene.size() == 0)
    fail(name, "all " + std::to_string(vertex.count) + " Gaussians have NaN or Inf attributes");
  return scene;
}

DeclaredScene declare_ply(const char* start, std::size_t start_size, std::uint64_t file_size,
                          const std::string& name) {
  if (std::string_view(start, start_size).find("end_header") == std::string_view::npos && start_size < file_size)
    return {};  // a header longer than the start: the full read checks it
  const Header header = parse_header(start, start_size, name);
  DeclaredScene declared;
  std::uint64_t data_bytes = 0;
  bool sized = header.format != Format::ascii;
  for (const Element& e : header.elements) {
    if (e.name == "vertex") declared.gaussians = e.count;
    for (const Property& p : e.properties)
      if (p.name.compare(0, 7, "f_rest_") == 0 || e.name == "sh") declared.sh_degree++;
    sized &= !e.has_list();
    if (e.record_size != 0 && e.count > (std::numeric_limits<std::uint64_t>::max() - data_bytes) / e.record_size)
      sized = false;  // the check below would overflow; the full read refuses it
    else data_bytes += e.count * e.record_size;
  }
  // f_rest (or sh) values per Gaussian to the degree they make (45 or more: degree 3).
  const int rest = declared.sh_degree;
  declared.sh_degree = rest >= 45 ? 3 : rest >= 24 ? 2 : rest >= 9 ? 1 : 0;
  const std::uint64_t available = file_size - std::min<std::uint64_t>(file_size, header.data_offset);
  if (sized && data_bytes != available) {
    const bool vertex_only = header.elements.size() == 1;
    fail(name, "the header declares " + declared_counts(header) + " (" + std::to_string(data_bytes) +
                   " bytes of data) but the file has " + std::to_string(available) + " bytes after the header: " +
                   (data_bytes > available ? "truncated file or wrong count"
                    : vertex_only           ? "the vertex count does not match the file size"
                                            : "the element counts do not match the file size"));
  }
  return declared;
}

Scene load_ply(const std::string& path, LoadReport* report, LoadProgress* progress) {
  const std::vector<char> bytes = read_regular_file(path, std::numeric_limits<std::size_t>::max(), progress);
  return parse_ply(bytes.data(), bytes.size(), path, report, progress);
}

}  // namespace flashgs
