// Zip archives as SOG bundles use them: written with stored entries, read with stored or
// deflated entries, every size checked before memory is taken.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/file_write.h"

namespace flashgs {

struct ZipEntry {
  std::string name;
  std::vector<std::uint8_t> bytes;
};
// Writes `entries` as a zip archive (stored, no compression: the WebP inside is compressed
// already) into `file`; throws flashgs::Error naming `name` when an entry is 4 GB or more
// (no zip64) or the build has no zlib (its CRC-32).
void write_zip(OutputFile& file, const std::vector<ZipEntry>& entries, const std::string& name);

// Whether `data` starts as a zip archive does (a local file header).
bool looks_like_zip(const char* data, std::size_t size);

// The entries of a zip archive in memory; `name` is used in messages.
class ZipReader {
 public:
  ZipReader(const char* data, std::size_t size, const std::string& name);
  bool contains(const std::string& entry) const;
  // The entry's bytes, inflated when deflated; throws flashgs::Error when it is missing,
  // larger than `max_bytes`, encrypted, compressed otherwise, or corrupt.
  std::vector<char> read(const std::string& entry, std::size_t max_bytes) const;

 private:
  struct Entry {
    std::string name;
    std::uint16_t flags = 0, method = 0;
    std::uint32_t crc = 0;
    std::uint64_t compressed = 0, size = 0, header_offset = 0;
  };
  const Entry* find(const std::string& entry) const;
  const unsigned char* m_data;
  std::size_t m_size;
  std::string m_name;
  std::vector<Entry> m_entries;
};

}  // namespace flashgs
