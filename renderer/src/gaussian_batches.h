// A scene file's Gaussians in batches: binary PLY is streamed from the disk, so that a scene
// larger than memory can be processed; other formats are loaded whole and handed out in slices.
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>

#include "flashgs/scene.h"

namespace flashgs {

class GaussianBatches {
 public:
  // Throws flashgs::Error naming the file for anything the scene readers refuse.
  explicit GaussianBatches(const std::string& path);
  std::uint64_t declared_count() const { return m_count; }  // before Gaussians with NaN are dropped
  int sh_degree() const { return m_sh_degree; }
  const TrainedKernel& trained_kernel() const { return m_kernel; }
  bool streamed() const { return !m_whole; }  // read from the disk batch by batch
  // Starts again from the first Gaussian.
  void rewind() { m_next = 0; }
  // The next up to `max_count` Gaussians into `batch`; false once all were handed out.
  bool next(Scene& batch, std::size_t max_count);

 private:
  std::string m_path;
  std::uint64_t m_count = 0, m_next = 0;
  int m_sh_degree = 0;
  TrainedKernel m_kernel;
  std::unique_ptr<Scene> m_whole;  // formats read whole
  // Binary PLY: a header for a batch is the file's own with the vertex count replaced.
  std::string m_header_before_count, m_header_after_count;
  std::uint64_t m_data_offset = 0, m_record_bytes = 0;
  std::ifstream m_file;
};

}  // namespace flashgs
