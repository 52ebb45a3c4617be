// The CUDA backend's host side: scene upload, buffer growth, stage launches, events, stats.
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "flashgs/backend_tuning.h"
#include "flashgs/cuda_renderer.h"
#include "flashgs/error.h"
#include "flashgs/frame_params.h"
#include "flashgs/spatial_order.h"
#include "device_buffer.h"
#include "host_parallel.h"
#include "pipeline.h"
#include "scene_pool.h"
#include "scene_upload.h"

namespace flashgs {

namespace cuda {

void check_cuda(cudaError_t status, const char* what) {
  if (status == cudaSuccess) return;
  cudaGetLastError();  // clear a sticky-free error so later calls are not blamed for it
  throw Error(std::string("cuda renderer: ") + what + " failed: " + cudaGetErrorString(status));
}

}  // namespace cuda

bool cuda_available(std::string* why) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    cudaGetLastError();
    if (why) *why = cudaGetErrorString(status);
    return false;
  }
  if (count == 0) {
    if (why) *why = "no CUDA device";
    return false;
  }
  cudaDeviceProp prop{};
  if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess || prop.major < 7) {
    cudaGetLastError();
    if (why) *why = "device 0 is older than compute capability 7.0";
    return false;
  }
  return true;
}

namespace {

using cuda::check_cuda;
using cuda::DeviceBuffer;
using cuda::Clock;
using cuda::seconds_since;

// Owns one CUDA runtime handle (a stream, an event, pinned memory) and destroys it, so that a
// constructor that throws half way leaks nothing.
template <typename Handle, cudaError_t (*Destroy)(Handle)>
class CudaHandle {
 public:
  CudaHandle() = default;
  CudaHandle(const CudaHandle&) = delete;
  CudaHandle& operator=(const CudaHandle&) = delete;
  ~CudaHandle() {
    if (handle_) Destroy(handle_);
  }
  Handle* out() { return &handle_; }  // for the call that creates it
  Handle get() const { return handle_; }

 private:
  Handle handle_ = nullptr;
};
using StreamHandle = CudaHandle<cudaStream_t, cudaStreamDestroy>;
using EventHandle = CudaHandle<cudaEvent_t, cudaEventDestroy>;
using PinnedHandle = CudaHandle<void*, cudaFreeHost>;

// What each frame reads back into pinned host memory.
struct HostReadback {
  cuda::FrameCounters counters;    // after the preprocess: pairs and culls of this frame
  cuda::TileTotals tile_totals[2] = {};  // FrameCounters::tile_totals, per event set
};

int bits_for(std::uint64_t values) {  // bits to hold 0 .. values - 1
  int bits = 0;
  while (bits < 64 && (std::uint64_t{1} << bits) < values) ++bits;
  return bits;
}

std::uint32_t float_exponent(float v) {  // biased exponent field of a positive float
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  return bits >> 23;
}

// The 32-bit key format for a frame of `tiles` tiles whose visible depths lie in
// [min_depth, max_depth]: the exponents that range spans, then as many mantissa bits as fit
// in `key_bits` (a tighter range leaves fewer Gaussians sharing a bin for the ranges pass to
// order; fewer key bits, fewer radix passes but more ties), at least 8 bits of depth.
// Returns the 64-bit format (depth_bits 0) when the tiles leave too few bits for depth.
cuda::KeyFormat compact_key_format(std::uint64_t tiles, double min_depth, double max_depth, int key_bits) {
  cuda::KeyFormat k;
  const int tile_bits = std::max(bits_for(tiles), 1);
  if (32 - tile_bits < 8) return k;
  const int depth_bits = std::min(32 - tile_bits, std::max(8, key_bits - tile_bits));
  const double near = std::max(min_depth, double{gm::kNearZ});
  const float far = static_cast<float>(std::min(std::max(max_depth, near), 1e30));
  const std::uint32_t lo = float_exponent(static_cast<float>(std::min(near, 1e30))), hi = float_exponent(far);
  const int exponent_bits = bits_for(hi - lo + 1);
  k.depth_bits = std::min(depth_bits, exponent_bits + 23);
  k.mantissa_bits = std::max(0, std::min(23, k.depth_bits - exponent_bits));
  k.exponent_base = lo;
  return k;
}

// The bin sort holds at most kBinSortSharedPairsMax pairs of a bin in shared memory.
static_assert(tuning_knob("bin_sort_shared_pairs").max == cuda::kBinSortSharedPairsMax,
              "the bin_sort_shared_pairs knob's range is the bin sort's shared-memory limit");
// A deferred work item is one warp's: at most a chunk per lane.
static_assert(tuning_knob("deferred_item_chunks").max == cuda::kWarp, "the deferred_item_chunks knob's range");

class CudaRendererImpl final : public CudaRenderer {
 public:
  explicit CudaRendererImpl(const BackendTuning& tuning) {
    check_cuda(cudaGetDevice(&device_), "cudaGetDevice");
    cudaDeviceProp prop{};
    check_cuda(cudaGetDeviceProperties(&prop, device_), "cudaGetDeviceProperties");
    device_name_ = prop.name;
    check_cuda(cudaStreamCreateWithFlags(stream_handle_.out(), cudaStreamNonBlocking), "stream creation");
    stream_ = stream_handle_.get();
    check_cuda(cudaStreamCreateWithFlags(copy_stream_handle_.out(), cudaStreamNonBlocking), "stream creation");
    // The knobs of flashgs/backend_tuning.h; each mode's auto is decided per scene or frame
    // (upload_scene, bin_sort_pays, emit_bin_counts_pays, dense_order_pays, run_frame).
    region_width_ = static_cast<int>(tuning.blend_region_width);
    stop_bound_ = tuning.blend_stop_bound != 0;
    large_box_tiles_ = static_cast<int>(tuning.large_box_tiles);
    item_chunks_ = static_cast<int>(tuning.deferred_item_chunks);
    chunk_cull_ = mode_of(tuning.chunk_cull);
    spatial_order_ = mode_of(tuning.spatial_order);
    print_upload_times_ = tuning.upload_times != 0;
    dense_tiles_mode_ = mode_of(tuning.dense_tiles_first);
    sort_key_bits_ = static_cast<int>(tuning.sort_key_bits);
    bin_sort_ = mode_of(tuning.bin_sort);
    bin_sort_shared_pairs_ = static_cast<unsigned>(tuning.bin_sort_shared_pairs);
    emit_bin_counts_ = mode_of(tuning.emit_bin_counts);
    initial_records_ = static_cast<std::uint64_t>(tuning.initial_records);
    // The blend starts beside the bin blocks where the device can launch a kernel early (sm_90
    // and later) unless the knob turns it off.
    int device = 0, major = 0;
    check_cuda(cudaGetDevice(&device), "device query");
    check_cuda(cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device), "device query");
    bin_overlap_ = major >= 9 && tuning.bin_overlap != 0;
    blend_resident_blocks_ = cuda::blend_resident_blocks();
    for (int set = 0; set < 2; ++set)
      for (int e = 0; e < kEventCount; ++e) {
        check_cuda(cudaEventCreate(event_handles_[set][e].out()), "event creation");
        events_[set][e] = event_handles_[set][e].get();
      }
    check_cuda(cudaMallocHost(pinned_.out(), sizeof(HostReadback)), "pinned read-back allocation");
    readback_ = new (pinned_.get()) HostReadback{};
    for (DeviceBuffer* b : working_buffers()) b->bind(&working_bytes_, &peak_bytes_, stream_);
    counters_.reserve(sizeof(cuda::FrameCounters), "frame counters");
  }

  // The handles and buffers free themselves (members); only the work in flight is waited for.
  ~CudaRendererImpl() override {
    if (stream_) cudaStreamSynchronize(stream_);
    if (copy_stream_handle_.get()) cudaStreamSynchronize(copy_stream_handle_.get());
  }

  std::string name() const override { return "cuda (" + device_name_ + ")"; }
  void* stream() const override { return stream_; }

  // Uploaded in the precision of the last frame, so that a viewer in an fp16 mode loads a
  // new scene once. The bounds are the scene's, so a later re-pack keeps them.
  void set_scene(std::shared_ptr<const Scene> scene) override {
    if (!scene) throw Error("cuda renderer: null scene");
    const bool was_pooled = pooled_;
    if (pooled_) device_scene_ = cuda::DeviceScene{};  // the pool's layout is floats
    upload_scene(std::move(scene), device_scene_.sh_half, device_scene_.shape_half);
    if (was_pooled) {
      pool_.reset();
      pooled_ = false;
    }
    const auto bounds_start = Clock::now();
    compute_bounds(*scene_);
    if (print_upload_times_)
      std::fprintf(stderr,
                   "scene upload of %zu Gaussians (%u host threads): order %.3f s, allocation %.3f s, packing %.3f s, "
                   "waiting for copies %.3f s, bounds %.3f s\n",
                   scene_->size(), cuda::host_threads_for(scene_->size(), 1), upload_times_.order, upload_times_.allocation,
                   upload_times_.packing, upload_times_.waiting, seconds_since(bounds_start));
  }

