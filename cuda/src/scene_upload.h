// SceneUploader: copies host arrays to the device in the device layout without a full host
// copy: each chunk is packed (on every host thread) into one of two pinned staging buffers
// while the other is being copied. A scene stored out of the device's order is read in its
// stored order and scattered on the device (scatter_to), not gathered on the host.
#pragma once

#include <cuda_runtime_api.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>

namespace flashgs {
namespace cuda {

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

class SceneUploader {
 public:
  // Writes the element for index i into `destination` (element_bytes bytes).
  using Pack = std::function<void(std::size_t i, void* destination)>;
  // The device memory scatter_to needs for its staging.
  static constexpr std::size_t kDeviceStagingBytes = std::size_t{64} << 20;

  explicit SceneUploader(cudaStream_t stream);
  ~SceneUploader();  // waits for the copies in flight
  SceneUploader(const SceneUploader&) = delete;
  SceneUploader& operator=(const SceneUploader&) = delete;

  // device[0 .. count) = pack(0 .. count), or after scatter_to device[places[i]] = pack(i);
  // throws flashgs::Error on a CUDA failure.
  void upload(void* device, std::size_t element_bytes, std::size_t count, const Pack& pack);
  // Later uploads put element i at places[i] (a device array: a permutation of the uploads'
  // indices), through `device_staging` (kDeviceStagingBytes of device memory). Both must stay
  // allocated until finish(); element sizes must then be multiples of 4 bytes.
  void scatter_to(const std::uint32_t* places, void* device_staging);
  // Returns once every copy has landed.
  void finish();
  // Wall-clock seconds so far spent packing on the host, and waiting for copies to land (a
  // staging buffer to come free, or finish).
  double pack_seconds() const { return m_pack_seconds; }
  double wait_seconds() const { return m_wait_seconds; }

 private:
  static constexpr std::size_t kStagingBytes = kDeviceStagingBytes / 2;
  cudaStream_t m_stream;
  const std::uint32_t* m_places = nullptr;
  char* m_device_staging = nullptr;
  void* m_staging[2] = {nullptr, nullptr};
  cudaEvent_t m_copied[2] = {nullptr, nullptr};
  int m_next = 0;
  double m_pack_seconds = 0, m_wait_seconds = 0;
};

// places[order[i]] = i for i < count: where each scene Gaussian goes when device Gaussian i is
// scene Gaussian order[i] (both device arrays), for SceneUploader::scatter_to.
void launch_inverse_order(const std::uint32_t* order, std::size_t count, std::uint32_t* places, cudaStream_t stream);

}  // namespace cuda
}  // namespace flashgs
