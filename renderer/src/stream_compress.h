// Compression for the scene writers: gzip (SPZ versions 1-3) and zstd (SPZ version 4).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace flashgs {

// One gzip stream of `size` bytes; throws flashgs::Error naming `name` when the build has no
// zlib or zlib fails.
std::vector<std::uint8_t> gzip_compress(const void* data, std::size_t size, const std::string& name);
// One zstd frame; throws likewise without libzstd.
std::vector<std::uint8_t> zstd_compress(const void* data, std::size_t size, const std::string& name);

}  // namespace flashgs