  // The parts stay on the device in a pool of pages (scene_pool.h): only parts not held yet are
  // uploaded, and a frame draws the listed pages. The regular scene's memory is given back.
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) override {
    if (!pool_) pool_ = std::make_unique<cuda::ScenePool>(stream_, &pool_bytes_, &pool_peak_bytes_);
    if (!pooled_) {
      check_cuda(cudaStreamSynchronize(stream_), "stream synchronisation");
      for (DeviceBuffer* b : {&scene_pos_, &scene_rot_, &scene_scale_, &scene_dc_, &scene_rest_, &scene_chunks_, &scene_ids_})
        b->release();
      scene_.reset();
    }
    pooled_ = true;
    device_scene_ = cuda::DeviceScene{};
    pool_->set_parts(parts, resident_bytes);  // on failure the pool is empty: frames draw nothing
    device_scene_ = pool_->scene();
    const cuda::SceneBounds& bounds = pool_->bounds();
    for (int a = 0; a < 3; ++a) bounds_centre_[a] = bounds.centre[a];
    bounds_radius_ = bounds.radius;
    max_opacity_ = bounds.max_opacity;
    last_tiles_ = 0;
  }

  // The scene on the device in the layout of DeviceScene: its SH as floats or (`sh_half`,
  // RenderOptions::fp16_sh) as halves, its rotation, scale and opacity as floats or
  // (`shape_half`, RenderOptions::fp16_shape) as one record of halves.
  void upload_scene(std::shared_ptr<const Scene> scene, bool sh_half, bool shape_half) {
    const std::size_t n = scene->size();
    if (n >= (std::size_t{1} << 32) - 1)
      throw Error("cuda renderer: " + std::to_string(n) + " Gaussians exceed the 32-bit Gaussian index");
    const int degree = scene->sh_degree;
    const int rest_floats = scene->sh_rest_per_gaussian();
    const int stride_vec4 = (rest_floats + 3) / 4;
    const std::size_t rest_group_bytes = sh_half ? sizeof(uint2) : sizeof(float4);  // 4 coefficients
    // Under fp16_sh the DC keeps its float slots but holds the half values.
    const auto dc = [&](std::size_t k) { return sh_half ? gm::round_to_half(scene->sh_dc[k]) : scene->sh_dc[k]; };

    // The device layout in spatial order where the stored one lacks it: device Gaussian i is
    // scene Gaussian order[i].
    const auto order_start = Clock::now();
    std::vector<std::uint32_t> order;
    if (spatial_order_ == kAlways) order = spatial_order(*scene);
    else if (spatial_order_ == kAuto && n >= kSpatialOrderMinGaussians) order = spatial_order_where_it_pays(*scene);
    upload_times_.order = seconds_since(order_start);
    const auto allocation_start = Clock::now();

    // Allocate the new scene next to the old one; on failure the old one stays.
    DeviceBuffer new_pos, new_rot, new_scale, new_dc, new_rest, new_chunks, new_ids;
    const std::size_t m = std::max<std::size_t>(n, 1);
    const std::size_t chunks = (n + cuda::kChunkSize - 1) / cuda::kChunkSize;
    new_pos.reserve(m * sizeof(float4), "scene positions");
    new_rot.reserve(m * sizeof(float4), shape_half ? "scene rotations, scales and opacities" : "scene rotations");
    if (!shape_half) new_scale.reserve(m * sizeof(float4), "scene scales");
    new_dc.reserve(m * sizeof(float2), "scene colours");
    if (stride_vec4 > 0) new_rest.reserve(n * stride_vec4 * rest_group_bytes, "scene SH bands");
    new_chunks.reserve(std::max<std::size_t>(chunks, 1) * sizeof(cuda::ChunkBound), "scene chunk bounds");
    // A reordered scene is read in its stored order and scattered on the device: gathering it
    // on the host cost ~0.1 s per million Gaussians.
    DeviceBuffer places, scatter_staging;  // during the upload only
    if (!order.empty()) {
      new_ids.reserve(n * sizeof(std::uint32_t), "scene order");
      places.reserve(n * sizeof(std::uint32_t), "the upload's scene order");
      scatter_staging.reserve(cuda::SceneUploader::kDeviceStagingBytes, "the upload's staging");
    }

    // Packed into the device layout chunk by chunk (no host copy of the whole scene), each
    // pack(i) reading scene Gaussian i.
    check_cuda(cudaStreamSynchronize(stream_), "stream synchronisation");
    upload_times_.allocation = seconds_since(allocation_start);
    const Scene& sc = *scene;
    cuda::SceneUploader uploader(stream_);
    if (!order.empty()) {
      uploader.upload(new_ids.as<void>(), sizeof(std::uint32_t), n,
                      [&](std::size_t i, void* dst) { *static_cast<std::uint32_t*>(dst) = order[i]; });
      cuda::launch_inverse_order(new_ids.as<std::uint32_t>(), n, places.as<std::uint32_t>(), stream_);
      uploader.scatter_to(places.as<std::uint32_t>(), scatter_staging.as<void>());
    }
    // The position's fourth float: the DC red under fp16_shape (the opacity moves into the
    // record of halves), the opacity otherwise.
    uploader.upload(new_pos.as<void>(), sizeof(float4), n, [&](std::size_t i, void* dst) {
      const float* p = &sc.positions[i * 3];
      *static_cast<float4*>(dst) = make_float4(p[0], p[1], p[2], shape_half ? dc(i * 3) : sc.opacities[i]);
    });
    if (shape_half) {
      uploader.upload(new_rot.as<void>(), sizeof(uint4), n, [&](std::size_t i, void* dst) {
        const float* q = &sc.rotations[i * 4];
        const float* sv = &sc.scales[i * 3];
        const auto pair = [](float low, float high) {
          return static_cast<unsigned>(gm::float_to_half_bits(low)) |
                 static_cast<unsigned>(gm::float_to_half_bits(high)) << 16;
        };
        *static_cast<uint4*>(dst) = make_uint4(pair(q[0], q[1]), pair(q[2], q[3]), pair(sv[0], sv[1]),
                                               pair(sv[2], sc.opacities[i]));
      });
    } else {
      uploader.upload(new_rot.as<void>(), sizeof(float4), n, [&](std::size_t i, void* dst) {
        const float* q = &sc.rotations[i * 4];
        *static_cast<float4*>(dst) = make_float4(q[0], q[1], q[2], q[3]);
      });
      uploader.upload(new_scale.as<void>(), sizeof(float4), n, [&](std::size_t i, void* dst) {
        const float* sv = &sc.scales[i * 3];
        *static_cast<float4*>(dst) = make_float4(sv[0], sv[1], sv[2], dc(i * 3));
      });
    }
    uploader.upload(new_dc.as<void>(), sizeof(float2), n, [&](std::size_t i, void* dst) {
      *static_cast<float2*>(dst) = make_float2(dc(i * 3 + 1), dc(i * 3 + 2));
    });
    if (stride_vec4 > 0)
      uploader.upload(new_rest.as<void>(), stride_vec4 * rest_group_bytes, n, [&](std::size_t i, void* dst) {
        std::memset(dst, 0, rest_group_bytes * stride_vec4);
        const float* rest = &sc.sh_rest[i * rest_floats];
        if (!sh_half) {
          std::memcpy(dst, rest, sizeof(float) * rest_floats);
          return;
        }
        std::uint16_t* halves = static_cast<std::uint16_t*>(dst);
        for (int k = 0; k < rest_floats; ++k) halves[k] = gm::float_to_half_bits(rest[k]);
      });
    cuda::DeviceScene next;
    next.count = n;
    next.sh_degree = degree;
    next.rest_stride_vec4 = stride_vec4;
    next.sh_half = sh_half;
    next.shape_half = shape_half;
    if (shape_half) {
      next.position_dc_r = new_pos.as<float4>();
      next.shape_record = new_rot.as<uint4>();
    } else {
      next.position_opacity = new_pos.as<float4>();
      next.rotation = new_rot.as<float4>();
      next.scale_dc_r = new_scale.as<float4>();
    }
    next.dc_gb = new_dc.as<float2>();
    next.sh_rest = sh_half ? nullptr : new_rest.as<float4>();
    next.sh_rest_half = sh_half ? new_rest.as<uint2>() : nullptr;
    next.chunks = new_chunks.as<cuda::ChunkBound>();
    next.scene_ids = order.empty() ? nullptr : new_ids.as<std::uint32_t>();
    cuda::launch_chunk_bounds(next, next.chunks, stream_);
    uploader.finish();
    upload_times_.packing = uploader.pack_seconds();
    upload_times_.waiting = uploader.wait_seconds();
    // The buffers change owners, not addresses: `next` stays valid.
    scene_pos_.swap(new_pos);
    scene_rot_.swap(new_rot);
    scene_scale_.swap(new_scale);
    scene_dc_.swap(new_dc);
    scene_rest_.swap(new_rest);
    scene_chunks_.swap(new_chunks);
    scene_ids_.swap(new_ids);
    device_scene_ = next;
    scene_ = std::move(scene);
    last_tiles_ = 0;
    settled_.known = false;  // the tile statistics were another scene's
  }

  void render(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) override {
    run_frame(camera, options, FrameTarget::host_image, &out, 0, stats);
  }

  void render_to_surface(const Camera& camera, const RenderOptions& options, std::uint64_t surface_object,
                         FrameStats* stats) override {
    run_frame(camera, options, FrameTarget::surface, nullptr, surface_object, stats);
  }

  void render_queued(const Camera& camera, const RenderOptions& options, FrameStats* stats) override {
    run_frame(camera, options, FrameTarget::device_image, nullptr, 0, stats);
  }

  void render_to_device(const Camera& camera, const RenderOptions& options, void* destination,
                        FrameStats* stats) override {
    if (!destination) throw Error("cuda renderer: no device buffer to render into");
    run_frame(camera, options, FrameTarget::device_copy, nullptr, 0, stats, destination);
  }

  void finish() override { check_cuda(cudaStreamSynchronize(stream_), "frame"); }

  // The debug planes of the last frame (per_pixel_options), waited for.
  void download_pixel_planes(int width, int height, FrameStats& stats) {
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    stats.pixel_depth.resize(pixels);
    stats.pixel_blended.resize(pixels);
    check_cuda(cudaMemcpyAsync(stats.pixel_depth.data(), pixel_depth_.as<void>(), pixels * sizeof(float),
                               cudaMemcpyDeviceToHost, stream_),
               "depth plane download");
    check_cuda(cudaMemcpyAsync(stats.pixel_blended.data(), pixel_blended_.as<void>(), pixels * sizeof(std::uint32_t),
                               cudaMemcpyDeviceToHost, stream_),
               "blended-count plane download");
    check_cuda(cudaStreamSynchronize(stream_), "debug plane download");
  }

  void download_tile_counts(std::vector<std::uint32_t>& counts) override {
    counts.resize(last_tiles_);
    std::vector<uint2> ranges(last_tiles_);
    const DeviceBuffer& lists = last_frame_binned_ ? tile_lists_ : ranges_;
    if (last_tiles_)
      check_cuda(cudaMemcpyAsync(ranges.data(), lists.as<void>(), last_tiles_ * sizeof(uint2),
                                 cudaMemcpyDeviceToHost, stream_),
                 "tile range download");
    check_cuda(cudaStreamSynchronize(stream_), "tile range download");
    for (std::size_t t = 0; t < last_tiles_; ++t) counts[t] = ranges[t].y - ranges[t].x;
  }

 private:
  enum Event { kBegin, kProjected, kScanned, kCounted, kEmitBegin, kEmitted, kSortBegin, kSorted, kRanged, kBlended,
               kEventCount };

  std::vector<DeviceBuffer*> working_buffers() {
    return {&counters_, &blend_, &record_ids_, &footprints_, &pair_counts_, &pair_offsets_, &keys_[0], &keys_[1], &values_[0],
            &values_[1], &ranges_, &tile_lists_, &bin_fill_, &bin_ready_, &dense_bins_, &tile_order_, &tile_places_, &chunk_list_, &image_, &cub_temp_,
            &deferred_footprints_, &deferred_records_, &deferred_hits_, &deferred_items_, &pixel_depth_, &pixel_blended_};
  }

  // A sphere around every Gaussian centre (the farthest depth a frame can sort is the camera's
  // distance to its centre plus its radius) and the largest opacity, on the host's threads (at
  // 100M Gaussians one thread took 0.8-0.95 s). Minima and maxima are the same in any order.
  void compute_bounds(const Scene& scene) {
    const std::size_t n = scene.size();
    const unsigned threads = cuda::host_threads_for(n, 1 << 16);
    struct Partial {
      double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
      double radius2 = 0;
      float max_opacity = 1.0f;  // a sigmoid's; a scene built in code may hold more (NaN is never culled by chunk)
    };
    std::vector<Partial> partial(threads);
    cuda::for_each_host_range(n, threads, [&](unsigned t, std::size_t begin, std::size_t end) {
      Partial& p = partial[t];
      for (std::size_t i = begin; i < end; ++i) {
        for (int a = 0; a < 3; ++a) {
          const double v = scene.positions[i * 3 + a];
          p.lo[a] = std::min(p.lo[a], v);
          p.hi[a] = std::max(p.hi[a], v);
        }
        p.max_opacity = std::max(p.max_opacity, scene.opacities[i]);
      }
    });
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    max_opacity_ = 1.0f;
    for (int a = 0; a < 3 && n > 0; ++a) {
      lo[a] = INFINITY;
      hi[a] = -INFINITY;
      for (const Partial& p : partial) {
        lo[a] = std::min(lo[a], p.lo[a]);
        hi[a] = std::max(hi[a], p.hi[a]);
      }
    }
    for (const Partial& p : partial) max_opacity_ = std::max(max_opacity_, p.max_opacity);
    for (int a = 0; a < 3; ++a) bounds_centre_[a] = 0.5 * (lo[a] + hi[a]);
    cuda::for_each_host_range(n, threads, [&](unsigned t, std::size_t begin, std::size_t end) {
      double radius2 = 0;
      for (std::size_t i = begin; i < end; ++i) {
        double d2 = 0;
        for (int a = 0; a < 3; ++a) {
          const double d = scene.positions[i * 3 + a] - bounds_centre_[a];
          d2 += d * d;
        }
        radius2 = std::max(radius2, d2);
      }
      partial[t].radius2 = radius2;
    });
    double radius2 = 0;
    for (const Partial& p : partial) radius2 = std::max(radius2, p.radius2);
    bounds_radius_ = std::sqrt(radius2);
    // fp16_shape may round the largest opacity up (rounding keeps the order, so this is the max).
    max_opacity_ = std::max(max_opacity_, gm::round_to_half(max_opacity_));
  }

  // A pooled scene is drawn through its page list, which only fused emission reads, from its
  // pages of floats.
  std::string scene_parts_refusal(const RenderOptions& options) const override {
    const char* off = options.is_baseline() ? "the baseline"
                      : !options.fused_emit ? "flash without fused emission"
                      : options.fp16_sh     ? "fp16 SH"
                      : options.fp16_shape  ? "fp16 shapes"
                                            : nullptr;
    return off ? std::string("a streamed scene (scene parts) is drawn by flash with fused emission in full precision, "
                             "not by ") + off
               : std::string();
  }
  void check_pooled_options(const RenderOptions& options) const {
    const std::string refusal = scene_parts_refusal(options);
    if (!refusal.empty()) throw Error("cuda renderer: " + refusal);
  }

  double distance_to_bounds_centre(const gm::CameraParams& cam) const {
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = cam.position[a] - bounds_centre_[a];
      d2 += d * d;
    }
    return std::sqrt(d2);
  }

  cuda::DeferredList deferred_list() const {
    cuda::DeferredList list;
    list.footprints = deferred_footprints_.as<gm::Footprint>();
    list.records = deferred_records_.as<std::uint32_t>();
    list.hits = deferred_hits_.as<std::uint32_t>();
    list.items = deferred_items_.as<uint2>();
    list.capacity = static_cast<std::uint32_t>(std::min({deferred_footprints_.bytes() / sizeof(gm::Footprint),
                                                         deferred_records_.bytes() / sizeof(std::uint32_t),
                                                         deferred_hits_.bytes() / sizeof(std::uint32_t)}));
    list.item_capacity = static_cast<std::uint32_t>(deferred_items_.bytes() / sizeof(uint2));
    return list;
  }

  // A frame that wanted more deferred entries or work items than the list holds emitted the
  // rest in preprocess, each box walked by the one warp that met it: with thousands of
  // frame-wide Gaussians (kacytran_try at 4K wants 24k-29k items, 1.3 ms of project stage)
  // that warp's serial walk set the kernel's length. The next frames get what this one
  // wanted, and a quarter more.
  void grow_deferred(std::uint64_t entries, std::uint64_t items) {
    const cuda::DeferredList list = deferred_list();
    if (entries > list.capacity) {
      const std::uint64_t capacity = std::min<std::uint64_t>(entries + entries / 4, device_scene_.count);
      deferred_footprints_.reserve(capacity * sizeof(gm::Footprint), "deferred-Gaussian footprints");
      deferred_records_.reserve(capacity * sizeof(std::uint32_t), "deferred-Gaussian records");
      deferred_hits_.reserve(capacity * sizeof(std::uint32_t), "deferred-Gaussian hits");
    }
    if (items > list.item_capacity) deferred_items_.reserve((items + items / 4) * sizeof(uint2), "deferred work items");
  }

  // Blend records the buffers hold: compact ones need an id each as well.
  std::uint32_t record_capacity() const {
    std::size_t records = blend_.bytes() / sizeof(cuda::BlendGaussian);
    if (compact_records_) records = std::min(records, record_ids_.bytes() / sizeof(std::uint32_t));
    return static_cast<std::uint32_t>(std::min<std::size_t>(records, UINT32_MAX));
  }

  // Compact records for at least `records` projected Gaussians (at most the scene's), with
  // `headroom` (a quarter more: the pair buffers' policy) so that a moving camera does not
  // grow them every few frames.
  void grow_records(std::uint64_t records, bool headroom) {
    if (records <= record_capacity()) return;
    const std::uint64_t wanted = headroom ? std::max<std::uint64_t>(records + records / 4, 1u << 16) : records;
    const std::uint64_t capacity = std::max<std::uint64_t>(1, std::min<std::uint64_t>(device_scene_.count, wanted));
    blend_.reserve(capacity * sizeof(cuda::BlendGaussian), "blend records");
    record_ids_.reserve(capacity * sizeof(std::uint32_t), "blend record ids");
  }

  cuda::FrameBuffers frame_buffers() const {
    cuda::FrameBuffers b;
    b.bins = bins_;
    b.key_format = key_format_;
    b.blend = blend_.as<cuda::BlendGaussian>();
    b.record_ids = compact_records_ ? record_ids_.as<std::uint32_t>() : nullptr;
    b.scene_ids = device_scene_.scene_ids;
    b.record_capacity = record_capacity();
    b.footprints = footprints_.as<gm::Footprint>();
    b.pair_counts = pair_counts_.as<std::uint32_t>();
    b.pair_offsets = pair_offsets_.as<std::uint32_t>();
    for (int k = 0; k < 2; ++k) {
      b.keys[k] = keys_[k].as<std::uint64_t>();
      b.values[k] = values_[k].as<std::uint32_t>();
    }
    b.pair_capacity = pair_capacity_;
    b.pair_values = bin_sort_frame_ ? keys_[0].as<std::uint32_t>() + pair_capacity_ : b.values[0];
    b.bin_fill = bin_fill_.as<std::uint32_t>();
    b.emitted_bin_counts = emitted_counts_frame_ ? b.bin_fill + static_cast<std::uint64_t>(bins_.x) * bins_.y : nullptr;
    b.deferred = deferred_list();
    b.tile_ranges = ranges_.as<uint2>();
    b.tile_capacity = ranges_.bytes() / sizeof(uint2);
    for (int k = 0; k < 2; ++k) b.tile_values[k] = keys_[k].as<std::uint32_t>();
    b.tile_lists = tile_lists_.as<uint2>();
    b.dense_bins = dense_bins_.as<std::uint32_t>();
    b.tile_order = tile_order_.as<std::uint32_t>();
    b.tile_places = tile_places_.as<std::uint32_t>();
    b.image_rgb = image_.as<float>();
    b.pixel_capacity = image_.bytes() / (3 * sizeof(float));
    b.cub_temp = cub_temp_.as<void>();
    b.cub_temp_bytes = cub_temp_.bytes();
    b.counters = counters_.as<cuda::FrameCounters>();
    b.chunk_list = list_chunks_ ? chunk_list_.as<std::uint32_t>() : nullptr;
    return b;
  }

  // Pair buffers for at least `pairs`, with a quarter of headroom so that a camera moving
  // through the scene does not grow them every few frames.
  void grow_pairs(std::uint64_t pairs) {
    if (pairs <= pair_capacity_) return;
    const std::uint64_t capacity = std::max<std::uint64_t>(pairs + pairs / 4, 1u << 16);
    pair_capacity_ = 0;  // stays 0 if an allocation below throws: nothing can be written
    for (int k = 0; k < 2; ++k) {
      keys_[k].reserve(capacity * sizeof(std::uint64_t), "sort keys");
      values_[k].reserve(capacity * sizeof(std::uint32_t), "sort values");
    }
    pair_capacity_ = capacity;
    grow_cub_temp();
  }

  // CUB's size queries (three of them) run only when the scene or the pair capacity changed.
  void grow_cub_temp() {
    if (device_scene_.count == cub_sized_for_gaussians_ && pair_capacity_ == cub_sized_for_pairs_) return;
    cub_temp_.reserve(std::max<std::size_t>(cuda::cub_temp_bytes_needed(device_scene_.count, pair_capacity_), 16),
                      "sort scratch");
    cub_sized_for_gaussians_ = device_scene_.count;  // only once the reserve succeeded
    cub_sized_for_pairs_ = pair_capacity_;
  }

  // Whether counting the pairs per bin in emission (FrameBuffers::emitted_bin_counts) pays over
  // the counting pass. Measured on an H200 (docs/PERFORMANCE.md): at 1080p (2,040 bins)
  // pc_playbot 0.280 -> 0.277-0.278 ms and pc_biker 0.190-0.192 -> 0.188-0.189; at 4K (8,160
  // bins) 0.589 -> 0.644-0.648 and 0.371-0.372 -> 0.391-0.392, where every scatter block scans
  // four times as many counts and every preprocess block clears and flushes four times as many.
  bool emit_bin_counts_pays(std::uint64_t bins) const {
    if (emit_bin_counts_ != kAuto) return emit_bin_counts_ == kAlways;
    return bins <= kBinSortAnyCoverageBins;
  }

  // Whether this frame blends its tiles fullest first (launch_tile_order, or the bin sort's order).
  bool dense_order(const RenderOptions& options, bool baseline, std::uint64_t tiles) const {
    return !baseline && options.dense_tiles_first && dense_order_pays(tiles);
  }

  // Whether ordering the tiles fullest first pays this frame. It costs two small kernels and
  // the locality of neighbouring tiles blending together, and gains when one tile's serial walk
  // outlasts what the blend's resident blocks do in a wave: when the fullest tile holds more
  // pairs than the mean per resident block. Judged on the latest finished frame (settled_), if
  // of the same size (the view moves little between frames); the first frame blends in image
  // order.
  bool dense_order_pays(std::uint64_t tiles) const {
    if (dense_tiles_mode_ != kAuto) return dense_tiles_mode_ == kAlways;
    if (!settled_.known || tiles != settled_.tiles || settled_.tile_pairs == 0) return false;
    return settled_.fullest_tile * blend_resident_blocks_ > settled_.tile_pairs;
  }

  // Keeps the tile statistics of the frame of event set `set`, which has finished.
  void settle(int set) {
    const cuda::TileTotals& totals = readback_->tile_totals[set];
    settled_ = SettledFrame{true, frame_tiles_[set], totals.tile_pairs, totals.max_tile_pairs};
  }

  // Whether sorting per bin (launch_bin_pairs, launch_bin_blocks) pays over CUB's radix sort of the whole frame.
  // Measured on an H200 (docs/PERFORMANCE.md): sort + ranges 18-41 us shorter at
  // 1080p on pc_biker and pc_playbot (2,040 bins of 200-400 pairs); at 4K (8,160 bins), since
  // the bin blocks write their tile lists without idle groups, 7-31 us shorter on five real
  // scenes, with no wait for the host between emission and sort, but not for frames of
  // frame-covering Gaussians (below); 0.1 ms longer on 7 x pc_playbot at 1080p (about 700
  // pairs per bin; bins of more than 1,024 sort in global memory). Judged on
  // the last frame's bin pairs and blend records: the emission that this decides comes before
  // this frame's count.
  bool bin_sort_pays(std::uint64_t bins) const {
    if (bins > cuda::kBinSortMaxBins) return false;  // beyond the scatter pass's shared histogram
    if (bin_sort_ != kAuto) return bin_sort_ == kAlways;
    if (last_bin_pairs_ > kBinSortMostPairsPerBin * bins) return false;
    // Frames whose Gaussians cover much of the frame (kacytran_try: ~200 bin pairs per visible
    // Gaussian, against ~4 on pc_playbot) lose at 4K: a chunk of pairs meets ~2,048 bins, and
    // the counting passes pay a global atomic per bin and chunk. At 1080p they still win.
    return bins <= kBinSortAnyCoverageBins || last_records_ == 0 ||
           last_bin_pairs_ <= kBinSortMostPairsPerGaussian * last_records_;
  }

  // Queues the read back of the frame's counters and the event the host waits for (kCounted):
  // on the frame's stream, or with `after` (the event of the work whose counts it reads) on a
  // stream of its own, so that the frame's next kernels do not wait for the copy (2-4 us a
  // frame on the H200 machine, docs/PERFORMANCE.md). Later kernels of the frame write only
  // counters that this read back is not used for, and the next frame resets them only after
  // the host has waited for it.
  void read_back_counts(const cuda::FrameBuffers& b, cudaEvent_t after) {
    cudaStream_t stream = stream_;
    if (after) {
      stream = copy_stream_handle_.get();
      check_cuda(cudaStreamWaitEvent(stream, after, 0), "pair count read back");
    }
    check_cuda(cudaMemcpyAsync(&readback_->counters, b.counters, sizeof(cuda::FrameCounters), cudaMemcpyDeviceToHost,
                               stream),
               "pair count read back");
    check_cuda(cudaEventRecord(events_[event_set_][kCounted], stream), "event record");
  }

  // Stage times of the frame whose events are in `set` (its work must have finished).
  StageTimes stage_times(int set) const {
    auto elapsed = [this, set](Event a, Event b) {
      float ms = 0;
      check_cuda(cudaEventElapsedTime(&ms, events_[set][a], events_[set][b]), "event timing");
      return static_cast<double>(ms);
    };
    StageTimes t;
    t.project_ms = elapsed(kBegin, kProjected);
    // Fused emission is in the project stage: such frames record no emit events.
    t.emit_ms = separate_emit_[set] ? elapsed(kProjected, kScanned) + elapsed(kEmitBegin, kEmitted) : 0.0;
    const Event sort_begin = sort_follows_project_[set] ? kProjected : kSortBegin;
    const Event ranged = ranges_in_sort_[set] ? kSorted : kRanged;
    t.sort_ms = elapsed(sort_begin, kSorted);
    t.ranges_ms = ranges_in_sort_[set] ? 0.0 : elapsed(kSorted, kRanged);
    t.blend_ms = elapsed(ranged, kBlended);
    t.sort_in_blend = sort_in_blend_[set];
    t.total_ms = t.project_ms + t.emit_ms + t.sort_ms + t.ranges_ms + t.blend_ms;
    return t;
  }

  // The blend writes RGBA8 pixels up to the camera's size: the surface must be an array of at
  // least that size with 4 x 8-bit channels, or the writes would land outside it.
  static void check_surface(std::uint64_t surface, const Camera& camera) {
    cudaResourceDesc desc{};
    check_cuda(cudaGetSurfaceObjectResourceDesc(&desc, static_cast<cudaSurfaceObject_t>(surface)),
               "surface query");
    if (desc.resType != cudaResourceTypeArray) throw Error("cuda renderer: the surface is not backed by a CUDA array");
    cudaChannelFormatDesc format{};
    cudaExtent extent{};
    unsigned flags = 0;
    check_cuda(cudaArrayGetInfo(&format, &extent, &flags, desc.res.array.array), "surface array query");
    if (format.x != 8 || format.y != 8 || format.z != 8 || format.w != 8)
      throw Error("cuda renderer: the surface is not RGBA8");
    if (extent.width < static_cast<std::size_t>(camera.width) || extent.height < static_cast<std::size_t>(camera.height))
      throw Error("cuda renderer: the surface is " + std::to_string(extent.width) + "x" +
                  std::to_string(extent.height) + ", smaller than the " + std::to_string(camera.width) + "x" +
                  std::to_string(camera.height) + " frame");
  }

  // Where a frame's pixels go: the host (render: downloaded, the frame waited for), a caller's
  // device buffer (render_to_device: copied there, waited for), a surface or the device image
  // (render_to_surface, render_queued: neither).
  enum class FrameTarget { host_image, device_copy, surface, device_image };

  // What the work after the pair count needs of its frame (run_frame).
  struct FramePlan {
    const Camera* camera;
    const gm::CameraParams* cam;
    const RenderOptions* options;
    const cuda::PreprocessArgs* args;
    Image* out;
    void* device_out;  // render_to_device's buffer
    std::uint64_t surface;
    bool float_image;  // the blend writes the device image (out, device_out, or a queued frame)
    std::uint64_t tiles, bins, pixels;
    bool baseline, fused, binned;
    bool sort_follows_project;  // nothing is queued between the project and sort stages
    // The host waits for the frame's end (its image goes to the host or a caller's buffer).
    bool waited() const { return out != nullptr || device_out != nullptr; }
  };

  // Queues the frame's work after preprocess: separate emission, sort, ranges, blend, the
  // statistics and the image download. `pairs` is the frame's pair count; a bin-sort frame
  // reads it on the device instead (pass 0).
  void queue_after_count(const FramePlan& f, std::uint64_t pairs) {
    cudaEvent_t* events = events_[event_set_];
    const gm::CameraParams& cam = *f.cam;
    const RenderOptions& options = *f.options;
    const bool dense_tiles_first = dense_order(options, f.baseline, f.tiles);
    if (dense_tiles_first && emitted_counts_frame_)
      throw Error("cuda renderer: internal error, the bin order changed between emission and sort");
    if (dense_tiles_first) {
      tile_order_.reserve(std::max<std::uint64_t>(f.bins, 1) * sizeof(std::uint32_t), "bin order");
      if (!bin_sort_frame_)  // the bin sort's counting pass orders the bins without it
        tile_places_.reserve(std::max<std::uint64_t>(f.bins, 1) * sizeof(std::uint32_t), "bin places");
    }
    const cuda::FrameBuffers b = frame_buffers();
    if (!f.fused) {
      check_cuda(cudaEventRecord(events[kEmitBegin], stream_), "event record");
      cuda::launch_duplicate(device_scene_.count, b, cam, f.args->exact_tile_test, stream_);
      check_cuda(cudaEventRecord(events[kEmitted], stream_), "event record");
    }

    const int tile_bits = std::max(bits_for(f.bins), 1);
    int end_bit = 64;
    if (key_format_.depth_bits > 0) end_bit = tile_bits + key_format_.depth_bits;
    else if (f.baseline || options.minimal_sort_bits) end_bit = std::min(64, 32 + tile_bits);
    // An event costs the GPU about a microsecond between kernels: stages that meet with
    // nothing between them share one.
    sort_follows_project_[event_set_] = f.sort_follows_project;
    if (!sort_follows_project_[event_set_]) check_cuda(cudaEventRecord(events[kSortBegin], stream_), "event record");
    // The bin sort writes the bin ranges and tile lists itself (its stage time includes them).
    // Where its bin blocks overlap the blend, nothing may come between them in the stream: the
    // sort stage is then the counting and scatter passes, and the bin blocks' time is in the
    // blend's (the two run together and cannot be timed apart).
    int which = 0;
    std::uint32_t* order = dense_tiles_first ? b.tile_order : nullptr;
    const bool overlap = bin_sort_frame_ && bin_overlap_ && !f.baseline;
    std::uint32_t* ready = nullptr;
    sort_in_blend_[event_set_] = overlap;
    if (overlap) {
      ready = bin_ready_.as<std::uint32_t>();
      if (++bin_frame_tag_ == 0) ++bin_frame_tag_;  // 0 is a fresh buffer's
    }
    if (bin_sort_frame_) {
      cuda::launch_bin_pairs(b, order, stream_);
      if (!overlap)
        cuda::launch_bin_blocks(cam.tiles_x, cam.tiles_y, b, bin_sort_shared_pairs_, order, nullptr, 0, stream_);
      zeroed_fill_bins_ = f.bins;
    } else {
      which = cuda::launch_sort(pairs, end_bit, b, stream_);
    }
    check_cuda(cudaEventRecord(events[kSorted], stream_), "event record");
    if (!bin_sort_frame_) {
      cuda::launch_ranges(pairs, f.bins, b, which, stream_);
      if (f.binned) cuda::launch_tile_lists(pairs, cam.tiles_x, cam.tiles_y, b, which, stream_);
    }
    if (dense_tiles_first && !bin_sort_frame_) cuda::launch_tile_order(f.bins, b, stream_);  // the bin sort did
    ranges_in_sort_[event_set_] = bin_sort_frame_;  // the bin sort writes the ranges and lists itself
    if (!ranges_in_sort_[event_set_]) check_cuda(cudaEventRecord(events[kRanged], stream_), "event record");
    if (overlap)
      cuda::launch_bin_blocks(cam.tiles_x, cam.tiles_y, b, bin_sort_shared_pairs_, order, ready, bin_frame_tag_, stream_);

    cuda::BlendArgs blend{};
    blend.width = cam.width;
    blend.height = cam.height;
    blend.tiles_x = cam.tiles_x;
    blend.tiles_y = cam.tiles_y;
    for (int k = 0; k < 3; ++k) blend.background[k] = options.background[k];
    blend.kernel = f.baseline || options.collect_pixel_planes ? cuda::BlendKernel::per_pixel
                              : (options.pipelined_blend ? cuda::BlendKernel::warp_tile_pipelined
                                                         : cuda::BlendKernel::warp_tile);
    blend.exp2_alpha = f.args->exp2_alpha;
    blend.half_blend = options.fp16_blend;
    blend.region_width = region_width_;
    blend.stop_bound = stop_bound_;
    blend.bins = bins_;
    blend.values = b.values[which];
    blend.tile_ranges = b.tile_ranges;
    blend.tile_lists = b.tile_lists;
    for (int k = 0; k < 2; ++k) blend.tile_values[k] = b.tile_values[k];
    blend.tile_order = order;
    blend.bins_ready = ready;
    blend.frame_tag = overlap ? bin_frame_tag_ : 0u;
    blend.gaussians = b.blend;
    blend.image_rgb = f.float_image ? b.image_rgb : nullptr;
    blend.surface = f.surface;
    if (options.collect_pixel_planes) {
      pixel_depth_.reserve(f.pixels * sizeof(float), "depth plane");
      pixel_blended_.reserve(f.pixels * sizeof(std::uint32_t), "blended-count plane");
      blend.pixel_depth = pixel_depth_.as<float>();
      blend.pixel_blended = pixel_blended_.as<std::uint32_t>();
    }
    cuda::launch_blend(blend, stream_);
    check_cuda(cudaEventRecord(events[kBlended], stream_), "event record");
    // The fullest tile and the tile pairs, for the statistics (after the last timed event:
    // not a stage's cost).
    cuda::launch_tile_stats(f.tiles, b, stream_);
    check_cuda(cudaMemcpyAsync(&readback_->tile_totals[event_set_], &b.counters->tile_totals, sizeof(cuda::TileTotals),
                               cudaMemcpyDeviceToHost, stream_),
               "tile statistics read back");
    if (f.out) {
      Image* out = f.out;
      if (out->width != f.camera->width || out->height != f.camera->height) out->resize(f.camera->width, f.camera->height);
      check_cuda(cudaMemcpyAsync(out->rgb.data(), b.image_rgb, f.pixels * 3 * sizeof(float), cudaMemcpyDeviceToHost,
                                 stream_),
                 "image download");
    } else if (f.device_out) {
      check_cuda(cudaMemcpyAsync(f.device_out, b.image_rgb, f.pixels * 3 * sizeof(float), cudaMemcpyDeviceToDevice,
                                 stream_),
                 "image copy to the caller's device buffer");
    }
  }

  // The debug planes come from the per-pixel kernel, which reads the float alpha form of
  // per-tile lists: a frame that collects them keeps its geometry switches (the same pairs but
  // for the bins) and leaves out the exp2 form, the half blend and the macro bins.
  static RenderOptions per_pixel_options(const RenderOptions& options) {
    RenderOptions o = options;
    o.exp2_alpha = o.fp16_blend = o.macro_bins = false;
    return o;
  }

  // Renders one frame: its path planned, its buffers sized, its preprocess queued and its
  // counts read back, then the rest of its work queued; its statistics where asked for.
  void run_frame(const Camera& camera, const RenderOptions& asked, FrameTarget target, Image* out,
                 std::uint64_t surface, FrameStats* stats_out, void* device_out = nullptr) {
    const RenderOptions options = asked.collect_pixel_planes ? per_pixel_options(asked) : asked;
    if (!scene_ && !pooled_) throw Error("cuda renderer: no scene set");
    if (camera.width < 1 || camera.height < 1) throw Error("cuda renderer: image size must be at least 1x1");
    if (surface) check_surface(surface, camera);
    if (pooled_) check_pooled_options(options);
    // A frame in another precision re-packs the scene from its host copy first.
    else if (options.fp16_sh != device_scene_.sh_half || options.fp16_shape != device_scene_.shape_half)
      upload_scene(scene_, options.fp16_sh, options.fp16_shape);
    const FramePath path = plan_frame_path(camera, options, target);
    size_frame_buffers(path, options);
    const cuda::PreprocessArgs args = preprocess_args(path, options);
    // Event sets alternate between frames, so that a surface frame's statistics can report
    // the previous frame's stage times without waiting for its own.
    const int previous_set = event_set_;
    const bool previous_complete = last_frame_complete_;  // all its events recorded
    last_frame_complete_ = false;
    event_set_ ^= 1;
    frame_tiles_[event_set_] = path.tiles;
    // The bin sort reads the pair count on the device, so a frame of fused emission queues
    // the rest of its work before the host waits for the count: the GPU then runs on instead
    // of idling while the host reads the count and launches the sort (8-16 us a frame).
    // Nothing it queues waits for the last frame's end (dense_order_pays reads a finished
    // frame's statistics), so frames queued back to back follow each other without a gap.
    const bool queue_before_count = bin_sort_frame_ && path.fused;
    // Such a frame that goes to the host (whose end the host waits for anyway) reads its counts
    // back at its end, after the blend: a copy between preprocess and sort kept the GPU idle
    // for 15-25 us on the H200 machine. A surface frame reads them back at once, so that
    // the host can go on while the GPU blends.
    const bool count_at_end = queue_before_count && (out || device_out);
    separate_emit_[event_set_] = !path.fused;
    const FramePlan frame{&camera,    &path.cam,  &options,    &args,         out,        device_out, surface,     path.float_image,
                          path.tiles, path.bins, path.pixels, path.baseline, path.fused, path.binned, count_at_end};
    const std::uint64_t pairs =
        queue_preprocess_and_read_back(frame, queue_before_count, count_at_end, previous_set, previous_complete);
    if (!queue_before_count) queue_after_count(frame, pairs);
    finish_frame(frame, pairs);
    if (stats_out) *stats_out = frame_stats(frame, pairs, previous_set, previous_complete);
  }

  // What plan_frame_path decides of a frame before any of its work is queued.
  struct FramePath {
    gm::CameraParams cam;
    std::uint64_t tiles, pixels, bins;
    std::size_t n;  // the scene's Gaussians
    bool baseline, fused, binned;
    bool float_image;  // the blend writes the device image (a host or a queued frame)
  };

  // The frame's path: its tiles and bins (macro bins where the scene allows them), its key
  // format (compact keys over the depths the view can hold) and its sort (per bin where that
  // pays, bin_sort_frame_).
  FramePath plan_frame_path(const Camera& camera, const RenderOptions& options, FrameTarget target) {
    const gm::CameraParams cam = make_camera_params(camera);
    // The emission kernels keep a box's tile range in 16 bits.
    if (cam.tiles_x > 0xffff || cam.tiles_y > 0xffff)
      throw Error("cuda renderer: an image side of more than " + std::to_string(0xffff * gm::kTileSize) +
                  " pixels is not supported");
    const std::uint64_t tiles = static_cast<std::uint64_t>(cam.tiles_x) * cam.tiles_y;
    const std::uint64_t pixels = static_cast<std::uint64_t>(cam.width) * cam.height;
    const std::size_t n = device_scene_.count;
    const bool baseline = options.is_baseline();
    const bool fused = !baseline && options.fused_emit;
    // Macro bins need the record in a pair value's low 28 bits (records are below the scene's size).
    const bool binned = !baseline && options.macro_bins && n <= cuda::kRecordMask;
    bins_.shift = binned ? cuda::kMacroBinShift : 0;
    bins_.x = (cam.tiles_x + (1 << bins_.shift) - 1) >> bins_.shift;
    bins_.y = (cam.tiles_y + (1 << bins_.shift) - 1) >> bins_.shift;
    const std::uint64_t bins = static_cast<std::uint64_t>(bins_.x) * bins_.y;
    // 3DGS sorts 64-bit keys over 32 + bits(tiles); flash packs tile and depth bin in 32 bits;
    // with the switch off, all 64 bits are sorted, to show what the switch buys.
    const bool compact_keys = !baseline && options.minimal_sort_bits;
    if (compact_keys) {
      // A centre inside the view cone at distance d from the camera has depth in
      // [d cos(half-diagonal angle), d]; the bounding sphere bounds d. Centres just outside
      // the cone (a Gaussian reaching into the frame) get clamped bins; the order stays exact
      // either way, only the ranges pass has more ties to order.
      const double distance = distance_to_bounds_centre(cam);
      const double tan_x = std::max(cam.cx, cam.width - cam.cx) / cam.fx;
      const double tan_y = std::max(cam.cy, cam.height - cam.cy) / cam.fy;
      const double cos_half_diagonal = 1.0 / std::sqrt(1.0 + tan_x * tan_x + tan_y * tan_y);
      key_format_ = compact_key_format(bins, (distance - bounds_radius_) * cos_half_diagonal,
                                       distance + bounds_radius_, sort_key_bits_);
    } else {
      key_format_ = cuda::KeyFormat{};
    }

    // The bin sort needs the depth bins of compact keys (depth_bits > 0) in 32-bit keys.
    bin_sort_frame_ = binned && key_format_.depth_bits > 0 && bin_sort_pays(bins);
    return FramePath{cam, tiles, pixels, bins, n, baseline, fused, binned, target != FrameTarget::surface};
  }

  // The buffers the frame's path needs, grown (never shrunk) to its bins, tiles, image and
  // records.
  void size_frame_buffers(const FramePath& path, const RenderOptions& options) {
    const std::uint64_t tiles = path.tiles, bins = path.bins, pixels = path.pixels;
    const std::size_t n = path.n;
    const bool baseline = path.baseline, fused = path.fused, binned = path.binned;
    if (bin_sort_frame_) {
      const std::size_t fill_bytes = bin_fill_.bytes();
      // Each bin's fill, then its count when emission counts (FrameBuffers::emitted_bin_counts).
      bin_fill_.reserve(std::max<std::uint64_t>(2 * bins, 1) * sizeof(std::uint32_t), "bin fill");
      if (bin_fill_.bytes() != fill_bytes) zeroed_fill_bins_ = 0;
      if (bin_overlap_) {  // flags of earlier frames' tags: a new buffer starts with none
        const std::size_t ready_bytes = bin_ready_.bytes();
        bin_ready_.reserve(std::max<std::uint64_t>(bins, 1) * sizeof(std::uint32_t), "bin ready flags");
        if (bin_ready_.bytes() != ready_bytes)
          check_cuda(cudaMemsetAsync(bin_ready_.as<void>(), 0, bin_ready_.bytes(), stream_), "bin flag reset");
      }
    }
    ranges_.reserve(std::max<std::uint64_t>(bins, 1) * sizeof(uint2), "bin ranges");
    if (binned) {
      tile_lists_.reserve(std::max<std::uint64_t>(tiles, 1) * sizeof(uint2), "tile lists");
      dense_bins_.reserve(std::max<std::uint64_t>(bins, 1) * sizeof(std::uint32_t), "dense bin list");
    }
    if (path.float_image) image_.reserve(pixels * 3 * sizeof(float), "frame image");
    // Fused emission keeps a blend record per projected Gaussian (FrameBuffers::blend), the
    // separate path one per Gaussian.
    compact_records_ = fused;
    if (fused) grow_records(std::min<std::uint64_t>(n, initial_records_), false);
    else blend_.reserve(std::max<std::size_t>(n, 1) * sizeof(cuda::BlendGaussian), "per-Gaussian blend data");
    if (fused && !baseline && options.warp_cooperative_emit) {
      // The list of deferred Gaussians, sized to the projected ones, and two work items each
      // (most boxes are one); a frame with more emits the rest in the preprocess kernel.
      const std::size_t projected = record_capacity();
      const std::size_t deferred = std::min<std::size_t>(std::max<std::size_t>(n, 1), 12288 + projected * 3 / 16);
      deferred_footprints_.reserve(deferred * sizeof(gm::Footprint), "deferred-Gaussian footprints");
      deferred_records_.reserve(deferred * sizeof(std::uint32_t), "deferred-Gaussian records");
      deferred_hits_.reserve(deferred * sizeof(std::uint32_t), "deferred-Gaussian hits");
      deferred_items_.reserve(2 * deferred * sizeof(uint2), "deferred work items");
    }
    if (!fused) {
      footprints_.reserve(std::max<std::size_t>(n, 1) * sizeof(gm::Footprint), "per-Gaussian footprints");
      pair_counts_.reserve(std::max<std::size_t>(n, 1) * sizeof(std::uint32_t), "per-Gaussian pair counts");
      pair_offsets_.reserve(std::max<std::size_t>(n, 1) * sizeof(std::uint32_t), "per-Gaussian pair offsets");
    }
    grow_cub_temp();  // allocates only when the scene or pairs grew
  }

  // The preprocess kernel's arguments; the chunk list sized where preprocess walks one.
  cuda::PreprocessArgs preprocess_args(const FramePath& path, const RenderOptions& options) {
    const gm::CameraParams& cam = path.cam;
    const std::size_t n = path.n;
    const bool baseline = path.baseline, fused = path.fused;
    cuda::PreprocessArgs args{};
    args.camera = cam;
    args.geometry = make_geometry_params(options);
    args.exact_tile_test = options.uses_exact_tile_test();
    args.warp_cooperative = !baseline && options.warp_cooperative_emit;
    args.exp2_alpha = !baseline && options.exp2_alpha;
    args.sh_degree = std::max(0, std::min(device_scene_.sh_degree, options.sh_degree_cap));
    args.large_box_tiles = large_box_tiles_;
    args.item_chunks = item_chunks_;
    // A pooled scene is always drawn through the chunk list: it lists the drawn pages.
    args.chunk_cull = !baseline && (pooled_ || chunk_cull_ == kAlways || (chunk_cull_ == kAuto && n >= kChunkCullMinGaussians));
    if (args.chunk_cull) args.chunk_frame = cuda::chunk_cull_frame(cam, args.geometry, max_opacity_);
    // Fused emission runs the chunk test as a pass of its own and preprocess over the chunks
    // it lists, so a chunk outside the view costs one thread rather than a block.
    list_chunks_ = args.chunk_cull && fused;
    if (list_chunks_)
      chunk_list_.reserve(
          std::max<std::size_t>((n + cuda::kChunkSize - 1) / cuda::kChunkSize, 1) * sizeof(std::uint32_t), "chunk list");
    return args;
  }

  // Queues project (+ fused emit), then the frame's one read back: the pair and record counts,
  // which it waits for; returns the pairs. Fused emission that overflowed wrote nothing past
  // the capacities; grow and run it again. A frame queued before its count
  // (queue_before_count) queues the rest of its work here too.
  std::uint64_t queue_preprocess_and_read_back(const FramePlan& frame, bool queue_before_count, bool count_at_end,
                                               int previous_set, bool previous_complete) {
    const RenderOptions& options = *frame.options;
    const cuda::PreprocessArgs& args = *frame.args;
    const std::uint64_t tiles = frame.tiles, bins = frame.bins;
    const std::size_t n = device_scene_.count;
    const bool baseline = frame.baseline, fused = frame.fused;
    cudaEvent_t* events = events_[event_set_];
    std::uint64_t pairs = 0;
    for (int attempt = 0;; ++attempt) {
      // Emission counts the pairs per bin where it pays, each preprocess block takes its own
      // chunk and the counting pass would not also order the bins.
      emitted_counts_frame_ = bin_sort_frame_ && fused && !list_chunks_ && emit_bin_counts_pays(bins) &&
                              !dense_order(options, baseline, tiles);
      if (bin_sort_frame_) {
        if (bins > zeroed_fill_bins_)
          check_cuda(cudaMemsetAsync(bin_fill_.as<void>(), 0, 2 * bins * sizeof(std::uint32_t), stream_),
                     "bin count reset");
        zeroed_fill_bins_ = 0;  // until the bin blocks are queued
      }
      const cuda::FrameBuffers b = frame_buffers();
      check_cuda(cudaMemsetAsync(b.counters, 0, sizeof(cuda::FrameCounters), stream_), "counter reset");
      check_cuda(cudaEventRecord(events[kBegin], stream_), "event record");
      cuda::launch_preprocess(device_scene_, b, args, fused, stream_);
      check_cuda(cudaEventRecord(events[kProjected], stream_), "event record");
      if (!fused) {
        cuda::launch_scan(n, b, stream_);
        check_cuda(cudaEventRecord(events[kScanned], stream_), "event record");
      }
      if (!count_at_end) read_back_counts(b, events[fused ? kProjected : kScanned]);
      if (queue_before_count) {
        queue_after_count(frame, 0);
        if (count_at_end) read_back_counts(b, nullptr);
      }
      check_cuda(cudaEventSynchronize(events[kCounted]), "preprocess");
      if (previous_complete) settle(previous_set);  // it ended before this frame began
      pairs = readback_->counters.pairs;
      if (pairs > static_cast<std::uint64_t>(INT32_MAX))
        throw Error("cuda renderer: the frame needs " + std::to_string(pairs) +
                    " Gaussian-tile pairs, more than the 2^31 the sort can take");
      const std::uint64_t records = readback_->counters.records;
      if (pairs <= pair_capacity_ && (!compact_records_ || records <= record_capacity())) break;
      // (A frame queued before its count blended nothing: its bin sort saw the overflow.)
      grow_pairs(pairs);
      if (compact_records_) grow_records(records, true);
      if (!fused) break;  // nothing was written yet
      if (attempt > 0) throw Error("cuda renderer: internal error, pair count changed between identical runs");
    }
    return pairs;
  }

  // What the next frames judge by (this frame's tiles, pairs and records; the deferred list
  // grown to what it wanted), and a frame for the host waited for.
  void finish_frame(const FramePlan& frame, std::uint64_t pairs) {
    const cuda::PreprocessArgs& args = *frame.args;
    const std::uint64_t tiles = frame.tiles;
    const bool fused = frame.fused, binned = frame.binned;
    if (args.warp_cooperative && fused)
      grow_deferred(readback_->counters.deferred, readback_->counters.deferred_items);
    last_tiles_ = tiles;
    last_bin_pairs_ = binned ? pairs : 0;
    last_records_ = compact_records_ ? readback_->counters.records : 0;
    last_frame_binned_ = binned;
    if (frame.waited()) {
      check_cuda(cudaStreamSynchronize(stream_), "frame");
      settle(event_set_);
    }
    last_frame_complete_ = true;
  }

  // The frame's counts, stage times and memory (a surface frame: the previous frame's times).
  FrameStats frame_stats(const FramePlan& frame, std::uint64_t pairs, int previous_set, bool previous_complete) {
    const gm::CameraParams& cam = *frame.cam;
    const RenderOptions& options = *frame.options;
    const std::size_t n = device_scene_.count;
    const bool binned = frame.binned;
    FrameStats stats;
    const cuda::FrameCounters& c = readback_->counters;
    stats.sorted_pairs = pairs;
    stats.tiles_x = cam.tiles_x;
    stats.tiles_y = cam.tiles_y;
    stats.gaussians = pooled_ ? pool_->drawn_gaussians() : n;  // a pool holds pages it does not draw
    stats.visible = c.by_reason[gm::kVisible];
    stats.culled_near = c.by_reason[gm::kCulledNear];
    stats.culled_offscreen = c.by_reason[gm::kCulledOffscreen];
    stats.culled_low_opacity = c.by_reason[gm::kCulledLowOpacity];
    stats.culled_degenerate = c.by_reason[gm::kCulledDegenerate];
    stats.culled_by_chunk = c.chunk_culled;
    // GPU time of each stage between events; host gaps (the pair-count wait) are not counted.
    // A surface frame is not waited for (the caller presents it while the GPU finishes): it
    // reports the previous frame's times, complete since this frame's pair-count wait.
    if (frame.waited() || !previous_complete) {
      check_cuda(cudaStreamSynchronize(stream_), "frame");
      stats.times = stage_times(event_set_);
      stats.max_tile_pairs = readback_->tile_totals[event_set_].max_tile_pairs;
      stats.kv_pairs = readback_->tile_totals[event_set_].tile_pairs;
    } else {
      stats.times = stage_times(previous_set);
      stats.max_tile_pairs = readback_->tile_totals[previous_set].max_tile_pairs;
      stats.kv_pairs = readback_->tile_totals[previous_set].tile_pairs;
    }
    // Tile keys count the tile pairs themselves; bins count them after the blend (above: this
    // frame's, or for a surface frame the previous one's, as the times).
    if (!binned) stats.kv_pairs = pairs;
    stats.device_memory_bytes = working_bytes_;
    stats.device_peak_bytes = peak_bytes_;
    stats.scene_device_bytes = scene_pos_.bytes() + scene_rot_.bytes() + scene_scale_.bytes() + scene_dc_.bytes() +
                               scene_rest_.bytes() + scene_chunks_.bytes() + scene_ids_.bytes() + pool_bytes_;
    if (options.collect_tile_counts) download_tile_counts(stats.tile_pair_counts);
    if (options.collect_pixel_planes) download_pixel_planes(cam.width, cam.height, stats);
    return stats;
  }

  int device_ = 0;
  std::string device_name_;
  // Declared before the buffers: destroyed after them.
  StreamHandle stream_handle_;
  StreamHandle copy_stream_handle_;  // the pair counts' read back (read_back_counts)
  EventHandle event_handles_[2][kEventCount];
  PinnedHandle pinned_;
  cudaStream_t stream_ = nullptr;  // stream_handle_'s
  cudaEvent_t events_[2][kEventCount] = {};  // event_handles_'
  HostReadback* readback_ = nullptr;         // in pinned_
  int event_set_ = 0;
  bool separate_emit_[2] = {false, false};  // per event set: its frame recorded the emit events
  bool last_frame_complete_ = false;  // the last frame recorded all its events
  std::uint64_t frame_tiles_[2] = {0, 0};  // per event set: its frame's tiles
  // The tile statistics of the latest frame known to have finished (dense_order_pays).
  struct SettledFrame {
    bool known = false;
    std::uint64_t tiles = 0, tile_pairs = 0, fullest_tile = 0;
  } settled_;
  bool list_chunks_ = false;          // this frame's preprocess walks a chunk list (FrameBuffers::chunk_list)
  bool compact_records_ = false;      // this frame keeps a blend record per projected Gaussian
  std::shared_ptr<const Scene> scene_;
  cuda::DeviceScene device_scene_;
  std::uint64_t working_bytes_ = 0, peak_bytes_ = 0;
  std::uint64_t pair_capacity_ = 0;
  std::size_t last_tiles_ = 0;
  int region_width_ = 0;  // the tuning's (constructor), as the knobs below
  bool stop_bound_ = true;
  std::size_t cub_sized_for_gaussians_ = ~std::size_t{0};  // sizes cub_temp_ was last checked for
  std::uint64_t cub_sized_for_pairs_ = 0;
  int large_box_tiles_ = 0;
  int item_chunks_ = 0;
  // Chunk culling pays off in large scenes (the 3.5M tiled scene's project stage fell 9%, the
  // 100M one's 2.8x on an H200) and costs a test per 256 Gaussians that cannot pay off when
  // the whole of a small scene is in view (pc_biker's and pc_playbot's orbit views).
  static constexpr std::size_t kChunkCullMinGaussians = std::size_t{1} << 20;
  // Spatial order pays in scenes of a few waves of preprocess blocks and more (pc_playbot in
  // random order: frames 8% / 6% shorter at 1080p / 4K; 10M Gaussians: 15% / 10%, the chunk
  // cull working again). Below, it gathers a small grid's heavy Gaussians into a few blocks
  // (v3dg_donut, 45k: 3% / 2% longer on the H200, docs/PERFORMANCE.md).
  static constexpr std::size_t kSpatialOrderMinGaussians = std::size_t{1} << 18;
  // Compact records a scene's first frame starts with: a view of more Gaussians grows them once
  // and runs again.
  std::uint64_t initial_records_ = 0;
  int sort_key_bits_ = 0;  // of a compact key (compact_key_format)
  unsigned bin_sort_shared_pairs_ = 0;
  enum Mode { kAuto, kAlways, kNever };
  static Mode mode_of(long long knob) { return knob == kTuningAuto ? kAuto : (knob != 0 ? kAlways : kNever); }
  Mode chunk_cull_ = kAuto;
  Mode spatial_order_ = kAuto;  // the scene's device layout in spatial order (upload_scene)
  // Where the last upload's wall-clock seconds went, printed by set_scene where asked for.
  struct UploadTimes {
    double order = 0, allocation = 0, packing = 0, waiting = 0;
  };
  UploadTimes upload_times_;
  bool print_upload_times_ = false;
  Mode dense_tiles_mode_ = kAuto;
  Mode bin_sort_ = kAuto;        // binned frames with compact keys sort per bin (launch_bin_pairs, launch_bin_blocks)
  bool bin_sort_frame_ = false;  // this frame does
  bool bin_overlap_ = false;     // bin-sort frames blend beside the bin blocks (launch_bin_blocks)
  std::uint32_t bin_frame_tag_ = 0;  // the last such frame's tag in bin_ready_
  bool sort_in_blend_[2] = {false, false};  // per event set: the bin blocks ran beside the blend
  bool sort_follows_project_[2] = {false, false};  // per event set: no kSortBegin, the sort began at kProjected
  bool ranges_in_sort_[2] = {false, false};        // per event set: no kRanged, no ranges stage
  // bin_fill_'s fills and counts of the first zeroed_fill_bins_ bins are zero (the bin blocks
  // zero them for the next frame; a new allocation has none).
  std::uint64_t zeroed_fill_bins_ = 0;
  Mode emit_bin_counts_ = kAuto;       // bin-sort frames count pairs per bin in emission
  bool emitted_counts_frame_ = false;  // this frame does (FrameBuffers::emitted_bin_counts)
  std::uint64_t last_bin_pairs_ = 0;  // the last frame's pairs if it was binned
  static constexpr std::uint64_t kBinSortMostPairsPerBin = 512;
  static constexpr std::uint64_t kBinSortAnyCoverageBins = 4096;     // 1080p-class frames
  static constexpr std::uint64_t kBinSortMostPairsPerGaussian = 32;
  std::uint64_t last_records_ = 0;  // the last frame's blend records (visible Gaussians), 0 if not counted
  std::uint64_t blend_resident_blocks_ = 1;  // warp-blend blocks the device runs at once
  cuda::KeyFormat key_format_;           // this frame's
  cuda::BinGrid bins_;                   // this frame's
  bool last_frame_binned_ = false;       // the last frame's tile counts are in tile_lists_
  double bounds_centre_[3] = {0, 0, 0};  // sphere around the scene's Gaussian centres
  double bounds_radius_ = 0;
  float max_opacity_ = 1.0f;             // of the scene (sets the flash extent's largest threshold)
  // Scene (not counted as working memory).
  DeviceBuffer scene_pos_, scene_rot_, scene_scale_, scene_dc_, scene_rest_, scene_chunks_, scene_ids_;
  // A streamed scene's parts (set_scene_parts) instead of the scene above while pooled_.
  std::unique_ptr<cuda::ScenePool> pool_;
  bool pooled_ = false;
  std::uint64_t pool_bytes_ = 0, pool_peak_bytes_ = 0;
  // Working memory.
  DeviceBuffer counters_, blend_, record_ids_, footprints_, pair_counts_, pair_offsets_, keys_[2], values_[2], ranges_, tile_lists_, bin_fill_,
      bin_ready_, dense_bins_, tile_order_, tile_places_, chunk_list_, image_,
      cub_temp_, deferred_footprints_, deferred_records_, deferred_hits_, deferred_items_;
  DeviceBuffer pixel_depth_, pixel_blended_;  // RenderOptions::collect_pixel_planes
};

}  // namespace

std::unique_ptr<CudaRenderer> make_cuda_renderer(const BackendTuning& tuning) {
  return std::make_unique<CudaRendererImpl>(tuning);
}

}  // namespace flashgs
