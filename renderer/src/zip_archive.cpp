// Writing and reading the zip archives SOG bundles are (see zip_archive.h). The layout is
// PKWARE's APPNOTE: local headers with the data, a central directory, its end record.
#include "zip_archive.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include "flashgs/error.h"
#include "flashgs/file_access.h"

#ifdef FLASHGS_HAVE_ZLIB
#include <zlib.h>
#endif

namespace flashgs {
namespace {

constexpr std::uint32_t kLocalHeader = 0x04034b50, kCentralHeader = 0x02014b50, kEndRecord = 0x06054b50;
constexpr std::size_t kLocalHeaderBytes = 30, kCentralHeaderBytes = 46, kEndRecordBytes = 22;
constexpr std::size_t kMaxCommentBytes = 0xffff;
constexpr std::uint16_t kVersion = 20;  // 2.0: stored and deflated entries
constexpr std::uint16_t kStored = 0, kDeflated = 8;
constexpr std::uint16_t kFlagEncrypted = 0x1;
// 1980-01-01 00:00 in MS-DOS form: a fixed date keeps the output reproducible.
constexpr std::uint16_t kDosTime = 0, kDosDate = (0 << 9) | (1 << 5) | 1;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

void put16(std::string& out, std::uint16_t v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>(v >> 8));
}
void put32(std::string& out, std::uint32_t v) {
  put16(out, static_cast<std::uint16_t>(v & 0xffff));
  put16(out, static_cast<std::uint16_t>(v >> 16));
}
std::uint16_t get16(const unsigned char* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
std::uint32_t get32(const unsigned char* p) { return std::uint32_t{get16(p)} | std::uint32_t{get16(p + 2)} << 16; }

std::uint32_t crc32_of(const std::vector<std::uint8_t>& bytes, const std::string& name) {
#ifdef FLASHGS_HAVE_ZLIB
  (void)name;
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t at = 0; at < bytes.size(); at += 1u << 30)
    crc = crc32(crc, bytes.data() + at, static_cast<uInt>(std::min<std::size_t>(bytes.size() - at, 1u << 30)));
  return static_cast<std::uint32_t>(crc);
#else
  (void)bytes;
  fail(name, "this build has no zlib, so zip archives cannot be written (install zlib1g-dev and rebuild)");
#endif
}

// The fields local and central headers share, from "version needed" to the extra field's length.
void put_common(std::string& out, const ZipEntry& entry, std::uint32_t crc) {
  put16(out, kVersion);
  put16(out, 0);  // flags
  put16(out, kStored);
  put16(out, kDosTime);
  put16(out, kDosDate);
  put32(out, crc);
  put32(out, static_cast<std::uint32_t>(entry.bytes.size()));
  put32(out, static_cast<std::uint32_t>(entry.bytes.size()));
  put16(out, static_cast<std::uint16_t>(entry.name.size()));
  put16(out, 0);  // extra field
}

}  // namespace

void write_zip(OutputFile& file, const std::vector<ZipEntry>& entries, const std::string& name) {
  std::string directory;
  std::uint64_t offset = 0;
  for (const ZipEntry& entry : entries) {
    if (entry.bytes.size() >= std::numeric_limits<std::uint32_t>::max() || offset >= std::numeric_limits<std::uint32_t>::max())
      fail(name, "the archive would pass 4 GB, which a zip archive without zip64 cannot hold");
    const std::uint32_t crc = crc32_of(entry.bytes, name);
    std::string local;
    put32(local, kLocalHeader);
    put_common(local, entry, crc);
    local += entry.name;
    file.write(local);
    file.write(entry.bytes.data(), entry.bytes.size());
    put32(directory, kCentralHeader);
    put16(directory, kVersion);  // made by
    put_common(directory, entry, crc);
    put16(directory, 0);  // comment
    put16(directory, 0);  // disk
    put16(directory, 0);  // internal attributes
    put32(directory, 0);  // external attributes
    put32(directory, static_cast<std::uint32_t>(offset));
    directory += entry.name;
    offset += local.size() + entry.bytes.size();
  }
  std::string end;
  put32(end, kEndRecord);
  put16(end, 0);
  put16(end, 0);
  put16(end, static_cast<std::uint16_t>(entries.size()));
  put16(end, static_cast<std::uint16_t>(entries.size()));
  put32(end, static_cast<std::uint32_t>(directory.size()));
  put32(end, static_cast<std::uint32_t>(offset));
  put16(end, 0);
  file.write(directory);
  file.write(end);
}

bool looks_like_zip(const char* data, std::size_t size) {
  return size >= 4 && get32(reinterpret_cast<const unsigned char*>(data)) == kLocalHeader;
}

