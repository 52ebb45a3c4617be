// DeviceBuffer: one device allocation whose size the owner's memory counters follow.
#pragma once

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

#include "flashgs/error.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {

// One device allocation; grows (discarding its content) but never shrinks. The owner's byte
// counters follow every change so FrameStats can report current and peak memory. Growing a
// bound buffer first waits for its stream: a frame still in flight may be reading the old
// allocation (cudaFree's implicit synchronisation is not something to rely on).
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  ~DeviceBuffer() { release(); }
  void bind(std::uint64_t* current, std::uint64_t* peak, cudaStream_t stream) {
    current_ = current;
    peak_ = peak;
    stream_ = stream;
  }
  // Ensures at least `bytes`; throws flashgs::Error when the device has no room.
  void reserve(std::size_t bytes, const char* what) {
    if (bytes <= bytes_) return;
    if (ptr_ && stream_) check_cuda(cudaStreamSynchronize(stream_), "stream synchronisation before a buffer grows");
    release();
    void* p = nullptr;
    const cudaError_t status = cudaMalloc(&p, bytes);
    if (status != cudaSuccess) {
      cudaGetLastError();
      std::size_t free_bytes = 0, total_bytes = 0;
      cudaMemGetInfo(&free_bytes, &total_bytes);
      throw Error(std::string("cuda renderer: out of GPU memory allocating ") + what + " (" +
                  std::to_string(bytes >> 20) + " MiB; " + std::to_string(free_bytes >> 20) + " of " +
                  std::to_string(total_bytes >> 20) + " MiB free)");
    }
    ptr_ = p;
    bytes_ = bytes;
    if (current_) {
      *current_ += bytes;
      *peak_ = std::max(*peak_, *current_);
    }
  }
  void release() {
    if (!ptr_) return;
    cudaFree(ptr_);
    if (current_) *current_ -= bytes_;
    ptr_ = nullptr;
    bytes_ = 0;
  }
  void swap(DeviceBuffer& other) {  // content and size; counters stay with each owner
    std::swap(ptr_, other.ptr_);
    std::swap(bytes_, other.bytes_);
  }
  template <typename T>
  T* as() const { return static_cast<T*>(ptr_); }
  std::size_t bytes() const { return bytes_; }

 private:
  void* ptr_ = nullptr;
  std::size_t bytes_ = 0;
  std::uint64_t* current_ = nullptr;
  std::uint64_t* peak_ = nullptr;
  cudaStream_t stream_ = nullptr;
};

}  // namespace cuda
}  // namespace flashgs
