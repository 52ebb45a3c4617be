// Chunked, double-buffered scene upload (see scene_upload.h).
#include "scene_upload.h"

#include <algorithm>
#include <string>

#include "flashgs/error.h"
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

constexpr unsigned kUploadBlock = 256;
constexpr std::size_t kUploadMaxBlocks = 4096;

unsigned upload_blocks(std::size_t threads) {
  return static_cast<unsigned>(std::min(kUploadMaxBlocks, std::max<std::size_t>(1, (threads + kUploadBlock - 1) / kUploadBlock)));
}

// to[places[first + e]] = from[e] for elements e < count of `words` 32-bit words each; a
// thread per word, so an element's words are written side by side.
__global__ void scatter_elements_kernel(const std::uint32_t* from, std::uint32_t* to, unsigned words,
                                        std::size_t first, std::size_t count, const std::uint32_t* places) {
  const std::size_t total = count * words;
  for (std::size_t t = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; t < total;
       t += static_cast<std::size_t>(gridDim.x) * blockDim.x) {
    const std::size_t e = t / words;
    to[static_cast<std::size_t>(places[first + e]) * words + (t - e * words)] = from[t];
  }
}

__global__ void inverse_order_kernel(const std::uint32_t* order, std::size_t count, std::uint32_t* places) {
  for (std::size_t i = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; i < count;
       i += static_cast<std::size_t>(gridDim.x) * blockDim.x)
    places[order[i]] = static_cast<std::uint32_t>(i);
}

}  // namespace

void launch_inverse_order(const std::uint32_t* order, std::size_t count, std::uint32_t* places, cudaStream_t stream) {
  if (count == 0) return;
  inverse_order_kernel<<<upload_blocks(count), kUploadBlock, 0, stream>>>(order, count, places);
  check_cuda(cudaGetLastError(), "scene order kernel launch");
}

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

void SceneUploader::scatter_to(const std::uint32_t* places, void* device_staging) {
  m_places = places;
  m_device_staging = static_cast<char*>(device_staging);
}

void SceneUploader::upload(void* device, std::size_t element_bytes, std::size_t count, const Pack& pack) {
  if (m_places && element_bytes % sizeof(std::uint32_t) != 0)
    throw Error("cuda renderer: internal error, a scattered upload of " + std::to_string(element_bytes) +
                "-byte elements");
  const std::size_t per_chunk = kStagingBytes / element_bytes;
  for (std::size_t begin = 0; begin < count; begin += per_chunk) {
    const std::size_t end = std::min(count, begin + per_chunk);
    const int slot = m_next;
    m_next ^= 1;
    const auto wait_start = Clock::now();
    check_cuda(cudaEventSynchronize(m_copied[slot]), "scene upload");  // the buffer's last copy landed
    const auto pack_start = Clock::now();
    m_wait_seconds += std::chrono::duration<double>(pack_start - wait_start).count();
    char* staging = static_cast<char*>(m_staging[slot]);
    pack_parallel(begin, end, element_bytes, staging, pack);
    m_pack_seconds += seconds_since(pack_start);
    const std::size_t bytes = (end - begin) * element_bytes;
    if (!m_places) {
      check_cuda(cudaMemcpyAsync(static_cast<char*>(device) + begin * element_bytes, staging, bytes,
                                 cudaMemcpyHostToDevice, m_stream),
                 "scene upload");
    } else {  // the device staging's slot is free: its last scatter came before in the stream
      char* device_staging = m_device_staging + slot * kStagingBytes;
      check_cuda(cudaMemcpyAsync(device_staging, staging, bytes, cudaMemcpyHostToDevice, m_stream), "scene upload");
      const unsigned words = static_cast<unsigned>(element_bytes / sizeof(std::uint32_t));
      scatter_elements_kernel<<<upload_blocks((end - begin) * words), kUploadBlock, 0, m_stream>>>(
          reinterpret_cast<const std::uint32_t*>(device_staging), static_cast<std::uint32_t*>(device), words, begin,
          end - begin, m_places);
      check_cuda(cudaGetLastError(), "scene scatter kernel launch");
    }
    check_cuda(cudaEventRecord(m_copied[slot], m_stream), "event record");
  }
}

void SceneUploader::finish() {
  const auto start = Clock::now();
  check_cuda(cudaStreamSynchronize(m_stream), "scene upload");
  m_wait_seconds += seconds_since(start);
}

}  // namespace cuda
}  // namespace flashgs