ZipReader::ZipReader(const char* data, std::size_t size, const std::string& name)
    : m_data(reinterpret_cast<const unsigned char*>(data)), m_size(size), m_name(name) {
  if (size < kEndRecordBytes) fail(name, "a zip archive of " + std::to_string(size) + " bytes is cut short");
  // The end record sits at the end, before a comment of up to 64 KB.
  std::size_t end = std::string::npos;
  const std::size_t lowest = size - kEndRecordBytes > kMaxCommentBytes ? size - kEndRecordBytes - kMaxCommentBytes : 0;
  for (std::size_t at = size - kEndRecordBytes + 1; at-- > lowest;)
    if (get32(m_data + at) == kEndRecord) {
      end = at;
      break;
    }
  if (end == std::string::npos) fail(name, "the zip archive has no end record (truncated file)");
  const unsigned char* e = m_data + end;
  const std::size_t count = get16(e + 10);
  const std::uint64_t directory_size = get32(e + 12), directory_offset = get32(e + 16);
  if (directory_offset == 0xffffffffu || count == 0xffff) fail(name, "a zip64 archive, which is not supported");
  if (directory_offset > end || directory_size > end - directory_offset)
    fail(name, "the zip archive's central directory lies outside the file (truncated or corrupt)");
  std::size_t at = directory_offset;
  for (std::size_t i = 0; i < count; ++i) {
    if (end - at < kCentralHeaderBytes || get32(m_data + at) != kCentralHeader)
      fail(name, "zip central directory entry " + std::to_string(i) + " is corrupt");
    const unsigned char* h = m_data + at;
    Entry entry;
    entry.flags = get16(h + 8);
    entry.method = get16(h + 10);
    entry.crc = get32(h + 16);
    entry.compressed = get32(h + 20);
    entry.size = get32(h + 24);
    const std::size_t name_bytes = get16(h + 28), extra = get16(h + 30), comment = get16(h + 32);
    entry.header_offset = get32(h + 42);
    if (end - at - kCentralHeaderBytes < name_bytes + extra + comment)
      fail(name, "zip central directory entry " + std::to_string(i) + " runs past the directory");
    entry.name.assign(reinterpret_cast<const char*>(h + kCentralHeaderBytes), name_bytes);
    at += kCentralHeaderBytes + name_bytes + extra + comment;
    m_entries.push_back(std::move(entry));
  }
}

const ZipReader::Entry* ZipReader::find(const std::string& entry) const {
  for (const Entry& e : m_entries)
    if (e.name == entry) return &e;
  return nullptr;
}

bool ZipReader::contains(const std::string& entry) const { return find(entry) != nullptr; }

std::vector<char> ZipReader::read(const std::string& entry_name, std::size_t max_bytes) const {
  const std::string where = m_name + " -> " + entry_name;
  const Entry* entry = find(entry_name);
  if (!entry) fail(m_name, "the zip archive has no entry \"" + printable_file_text(entry_name) + "\"");
  if (entry->flags & kFlagEncrypted) fail(where, "the entry is encrypted");
  if (entry->size > max_bytes)
    fail(where, "the entry declares " + std::to_string(entry->size) + " bytes, more than " +
                    std::to_string(max_bytes) + " it may have");
  if (entry->header_offset > m_size || m_size - entry->header_offset < kLocalHeaderBytes ||
      get32(m_data + entry->header_offset) != kLocalHeader)
    fail(where, "the entry's local header is missing or corrupt");
  const unsigned char* local = m_data + entry->header_offset;
  const std::uint64_t data_offset = entry->header_offset + kLocalHeaderBytes + get16(local + 26) + get16(local + 28);
  if (data_offset > m_size || m_size - data_offset < entry->compressed)
    fail(where, "the entry's data runs past the end of the archive (truncated file)");
  const unsigned char* data = m_data + data_offset;
  std::vector<char> out;
  if (entry->method == kStored) {
    if (entry->compressed != entry->size) fail(where, "a stored entry whose two sizes differ");
    out.assign(data, data + entry->size);
  } else if (entry->method == kDeflated) {
#ifdef FLASHGS_HAVE_ZLIB
    out.resize(entry->size);
    z_stream z{};
    if (inflateInit2(&z, -15) != Z_OK) fail(where, "zlib could not start inflating");
    z.next_in = const_cast<Bytef*>(data);
    z.avail_in = static_cast<uInt>(entry->compressed);
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    const int status = inflate(&z, Z_FINISH);
    const bool whole = status == Z_STREAM_END && z.avail_out == 0;
    inflateEnd(&z);
    if (!whole) fail(where, "the deflated data is corrupt or does not hold the " + std::to_string(entry->size) +
                                " bytes the archive declares");
#else
    fail(where, "this build has no zlib, so deflated zip entries cannot be read (install zlib1g-dev and rebuild)");
#endif
  } else {
    fail(where, "zip compression method " + std::to_string(entry->method) + " is not supported (stored and deflate are)");
  }
#ifdef FLASHGS_HAVE_ZLIB
  const uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(out.data()), static_cast<uInt>(out.size()));
  if (static_cast<std::uint32_t>(crc) != entry->crc) fail(where, "the entry's CRC-32 does not match: corrupt archive");
#endif
  return out;
}

}  // namespace flashgs
