// Chunked, double-buffered scene upload (see scene_upload.h).
#include "scene_upload.h"

#include <algorithm>

#include "host_parallel.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

// pack(i) for i in [begin, end), split over the host's threads.
void pack_parallel(std::size_t begin, std::size_t end, std::size_t element_bytes, char* destination,
                   const SceneUploader::Pack& pack) {
  const std::size_t count = end - begin;
  for_each_host_range(count, host_threads_for(count, 4096), [&](unsigned, std::size_t lo, std::size_t hi) {
    for (std::size_t i = begin + lo; i < begin + hi; ++i) pack(i, destination + (i - begin) * element_bytes);
  });
}

}  // namespace

SceneUploader::SceneUploader(cudaStream_t stream) : m_stream(stream) {
  for (int k = 0; k < 2; ++k) {
    check_cuda(cudaMallocHost(&m_staging[k], kStagingBytes), "pinned staging allocation");
    check_cuda(cudaEventCreateWithFlags(&m_copied[k], cudaEventDisableTiming), "event creation");
  }
}

SceneUploader::~SceneUploader() {
  if (m_stream) cudaStreamSynchronize(m_stream);
  for (int k = 0; k < 2; ++k) {
    if (m_copied[k]) cudaEventDestroy(m_copied[k]);
    if (m_staging[k]) cudaFreeHost(m_staging[k]);
  }
}

void SceneUploader::upload(void* device, std::size_t element_bytes, std::size_t count, const Pack& pack) {
  const std::size_t per_chunk = kStagingBytes / element_bytes;
  for (std::size_t begin = 0; begin < count; begin += per_chunk) {
    const std::size_t end = std::min(count, begin + per_chunk);
    const int slot = m_next;
    m_next ^= 1;
    check_cuda(cudaEventSynchronize(m_copied[slot]), "scene upload");  // the buffer's last copy landed
    char* staging = static_cast<char*>(m_staging[slot]);
    pack_parallel(begin, end, element_bytes, staging, pack);
    check_cuda(cudaMemcpyAsync(static_cast<char*>(device) + begin * element_bytes, staging,
                               (end - begin) * element_bytes, cudaMemcpyHostToDevice, m_stream),
               "scene upload");
    check_cuda(cudaEventRecord(m_copied[slot], m_stream), "event record");
  }
}

void SceneUploader::finish() { check_cuda(cudaStreamSynchronize(m_stream), "scene upload"); }

}  // namespace cuda
}  // namespace flashgs
