// Batches of a scene's Gaussians: binary PLY read range by range, the rest loaded whole.
#include "gaussian_batches.h"

#include <algorithm>
#include <sstream>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "ply_header.h"

namespace flashgs {
namespace {

constexpr std::size_t kHeaderWindow = 1 << 20;

// The header text of a PLY file whose only element is its vertex element, up to and after
// the vertex count, when the file is binary and may be read range by range.
bool streamable_ply(const ply::Header& header, std::string& before, std::string& after) {
  if (header.format == ply::Format::ascii || header.elements.empty() || header.elements[0].name != "vertex" ||
      header.elements[0].has_list())
    return false;
  std::ostringstream text;
  text << "ply\nformat " << (header.format == ply::Format::binary_little_endian ? "binary_little_endian" : "binary_big_endian")
       << " 1.0\n";
  for (const std::string& comment : header.comments) text << "comment " << comment << "\n";
  text << "element vertex ";
  before = text.str();
  std::ostringstream rest;
  rest << "\n";
  for (const ply::Property& p : header.elements[0].properties) rest << "property " << p.type << " " << p.name << "\n";
  rest << "end_header\n";
  after = rest.str();
  return true;
}

}  // namespace

GaussianBatches::GaussianBatches(const std::string& path) : m_path(path) {
  check_regular_file(path);
  const std::vector<char> head = read_file_start(path, kHeaderWindow);
  bool streamed = false;
  if (head.size() >= 4 && std::string(head.data(), 4) == "ply\n") {
    try {
      const ply::Header header = ply::parse_header(head.data(), head.size(), path);
      streamed = streamable_ply(header, m_header_before_count, m_header_after_count) &&
                 header.elements.size() == 1;
      if (streamed) {
        m_count = header.elements[0].count;
        m_data_offset = header.data_offset;
        m_record_bytes = header.elements[0].record_size;
      }
    } catch (const Error&) {
      streamed = false;  // not the INRIA layout: the format readers below say what it is
    }
  }
  if (streamed) {
    // The first Gaussian read as a batch checks the layout (and gives the SH degree and marks).
    m_file.open(path, std::ios::binary);
    if (!m_file) throw Error(printable_file_text(path, kMaxPrintedPathBytes) + ": cannot open");
    Scene first;
    if (m_count == 0 || !next(first, 1))
      throw Error(printable_file_text(path, kMaxPrintedPathBytes) + ": the header declares 0 vertices: there are no Gaussians");
    m_sh_degree = first.sh_degree;
    m_kernel = first.trained_kernel;
    m_next = 0;
    return;
  }
  m_whole = std::make_unique<Scene>(load_scene_file(path));
  m_count = m_whole->size();
  m_sh_degree = m_whole->sh_degree;
  m_kernel = m_whole->trained_kernel;
}

bool GaussianBatches::next(Scene& batch, std::size_t max_count) {
  if (m_next >= m_count) return false;
  const std::uint64_t n = std::min<std::uint64_t>(max_count, m_count - m_next);
  if (m_whole) {
    batch = Scene{};
    batch.trained_kernel = m_whole->trained_kernel;
    batch.append_range(*m_whole, m_next, n);
    m_next += n;
    return true;
  }
  std::string bytes = m_header_before_count + std::to_string(n) + m_header_after_count;
  const std::size_t header_bytes = bytes.size();
  bytes.resize(header_bytes + n * m_record_bytes);
  m_file.clear();
  m_file.seekg(static_cast<std::streamoff>(m_data_offset + m_next * m_record_bytes));
  m_file.read(&bytes[header_bytes], static_cast<std::streamsize>(n * m_record_bytes));
  if (static_cast<std::uint64_t>(m_file.gcount()) != n * m_record_bytes)
    throw Error(printable_file_text(m_path, kMaxPrintedPathBytes) + ": the file ends inside vertex " +
                std::to_string(m_next + static_cast<std::uint64_t>(m_file.gcount()) / m_record_bytes) + " of " +
                std::to_string(m_count) + ": truncated file or wrong vertex count");
  batch = parse_ply(bytes.data(), bytes.size(), m_path);
  m_next += n;
  return true;
}

}  // namespace flashgs
