// ScenePool: the GPU-resident scene of a streamed LOD cut (Renderer::set_scene_parts). Parts
// live in pages of kChunkSize Gaussians, so that a part is uploaded once and drawn for as long
// as cuts keep it, and a cut is drawn by listing its pages: no per-cut copy of the scene.
#pragma once

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "device_buffer.h"
#include "flashgs/scene_parts.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {

static_assert(kChunkSize == kScenePartPageGaussians, "a pool page is a chunk of the chunk cull");

// The sphere around a drawn set's centres and its largest opacity (what a frame's key format
// and chunk test need of the scene).
struct SceneBounds {
  double centre[3] = {0, 0, 0};
  double radius = 0;
  float max_opacity = 1.0f;
};

class ScenePool {
 public:
  // Device memory is counted in *current / *peak (the renderer's FrameStats figures).
  ScenePool(cudaStream_t stream, std::uint64_t* current, std::uint64_t* peak);
  ~ScenePool();
  ScenePool(const ScenePool&) = delete;
  ScenePool& operator=(const ScenePool&) = delete;

  // Makes `parts` the drawn set: uploads those not resident (queued on the stream, before the
  // next frame's work), and keeps parts no longer drawn while the pool stays within
  // `resident_bytes` (0: no limit), evicting the least recently drawn first. The pool grows
  // when the drawn parts need it, whatever the limit. Throws flashgs::Error when the device
  // has no room; the pool is then empty.
  void set_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes);
  // The scene to draw (valid until the next set_parts) and its bounds.
  const DeviceScene& scene() const { return m_scene; }
  const SceneBounds& bounds() const { return m_bounds; }
  std::uint64_t drawn_gaussians() const { return m_drawn_gaussians; }
  // Gaussians uploaded since the pool was made (each part once while it stays resident).
  std::uint64_t uploaded_gaussians() const { return m_uploaded; }
  std::uint64_t resident_parts() const { return m_parts.size(); }
  std::uint64_t bytes() const;

 private:
  struct Resident {
    std::vector<std::uint32_t> pages;
    std::uint64_t last_drawn = 0;
    float lo[3], hi[3];  // the box of its centres
    float max_opacity = 1.0f;
  };
  void clear();
  void reset_layout(int sh_degree);
  void release_staging();
  void size_staging(std::uint64_t resident_bytes);
  std::size_t staging_bytes() const;
  void grow(std::size_t pages);
  void evict(const std::unordered_map<std::uint64_t, Resident>::iterator& victim);
  bool evict_least_recent();
  void upload(const std::vector<const ScenePart*>& parts);
  void flush_staging(std::size_t staged_pages);
  void write_draw_list(const std::vector<ScenePart>& parts);
  std::size_t page_bytes() const;

  cudaStream_t m_stream;
  std::uint64_t* m_current;
  std::uint64_t* m_peak;
  int m_sh_degree = -1;
  int m_rest_stride_vec4 = 0;
  std::size_t m_capacity_pages = 0;
  DeviceBuffer m_position, m_rotation, m_scale, m_dc, m_rest, m_chunks;
  DeviceBuffer m_ids;                        // per slot: its place in the cut's order (DeviceScene::scene_ids)
  DeviceBuffer m_draw_chunks, m_draw_bases;  // per drawn page: the page, and the id of its first Gaussian
  std::vector<std::uint32_t> m_free_pages;
  std::unordered_map<std::uint64_t, Resident> m_parts;
  std::uint64_t m_generation = 0;
  std::uint64_t m_uploaded = 0;
  std::uint64_t m_drawn_gaussians = 0;
  DeviceScene m_scene;
  SceneBounds m_bounds;

  // Host-to-device staging: packed records of whole pages and their page table (pool page,
  // members), in pinned memory, two halves used in turn; the device copies beside.
  void* m_staging = nullptr;        // pinned
  uint2* m_staged_pages = nullptr;  // pinned, per half
  DeviceBuffer m_device_staging, m_device_pages;
  cudaEvent_t m_staging_free[2] = {nullptr, nullptr};
  int m_half = 0;
  std::size_t m_staging_half_bytes = 0;
  std::size_t m_staging_page_capacity = 0;  // pages per half
  // The draw list's pinned copies, used in turn (a copy may still be in flight).
  std::uint32_t* m_draw_list[2] = {nullptr, nullptr};
  std::uint32_t* m_draw_bases_host[2] = {nullptr, nullptr};
  std::size_t m_draw_list_capacity = 0;
  cudaEvent_t m_draw_list_free[2] = {nullptr, nullptr};
  int m_draw_half = 0;
};

}  // namespace cuda
}  // namespace flashgs
