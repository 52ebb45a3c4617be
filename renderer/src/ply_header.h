// The header of a PLY file: its format, elements and properties (shared by the INRIA and the
// PlayCanvas compressed PLY readers).
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace flashgs::ply {

enum class Format { binary_little_endian, binary_big_endian, ascii };

struct Property {
  std::string name;
  std::string type;  // canonical: char uchar short ushort int uint float double, or "list"
  int size = 0;      // bytes in binary formats (of one item, for a list)
  int kind = 0;      // 0..7: char uchar short ushort int uint float double, so the per-value read does no string compares
  int count_size = 0, count_kind = 0;  // a list's item count: its bytes and type
  std::size_t offset = 0;  // byte offset inside one binary record (elements without lists)
  bool is_list() const { return count_size != 0; }
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
  std::size_t record_size = 0;  // bytes of the properties that are not lists
  bool has_list() const {
    return std::any_of(properties.begin(), properties.end(), [](const Property& p) { return p.is_list(); });
  }
};

struct Header {
  Format format = Format::binary_little_endian;
  std::vector<Element> elements;
  std::size_t data_offset = 0;  // first byte after "end_header\n"
  std::vector<std::string> comments;  // the text after "comment ", in header order (trainers' marks)
};

// Throws flashgs::Error naming `name` and the problem for anything that is not a complete
// PLY header.
Header parse_header(const char* data, std::size_t size, const std::string& name);

// File text inside a message: quoted, escaped and cut short.
std::string quoted(std::string_view text);

}  // namespace flashgs::ply
