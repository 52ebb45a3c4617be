// SceneUploader: copies host arrays to the device in the device layout without a full host
// copy: each chunk is packed (on every host thread) into one of two pinned staging buffers
// while the other is being copied.
#pragma once

#include <cuda_runtime_api.h>

#include <cstddef>
#include <functional>

namespace flashgs {
namespace cuda {

class SceneUploader {
 public:
  // Writes the element for index i into `destination` (element_bytes bytes).
  using Pack = std::function<void(std::size_t i, void* destination)>;

  explicit SceneUploader(cudaStream_t stream);
  ~SceneUploader();  // waits for the copies in flight
  SceneUploader(const SceneUploader&) = delete;
  SceneUploader& operator=(const SceneUploader&) = delete;

  // device[0 .. count) = pack(0 .. count); throws flashgs::Error on a CUDA failure.
  void upload(void* device, std::size_t element_bytes, std::size_t count, const Pack& pack);
  // Returns once every copy has landed.
  void finish();

 private:
  static constexpr std::size_t kStagingBytes = std::size_t{32} << 20;
  cudaStream_t m_stream;
  void* m_staging[2] = {nullptr, nullptr};
  cudaEvent_t m_copied[2] = {nullptr, nullptr};
  int m_next = 0;
};

}  // namespace cuda
}  // namespace flashgs
