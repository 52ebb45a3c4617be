// Parses and checks PLY headers: every line, type and count, before any data is read.
#include "ply_header.h"

#include <cstring>
#include <map>
#include <sstream>

#include "flashgs/error.h"

namespace flashgs::ply {
namespace {

// Largest header we accept; real headers are about 2 KB.
constexpr std::size_t kMaxHeaderBytes = 1 << 20;
constexpr const char* kCrOnlyLines = "the header has lines ending in CR alone; PLY header lines end in LF or CR LF";

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

}  // namespace

std::string quoted(std::string_view text) { return "\"" + printable_file_text(text) + "\""; }

Header parse_header(const char* data, std::size_t size, const std::string& name) {
  Header header;
  if (size == 0) fail(name, "not a PLY file (it is empty)");
  if (size < 4 || std::memcmp(data, "ply", 3) != 0 || (data[3] != '\n' && data[3] != '\r'))
    fail(name, "not a PLY file (it does not start with \"ply\")");
  if (data[3] == '\r' && (size < 5 || data[4] != '\n'))
    fail(name, kCrOnlyLines);
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
    if (line.find('\r') != std::string::npos)
      fail(name, kCrOnlyLines);
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
      else fail(name, "unknown PLY format " + quoted(format));
      saw_format = true;
    } else if (keyword == "comment") {
      const std::size_t text = line.find_first_not_of(" \t", line.find("comment") + 7);
      header.comments.push_back(text == std::string::npos ? std::string() : line.substr(text));
    } else if (keyword == "obj_info" || keyword.empty()) {
      continue;
    } else if (keyword == "element") {
      Element element;
      std::string count_text;
      words >> element.name >> count_text;
      if (element.name.empty() || count_text.empty() ||
          count_text.find_first_not_of("0123456789") != std::string::npos ||
          count_text.size() > 19)
        fail(name, "header line " + std::to_string(line_number) + ": bad element line " + quoted(line));
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
        count_type = canonical_type(count_type);
        item_type = canonical_type(item_type);
        property.type = "list";
        property.count_size = type_size(count_type);
        property.count_kind = type_kind(count_type);
        property.size = type_size(item_type);
        property.kind = type_kind(item_type);
        if (property.count_size == 0 || property.count_kind > 5 || property.size == 0)
          fail(name, "header line " + std::to_string(line_number) + ": bad list property " + quoted(line) +
                         " (the count needs an integer type, the items a known type)");
      } else {
        words >> prop_name;
        property.type = canonical_type(type);
        property.size = type_size(property.type);
        property.kind = type_kind(property.type);
        if (property.size == 0)
          fail(name, "header line " + std::to_string(line_number) + ": unknown property type " + quoted(type));
      }
      if (prop_name.empty())
        fail(name, "header line " + std::to_string(line_number) + ": property without a name");
      property.name = prop_name;
      Element& element = header.elements.back();
      property.offset = element.record_size;
      if (!property.is_list()) element.record_size += static_cast<std::size_t>(property.size);
      element.properties.push_back(property);
    } else if (keyword == "end_header") {
      saw_end = true;
      break;
    } else {
      fail(name, "header line " + std::to_string(line_number) + ": unexpected " + quoted(keyword));
    }
  }
  if (!saw_end && limit < size)
    fail(name, "no end_header line in the first " + std::to_string(kMaxHeaderBytes >> 20) +
                   " MB (real PLY headers are a few KB)");
  if (!saw_end) fail(name, "the header has no end_header line (truncated or not a PLY file)");
  if (!saw_format) fail(name, "the header has no format line");
  header.data_offset = pos;
  return header;
}
}  // namespace flashgs::ply
