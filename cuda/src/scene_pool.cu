// The pooled scene of a streamed cut (see scene_pool.h): page allocation, least-recently-drawn
// eviction, staged uploads scattered into pages on the device, and the per-cut page list.
#include "scene_pool.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "flashgs/error.h"
#include "host_parallel.h"

namespace flashgs {
namespace cuda {
namespace {

// Each half of the upload staging: 16 MiB, less under a small cap (a 32nd of it, at least 1 MiB).
constexpr std::size_t kStagingHalfMaxBytes = std::size_t{16} << 20;
constexpr std::size_t kStagingHalfMinBytes = std::size_t{1} << 20;
constexpr unsigned kScatterBlock = 256;
// A staged Gaussian: position and opacity, rotation, scale and DC red, DC green and blue, then
// its higher SH bands as DeviceScene::sh_rest holds them.
constexpr unsigned kShapeVec4 = 4;

std::size_t pages_for(std::size_t gaussians) { return (gaussians + kChunkSize - 1) / kChunkSize; }

__global__ void pool_scatter_kernel(const float4* __restrict__ staged, unsigned record_vec4,
                                    const uint2* __restrict__ pages, unsigned page_count, DeviceScene pool) {
  const std::size_t total = static_cast<std::size_t>(page_count) * kChunkSize;
  for (std::size_t t = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; t < total;
       t += static_cast<std::size_t>(gridDim.x) * blockDim.x) {
    const uint2 page = pages[t / kChunkSize];
    const unsigned lane = static_cast<unsigned>(t % kChunkSize);
    if (lane >= page.y) continue;
    const float4* record = staged + t * record_vec4;
    const std::size_t to = static_cast<std::size_t>(page.x) * kChunkSize + lane;
    pool.position_opacity[to] = record[0];
    pool.rotation[to] = record[1];
    pool.scale_dc_r[to] = record[2];
    pool.dc_gb[to] = make_float2(record[3].x, record[3].y);
    const unsigned rest = record_vec4 - kShapeVec4;
    for (unsigned k = 0; k < rest; ++k) pool.sh_rest[to * rest + k] = record[kShapeVec4 + k];
  }
}

// ids[page * kChunkSize + lane] = bases[k] + lane for the k-th drawn page: each drawn Gaussian's
// place in the parts' order, so that pairs of equal depth blend in the order of the assembled
// scene whatever pages the parts landed in.
__global__ void pool_ids_kernel(const std::uint32_t* __restrict__ pages, const std::uint32_t* __restrict__ bases,
                                unsigned page_count, std::uint32_t* __restrict__ ids) {
  const std::size_t total = static_cast<std::size_t>(page_count) * kChunkSize;
  for (std::size_t t = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x; t < total;
       t += static_cast<std::size_t>(gridDim.x) * blockDim.x) {
    const std::size_t k = t / kChunkSize;
    const unsigned lane = static_cast<unsigned>(t % kChunkSize);
    ids[static_cast<std::size_t>(pages[k]) * kChunkSize + lane] = bases[k] + lane;
  }
}

// Grows `buffer` to `bytes`, keeping its first `keep` bytes (queued on `stream`).
void grow_keeping(DeviceBuffer& buffer, std::size_t bytes, std::size_t keep, std::uint64_t* current, std::uint64_t* peak,
                  cudaStream_t stream, const char* what) {
  if (bytes <= buffer.bytes()) return;
  DeviceBuffer next;
  next.bind(current, peak, stream);
  next.reserve(bytes, what);
  if (keep > 0)
    check_cuda(cudaMemcpyAsync(next.as<void>(), buffer.as<void>(), keep, cudaMemcpyDeviceToDevice, stream), "pool growth");
  check_cuda(cudaStreamSynchronize(stream), "pool growth");
  buffer.swap(next);  // `next` frees the old allocation (counted by `current`)
}

}  // namespace

ScenePool::ScenePool(cudaStream_t stream, std::uint64_t* current, std::uint64_t* peak)
    : m_stream(stream), m_current(current), m_peak(peak) {
  for (DeviceBuffer* b : {&m_position, &m_rotation, &m_scale, &m_dc, &m_rest, &m_chunks, &m_ids, &m_draw_chunks,
                          &m_draw_bases, &m_device_staging, &m_device_pages})
    b->bind(current, peak, stream);
  for (int k = 0; k < 2; ++k) {
    check_cuda(cudaEventCreateWithFlags(&m_staging_free[k], cudaEventDisableTiming), "event creation");
    check_cuda(cudaEventCreateWithFlags(&m_draw_list_free[k], cudaEventDisableTiming), "event creation");
  }
}

ScenePool::~ScenePool() {
  cudaStreamSynchronize(m_stream);
  for (int k = 0; k < 2; ++k) {
    if (m_staging_free[k]) cudaEventDestroy(m_staging_free[k]);
    if (m_draw_list_free[k]) cudaEventDestroy(m_draw_list_free[k]);
    if (m_draw_list[k]) cudaFreeHost(m_draw_list[k]);
    if (m_draw_bases_host[k]) cudaFreeHost(m_draw_bases_host[k]);
  }
  release_staging();
}

void ScenePool::release_staging() {
  if (m_stream) cudaStreamSynchronize(m_stream);
  if (m_staged_pages) cudaFreeHost(m_staged_pages);
  if (m_staging) cudaFreeHost(m_staging);
  m_staged_pages = nullptr;
  m_staging = nullptr;
  m_device_staging.release();
  m_device_pages.release();
  m_staging_half_bytes = 0;
  m_staging_page_capacity = 0;
}

void ScenePool::size_staging(std::uint64_t resident_bytes) {
  const std::size_t half = resident_bytes ? std::min(kStagingHalfMaxBytes, std::max<std::size_t>(kStagingHalfMinBytes, resident_bytes / 32))
                                          : kStagingHalfMaxBytes;
  if (half == m_staging_half_bytes) return;
  release_staging();
  const std::size_t record_bytes = (kShapeVec4 + m_rest_stride_vec4) * sizeof(float4);
  m_staging_page_capacity = std::max<std::size_t>(1, half / (kChunkSize * record_bytes));
  m_staging_half_bytes = m_staging_page_capacity * kChunkSize * record_bytes;
  check_cuda(cudaMallocHost(&m_staging, 2 * m_staging_half_bytes), "pinned pool staging allocation");
  check_cuda(cudaMallocHost(&m_staged_pages, 2 * m_staging_page_capacity * sizeof(uint2)), "pinned pool page table");
  m_device_staging.reserve(2 * m_staging_half_bytes, "pool staging");
  m_device_pages.reserve(2 * m_staging_page_capacity * sizeof(uint2), "pool page table");
}

std::size_t ScenePool::staging_bytes() const {
  return m_device_staging.bytes() + m_device_pages.bytes();
}

std::size_t ScenePool::page_bytes() const {
  // The shape, colour, SH bands and id of each Gaussian; the page's bounds and draw-list entry.
  const std::size_t per_gaussian = 3 * sizeof(float4) + sizeof(float2) + m_rest_stride_vec4 * sizeof(float4) +
                                   sizeof(std::uint32_t);
  return kChunkSize * per_gaussian + sizeof(ChunkBound) + 2 * sizeof(std::uint32_t);
}

std::uint64_t ScenePool::bytes() const {
  std::uint64_t total = 0;
  for (const DeviceBuffer* b : {&m_position, &m_rotation, &m_scale, &m_dc, &m_rest, &m_chunks, &m_ids, &m_draw_chunks,
                                &m_draw_bases, &m_device_staging, &m_device_pages})
    total += b->bytes();
  return total;
}

void ScenePool::clear() {
  if (m_stream) cudaStreamSynchronize(m_stream);
  for (DeviceBuffer* b : {&m_position, &m_rotation, &m_scale, &m_dc, &m_rest, &m_chunks, &m_ids, &m_draw_chunks, &m_draw_bases})
    b->release();
  m_free_pages.clear();
  m_parts.clear();
  m_capacity_pages = 0;
  m_sh_degree = -1;
  m_scene = DeviceScene{};
  m_drawn_gaussians = 0;
}

void ScenePool::reset_layout(int sh_degree) {
  clear();
  m_sh_degree = sh_degree;
  const int rest_floats = 3 * (sh_coefficient_count(sh_degree) - 1);
  m_rest_stride_vec4 = (rest_floats + 3) / 4;
  release_staging();  // its records are of the new layout
}

void ScenePool::grow(std::size_t pages) {
  if (pages <= m_capacity_pages) return;
  const std::size_t old = m_capacity_pages * kChunkSize, now = pages * kChunkSize;
  grow_keeping(m_position, now * sizeof(float4), old * sizeof(float4), m_current, m_peak, m_stream, "pool positions");
  grow_keeping(m_rotation, now * sizeof(float4), old * sizeof(float4), m_current, m_peak, m_stream, "pool rotations");
  grow_keeping(m_scale, now * sizeof(float4), old * sizeof(float4), m_current, m_peak, m_stream, "pool scales");
  grow_keeping(m_dc, now * sizeof(float2), old * sizeof(float2), m_current, m_peak, m_stream, "pool colours");
  if (m_rest_stride_vec4 > 0)
    grow_keeping(m_rest, now * m_rest_stride_vec4 * sizeof(float4), old * m_rest_stride_vec4 * sizeof(float4), m_current,
                 m_peak, m_stream, "pool SH bands");
  grow_keeping(m_chunks, pages * sizeof(ChunkBound), m_capacity_pages * sizeof(ChunkBound), m_current, m_peak, m_stream,
               "pool page bounds");
  m_ids.reserve(now * sizeof(std::uint32_t), "pool Gaussian ids");  // rewritten for every cut
  m_draw_chunks.reserve(pages * sizeof(std::uint32_t), "pool draw list");
  m_draw_bases.reserve(pages * sizeof(std::uint32_t), "pool draw list");
  // Highest pages last, so that the lowest free page is used first.
  for (std::size_t p = pages; p-- > m_capacity_pages;) m_free_pages.push_back(static_cast<std::uint32_t>(p));
  m_capacity_pages = pages;
}

void ScenePool::evict(const std::unordered_map<std::uint64_t, Resident>::iterator& victim) {
  for (std::uint32_t page : victim->second.pages) m_free_pages.push_back(page);
  m_parts.erase(victim);
}

bool ScenePool::evict_least_recent() {
  auto victim = m_parts.end();
  for (auto it = m_parts.begin(); it != m_parts.end(); ++it)
    if (it->second.last_drawn < m_generation && (victim == m_parts.end() || it->second.last_drawn < victim->second.last_drawn))
      victim = it;
  if (victim == m_parts.end()) return false;
  evict(victim);
  return true;
}

void ScenePool::set_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) {
  try {
    ++m_generation;
    if (!parts.empty() && parts.front().source->sh_degree != m_sh_degree) reset_layout(parts.front().source->sh_degree);
    std::vector<const ScenePart*> missing;
    std::size_t needed = 0;
    for (const ScenePart& part : parts) {
      if (part.source->sh_degree != m_sh_degree)
        throw Error("cuda renderer: scene parts of SH degree " + std::to_string(part.source->sh_degree) + " beside " +
                    std::to_string(m_sh_degree));
      if (part.first > part.source->size() || part.count > part.source->size() - part.first)
        throw Error("cuda renderer: a scene part beyond its scene's " + std::to_string(part.source->size()) + " Gaussians");
      auto it = m_parts.find(part.key);
      if (it != m_parts.end()) {
        it->second.last_drawn = m_generation;
        continue;
      }
      m_parts[part.key].last_drawn = m_generation;  // pages come with the upload
      missing.push_back(&part);
      needed += pages_for(part.count);
    }
    size_staging(resident_bytes);
    const std::size_t limit_pages = resident_bytes ? std::max<std::size_t>(1, (resident_bytes - std::min<std::uint64_t>(
                                                                                     resident_bytes, staging_bytes())) /
                                                                                     page_bytes())
                                                   : std::numeric_limits<std::size_t>::max();
    const auto used = [&] { return m_capacity_pages - m_free_pages.size(); };
    while ((m_free_pages.size() < needed || used() + needed > limit_pages) && evict_least_recent()) {
    }
    if (m_free_pages.size() < needed) {
      const std::size_t wanted = used() + needed;
      grow(std::max(wanted, std::min(limit_pages, wanted + wanted / 4)));
    }
    upload(missing);
    write_draw_list(parts);
  } catch (...) {
    clear();
    throw;
  }
}

void ScenePool::upload(const std::vector<const ScenePart*>& parts) {
  // Each part's pages in turn: (part, its page k, the pool page).
  struct PageJob {
    const ScenePart* part;
    std::size_t page;
    std::uint32_t pool_page;
  };
  std::vector<PageJob> jobs;
  for (const ScenePart* part : parts) {
    Resident& resident = m_parts[part->key];
    const Scene& s = *part->source;
    for (int a = 0; a < 3; ++a) {
      resident.lo[a] = INFINITY;
      resident.hi[a] = -INFINITY;
    }
    resident.max_opacity = 1.0f;
    for (std::size_t i = part->first; i < part->first + part->count; ++i) {
      for (int a = 0; a < 3; ++a) {
        resident.lo[a] = std::min(resident.lo[a], s.positions[i * 3 + a]);
        resident.hi[a] = std::max(resident.hi[a], s.positions[i * 3 + a]);
      }
      resident.max_opacity = std::max(resident.max_opacity, s.opacities[i]);
    }
    for (std::size_t k = 0; k < pages_for(part->count); ++k) {
      const std::uint32_t page = m_free_pages.back();
      m_free_pages.pop_back();
      resident.pages.push_back(page);
      jobs.push_back(PageJob{part, k, page});
    }
    m_uploaded += part->count;
  }
  const std::size_t record_vec4 = kShapeVec4 + m_rest_stride_vec4;
  const int rest_floats = 3 * (sh_coefficient_count(m_sh_degree) - 1);
  for (std::size_t begin = 0; begin < jobs.size(); begin += m_staging_page_capacity) {
    const std::size_t end = std::min(jobs.size(), begin + m_staging_page_capacity);
    check_cuda(cudaEventSynchronize(m_staging_free[m_half]), "pool upload");  // the half's last copy landed
    float4* staged = reinterpret_cast<float4*>(static_cast<char*>(m_staging) + m_half * m_staging_half_bytes);
    uint2* table = m_staged_pages + m_half * m_staging_page_capacity;
    for_each_host_range(end - begin, host_threads_for((end - begin) * kChunkSize, 4096),
                        [&](unsigned, std::size_t lo, std::size_t hi) {
      for (std::size_t j = lo; j < hi; ++j) {
        const PageJob& job = jobs[begin + j];
        const Scene& s = *job.part->source;
        const std::size_t first = job.part->first + job.page * kChunkSize;
        const std::size_t members = std::min<std::size_t>(kChunkSize, job.part->count - job.page * kChunkSize);
        table[j] = make_uint2(job.pool_page, static_cast<unsigned>(members));
        for (std::size_t m = 0; m < members; ++m) {
          const std::size_t i = first + m;
          float4* record = staged + (j * kChunkSize + m) * record_vec4;
          const float* p = &s.positions[i * 3];
          const float* q = &s.rotations[i * 4];
          const float* sc = &s.scales[i * 3];
          const float* dc = &s.sh_dc[i * 3];
          record[0] = make_float4(p[0], p[1], p[2], s.opacities[i]);
          record[1] = make_float4(q[0], q[1], q[2], q[3]);
          record[2] = make_float4(sc[0], sc[1], sc[2], dc[0]);
          record[3] = make_float4(dc[1], dc[2], 0.0f, 0.0f);
          if (rest_floats > 0) {
            float* rest = reinterpret_cast<float*>(record + kShapeVec4);
            std::memset(rest, 0, m_rest_stride_vec4 * sizeof(float4));
            std::memcpy(rest, &s.sh_rest[i * rest_floats], rest_floats * sizeof(float));
          }
        }
      }
    });
    const std::size_t count = end - begin;
    char* device_staging = m_device_staging.as<char>() + m_half * m_staging_half_bytes;
    uint2* device_pages = m_device_pages.as<uint2>() + m_half * m_staging_page_capacity;
    check_cuda(cudaMemcpyAsync(device_staging, staged, count * kChunkSize * record_vec4 * sizeof(float4),
                               cudaMemcpyHostToDevice, m_stream),
               "pool upload");
    check_cuda(cudaMemcpyAsync(device_pages, table, count * sizeof(uint2), cudaMemcpyHostToDevice, m_stream), "pool upload");
    DeviceScene pool = m_scene;
    pool.position_opacity = m_position.as<float4>();
    pool.rotation = m_rotation.as<float4>();
    pool.scale_dc_r = m_scale.as<float4>();
    pool.dc_gb = m_dc.as<float2>();
    pool.sh_rest = m_rest_stride_vec4 > 0 ? m_rest.as<float4>() : nullptr;
    pool.chunks = m_chunks.as<ChunkBound>();
    pool.count = m_capacity_pages * kChunkSize;
    const unsigned blocks = static_cast<unsigned>(std::min<std::size_t>(4096, (count * kChunkSize + kScatterBlock - 1) / kScatterBlock));
    pool_scatter_kernel<<<blocks, kScatterBlock, 0, m_stream>>>(reinterpret_cast<const float4*>(device_staging),
                                                              static_cast<unsigned>(record_vec4), device_pages,
                                                              static_cast<unsigned>(count), pool);
    check_cuda(cudaGetLastError(), "pool scatter kernel launch");
    pool.draw_chunks = m_draw_chunks.as<std::uint32_t>();  // marks the scene pooled for the bounds pass
    launch_page_bounds(pool, device_pages, static_cast<unsigned>(count), m_stream);
    check_cuda(cudaEventRecord(m_staging_free[m_half], m_stream), "event record");
    m_half ^= 1;
  }
}

void ScenePool::write_draw_list(const std::vector<ScenePart>& parts) {
  std::size_t pages = 0;
  for (const ScenePart& part : parts) pages += pages_for(part.count);
  if (pages > m_draw_list_capacity) {
    check_cuda(cudaStreamSynchronize(m_stream), "pool draw list");  // both copies are done
    for (int k = 0; k < 2; ++k) {
      if (m_draw_list[k]) cudaFreeHost(m_draw_list[k]);
      if (m_draw_bases_host[k]) cudaFreeHost(m_draw_bases_host[k]);
      m_draw_list[k] = m_draw_bases_host[k] = nullptr;
    }
    m_draw_list_capacity = 0;
    const std::size_t capacity = std::max<std::size_t>(pages + pages / 4, 1024);
    for (int k = 0; k < 2; ++k) {
      check_cuda(cudaMallocHost(&m_draw_list[k], capacity * sizeof(std::uint32_t)), "pinned pool draw list");
      check_cuda(cudaMallocHost(&m_draw_bases_host[k], capacity * sizeof(std::uint32_t)), "pinned pool draw list");
    }
    m_draw_list_capacity = capacity;
  }
  check_cuda(cudaEventSynchronize(m_draw_list_free[m_draw_half]), "pool draw list");
  std::uint32_t* list = m_draw_list[m_draw_half];
  std::uint32_t* bases = m_draw_bases_host[m_draw_half];
  std::size_t n = 0;
  SceneBounds bounds;
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  m_drawn_gaussians = 0;
  for (const ScenePart& part : parts) {
    const Resident& resident = m_parts.at(part.key);
    for (std::size_t k = 0; k < resident.pages.size(); ++k) {
      list[n] = resident.pages[k];
      bases[n++] = static_cast<std::uint32_t>(m_drawn_gaussians + k * kChunkSize);
    }
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], double(resident.lo[a]));
      hi[a] = std::max(hi[a], double(resident.hi[a]));
    }
    bounds.max_opacity = std::max(bounds.max_opacity, resident.max_opacity);
    m_drawn_gaussians += part.count;
  }
  double radius2 = 0;
  for (int a = 0; a < 3 && n > 0; ++a) {
    bounds.centre[a] = 0.5 * (lo[a] + hi[a]);
    radius2 += 0.25 * (hi[a] - lo[a]) * (hi[a] - lo[a]);
  }
  bounds.radius = std::sqrt(radius2);
  m_bounds = bounds;
  if (m_drawn_gaussians >= (std::uint64_t{1} << 32))
    throw Error("cuda renderer: " + std::to_string(m_drawn_gaussians) + " Gaussians drawn exceed the 32-bit Gaussian index");
  if (n > 0) {
    check_cuda(cudaMemcpyAsync(m_draw_chunks.as<void>(), list, n * sizeof(std::uint32_t), cudaMemcpyHostToDevice, m_stream),
               "pool draw list");
    check_cuda(cudaMemcpyAsync(m_draw_bases.as<void>(), bases, n * sizeof(std::uint32_t), cudaMemcpyHostToDevice, m_stream),
               "pool draw list");
    const unsigned blocks = static_cast<unsigned>(std::min<std::size_t>(4096, (n * kChunkSize + kScatterBlock - 1) / kScatterBlock));
    pool_ids_kernel<<<blocks, kScatterBlock, 0, m_stream>>>(m_draw_chunks.as<std::uint32_t>(), m_draw_bases.as<std::uint32_t>(),
                                                          static_cast<unsigned>(n), m_ids.as<std::uint32_t>());
    check_cuda(cudaGetLastError(), "pool ids kernel launch");
  }
  check_cuda(cudaEventRecord(m_draw_list_free[m_draw_half], m_stream), "event record");
  m_draw_half ^= 1;

  m_scene = DeviceScene{};
  m_scene.count = m_capacity_pages * kChunkSize;
  m_scene.sh_degree = m_sh_degree;
  m_scene.rest_stride_vec4 = m_rest_stride_vec4;
  m_scene.position_opacity = m_position.as<float4>();
  m_scene.rotation = m_rotation.as<float4>();
  m_scene.scale_dc_r = m_scale.as<float4>();
  m_scene.dc_gb = m_dc.as<float2>();
  m_scene.sh_rest = m_rest_stride_vec4 > 0 ? m_rest.as<float4>() : nullptr;
  m_scene.chunks = m_chunks.as<ChunkBound>();
  m_scene.scene_ids = m_ids.as<std::uint32_t>();
  m_scene.draw_chunks = m_draw_chunks.as<std::uint32_t>();
  m_scene.draw_chunk_count = static_cast<std::uint32_t>(n);
}

}  // namespace cuda
}  // namespace flashgs
