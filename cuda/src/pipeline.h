// Internal to the CUDA backend: the device-resident scene, the per-frame buffers and the
// launch functions of each stage (one .cu per stage), shared by the host class and kernels.
#pragma once

#include <cuda_runtime_api.h>
#include <vector_types.h>

#include <cstddef>
#include <cstdint>

#include "flashgs/gaussian_math.h"

namespace flashgs {
namespace cuda {

constexpr int kWarp = 32;

// Preprocess takes the Gaussians in chunks of this many (one block each) and skips the
// projection of a chunk whose bounds lie outside the view (chunk_cull.cuh).
constexpr int kChunkSize = 256;

// The bounds of one chunk (kChunkSize consecutive Gaussians). Every view-space centre of the chunk lies within `radius` of the view of (cx, cy, cz)
// (a rotation keeps distances). cullable = 0 when a Gaussian could not be bounded: a
// non-finite or astronomically large value, or a quaternion that is not a unit one (its
// matrix would not be a rotation, and the footprint bound assumes one).
struct ChunkBound {
  float cx, cy, cz, radius;
  float max_scale;    // largest |scale| of the chunk
  float min_opacity;  // smallest opacity: none is culled for low opacity when it is >= tau
  unsigned cullable;
  unsigned members;   // Gaussians in the chunk (kChunkSize but for the last)
};

// What the chunk test says of a chunk this frame.
enum ChunkVerdict : int {
  kChunkProject = 0,     // may reach the image: every Gaussian is projected
  kChunkClassify = 1,    // outside the view: each Gaussian's reason read from its centre and opacity
  kChunkAllNear = 2,     // every centre behind the near plane: no Gaussian is read
  kChunkAllOffscreen = 3 // in front, outside, none below tau: no Gaussian is read
};

// The per-frame constants of the chunk test (chunk_verdict), from chunk_cull_frame().
// Proof that a chunk passing it has no Gaussian on the image: a flash footprint's half-width
// is at most s sqrt(lambda_max + 0.3 + 0.32) + 1 pixels (dilation, spread floor, ceil) with
// s^2 = max(9, 2 ln(o_max / tau)) the largest threshold, and lambda_max <= (K sigma / z)^2
// for K >= ||J||_F over the clamped frustum directions (1% more for quaternions within 1e-3
// of unit norm). So the box misses the right edge when fx x - (16 tiles_x + pad - cx) z >
// s K sigma (z > 0), likewise for the other edges: n.v > reach with n an edge normal below.
// Over a ball of centres the left side is smallest at its centre minus |n| radius. The pad
// (2 pixels more) and the slack of the device test cover float rounding in the projection.
struct ChunkCullFrame {
  float edge_normal[4][3];     // view space: right, left, bottom, top edges, pointing out
  float edge_normal_length[4];
  float reach_per_sigma;       // s K
  float jacobian_bound;        // K
};
// The constants for camera `cam` and flash geometry `geo`; `max_opacity` of the scene.
ChunkCullFrame chunk_cull_frame(const gm::CameraParams& cam, const gm::GeometryParams& geo, float max_opacity);

// The scene on the device, in a compact layout sized to its SH degree: 56 bytes per Gaussian
// for degree 0 (40 under RenderOptions::fp16_shape), plus 48/96/192 bytes of higher bands for
// degree 1/2/3 (24/48/96 bytes as halves under RenderOptions::fp16_sh). Read a Gaussian's
// shape through load_shape (scene_access.cuh), which knows both layouts.
struct DeviceScene {
  std::size_t count = 0;
  int sh_degree = 0;
  int rest_stride_vec4 = 0;           // groups of 4 higher-band SH coefficients per Gaussian (padded)
  bool sh_half = false;               // fp16_sh: sh_rest_half instead of sh_rest, DC rounded to halves
  bool shape_half = false;            // fp16_shape: position_dc_r and shape_record instead of the next three
  float4* position_opacity = nullptr;  // [count] world x, y, z; opacity in [0, 1]
  float4* rotation = nullptr;          // [count] unit quaternion w, x, y, z
  float4* scale_dc_r = nullptr;        // [count] linear scale x, y, z; SH DC red
  float4* position_dc_r = nullptr;     // [count] world x, y, z; SH DC red
  uint4* shape_record = nullptr;       // [count] halves: quaternion w, x, y, z; scale x, y, z; opacity
  float2* dc_gb = nullptr;             // [count] SH DC green, blue
  float4* sh_rest = nullptr;           // [count][rest_stride_vec4] bands 1.., [k][channel], zero padded
  uint2* sh_rest_half = nullptr;       // the same as IEEE halves, 4 per uint2 (lowest bits first)
  ChunkBound* chunks = nullptr;        // [ceil(count / kChunkSize)]
  // [count] the scene index of device Gaussian i, where the upload put them in spatial order
  // (flashgs/spatial_order.h); null: i. Pairs of equal depth blend in scene index order.
  const std::uint32_t* scene_ids = nullptr;
  // A pooled scene (ScenePool, a streamed cut): chunks are pages of the pool, partly filled
  // (ChunkBound::members, the first lanes), and only the draw_chunk_count chunks listed in
  // draw_chunks are drawn, through the chunk list (launch_chunk_list). Null: every chunk.
  const std::uint32_t* draw_chunks = nullptr;
  std::uint32_t draw_chunk_count = 0;
};

// Gaussians of chunk `chunk` (of a pooled scene: its page's members).
__host__ __device__ inline unsigned chunk_members(const DeviceScene& scene, const ChunkBound* bounds, std::size_t chunk) {
  if (scene.draw_chunks) return bounds[chunk].members;
  const std::size_t first = chunk * kChunkSize;
  return static_cast<unsigned>(scene.count - first < kChunkSize ? scene.count - first : kChunkSize);
}

// What the blend stage reads per Gaussian (48 bytes, three 16-byte loads): the whitened
// footprint (gm::Footprint::whiten, q = (w0 dx + w1 dy)^2 + (w2 dx + w3 dy)^2, accurate far
// along needles where the conic form cancels). In exp2 mode w is pre-scaled by
// sqrt(log2(e) / 2) and the opacity is stored as log2(o), so alpha = exp2(log2 o - q') with
// q' = u'^2 + v'^2; otherwise it is the CPU's raw whitened rows and opacity.
struct alignas(16) BlendGaussian {
  float mean_x, mean_y, w0, w1;
  float w2, w3, opacity, red;
  float green, blue, reach_y, depth;  // reach_y: |dy| beyond which alpha < 1/255 for sure;
                                       // depth: view-space z, for the ranges pass's tie order
};

// How a pair's sort key is packed. depth_bits == 0: 64 bits, tile << 32 | the depth's float
// bits (3DGS). Otherwise 32 bits, tile << depth_bits | a depth bin: the float's exponent
// (from exponent_base, the near plane's) and its top mantissa_bits, clamped to depth_bits.
// Bins are monotonic in depth, so sorting them orders every pair but those of one tile
// sharing a bin, which the ranges pass orders by exact depth: half the key bytes and two
// fewer radix passes than the 64-bit key, with the same final order.
struct KeyFormat {
  int depth_bits = 0;
  int mantissa_bits = 0;
  std::uint32_t exponent_base = 0;
};

// What the pairs are keyed by: bins of 2^shift x 2^shift tiles (RenderOptions::macro_bins:
// shift 1, 32x32 pixels), or tiles (shift 0). A Gaussian has one pair per bin it touches,
// whose value carries the bits of the bin's tiles it touches (kBinTileBitsShift and up), so
// the sort has about half the pairs while the blend still visits only the Gaussians of its
// tile, in the same order. Bins are row-major, x bins per row.
struct BinGrid {
  int shift = 0;
  int x = 0, y = 0;
};
constexpr int kMacroBinShift = 1;
constexpr int kBinTileBitsShift = 28;                                  // up to 4 tile bits
constexpr std::uint32_t kRecordMask = (1u << kBinTileBitsShift) - 1u;  // a binned value's record

// Tiles are ordered for the blend by the bit length of their pair count (launch_tile_order).
constexpr int kTileClasses = 33;

// Counters one frame accumulates on the device; copied to the host once per frame.
// The frame's tile statistics (launch_tile_stats, after the blend), read back in one copy.
struct TileTotals {
  unsigned long long tile_pairs;  // Gaussian-tile pairs (FrameCounters::pairs counts bins)
  unsigned int max_tile_pairs;    // pairs of the fullest tile
};

struct FrameCounters {
  unsigned long long pairs;        // Gaussian-tile pairs wanted (may exceed capacity)
  // Gaussians by gm::CullReason: kVisible counts those with at least one pair, and one whose
  // box met the image but whose ellipse missed every tile counts as kCulledOffscreen.
  unsigned int by_reason[gm::kCullReasonCount];
  TileTotals tile_totals;
  unsigned int deferred;           // Gaussians deferred to deferred_emit_kernel (may exceed capacity)
  unsigned long long deferred_items;  // their work items (may exceed item_capacity)
  unsigned long long chunk_culled; // Gaussians of chunks outside the view (classified, not projected)
  unsigned int listed_chunks;      // chunks the chunk cull left to preprocess (launch_chunk_list)
  unsigned int tiles_by_class[kTileClasses];  // tiles per pair-count class (launch_tile_order)
  unsigned int records;            // blend records wanted (compact records: may exceed capacity)
  unsigned int dense_bins;         // bins listed in FrameBuffers::dense_bins (launch_tile_lists)
  unsigned int bin_count_blocks;   // blocks of the bin sort's counting pass done (launch_bin_pairs)
};

// Gaussians whose emission the preprocess kernel leaves to a later kernel, so that their long
// tile loops are spread over the whole GPU instead of holding the warp that met them. Each
// box is cut into work items of up to PreprocessArgs::item_chunks chunks of 32 bins, which
// name their entry, so a warp's entries and items are reserved by an atomic each.
struct DeferredList {
  gm::Footprint* footprints = nullptr;  // [capacity]
  std::uint32_t* records = nullptr;     // [capacity] blend record (the pairs' value)
  std::uint32_t* hits = nullptr;        // [capacity] 1 once one of the entry's items emitted a pair
  uint2* items = nullptr;               // [item_capacity] entry, first chunk (kNoDeferredEntry: none)
  std::uint32_t capacity = 0;           // beyond either capacity, the preprocess kernel emits a box itself
  std::uint32_t item_capacity = 0;
};
constexpr std::uint32_t kNoDeferredEntry = 0xffffffffu;  // an item reserved for a box that did not fit

// Buffers of the frame pipeline; every size is a high-water mark (grown, never shrunk).
struct FrameBuffers {
  // Blend records. Fused emission keeps one per projected Gaussian: record_ids[r] is record
  // r's Gaussian (its scene index) and the pairs' values are record numbers, so the blend data
  // grows with what the frame sees, not with the scene. The separate path (record_ids null)
  // indexes them by device Gaussian, whose scene index is scene_ids' (DeviceScene). A frame
  // that wants more than record_capacity writes none past it; the host sees
  // FrameCounters::records, grows the buffers and runs the frame again.
  BlendGaussian* blend = nullptr;         // [record_capacity]
  std::uint32_t* record_ids = nullptr;    // [record_capacity], or null
  const std::uint32_t* scene_ids = nullptr;  // DeviceScene::scene_ids
  std::uint32_t record_capacity = 0;
  // Per Gaussian, separate-emission path only.
  gm::Footprint* footprints = nullptr;    // [gaussians]
  std::uint32_t* pair_counts = nullptr;   // [gaussians] pairs per Gaussian (separate path)
  std::uint32_t* pair_offsets = nullptr;  // [gaussians] inclusive prefix sum of pair_counts
  // Deferred by the fused kernel: boxes of more than large_box_tiles.
  DeferredList deferred;
  // Per pair: key (see KeyFormat; 32-bit keys use the front half, the tile part is a bin of
  // `bins`), value = blend record (and tile bits, see BinGrid); two of each for the sort.
  BinGrid bins;
  KeyFormat key_format;
  std::uint64_t* keys[2] = {nullptr, nullptr};    // [pair_capacity]
  std::uint32_t* values[2] = {nullptr, nullptr};  // [pair_capacity]
  std::uint64_t pair_capacity = 0;
  // Where emission writes the pair values: values[0], or for the bin sort the upper half of
  // keys[0] (as 32-bit words from pair_capacity), which leaves keys[1] and values[] free for
  // the pairs in bin order (launch_bin_pairs).
  std::uint32_t* pair_values = nullptr;
  // The bin sort's per-bin counts, then each bin's next free place (with emitted_bin_counts:
  // the places taken so far, from zero); the bin blocks leave it zeroed for the next frame.
  std::uint32_t* bin_fill = nullptr;  // [bins]
  // Bin-sort frames without the dense-first order or a chunk list (where it pays, see
  // CudaRenderer's emit_bin_counts_pays): the pairs per bin, counted by the emission
  // kernels (bin_tally.cuh), so that no counting pass runs and each scatter block finds the bins'
  // places itself (null: the counting pass counts). The bin blocks leave it zeroed.
  std::uint32_t* emitted_bin_counts = nullptr;  // [bins]
  // Per bin: [start, end) of its pairs in the sorted list.
  uint2* tile_ranges = nullptr;  // [tile_capacity]
  std::uint64_t tile_capacity = 0;
  // Binned frames: each tile's blend records, gathered once from its bin's values
  // (launch_tile_lists), so that the blend walks its own tile's list. They live in the key
  // buffers, which nothing reads after the ranges pass: bin [s, e)'s top tiles in
  // tile_values[0] from 2s and from 2s + (e - s), its bottom tiles likewise in tile_values[1].
  // tile_lists[tile] is [start, end) in the buffer of the tile's row parity.
  std::uint32_t* tile_values[2] = {nullptr, nullptr};  // keys[0], keys[1] as 2 x pair_capacity
  uint2* tile_lists = nullptr;                         // [tiles]
  std::uint32_t* dense_bins = nullptr;                 // [bins] bins too full for one warp to list
  // The blend's tile order, fullest first: tile_order[block] = tile; tile_places holds each
  // tile's class and place within it on the way (launch_tile_order).
  std::uint32_t* tile_order = nullptr;   // [tile_capacity]
  std::uint32_t* tile_places = nullptr;  // [tile_capacity]
  // Frame image, float RGB, row 0 at the top.
  float* image_rgb = nullptr;  // [pixel_capacity * 3]
  std::uint64_t pixel_capacity = 0;
  void* cub_temp = nullptr;  // sort and scan scratch
  std::size_t cub_temp_bytes = 0;
  FrameCounters* counters = nullptr;  // [1] device
  // Fused emission with the chunk cull: the chunks left to preprocess, chunk << 1 | 1 for
  // kChunkClassify, 0 for kChunkProject (null: preprocess tests every chunk itself).
  std::uint32_t* chunk_list = nullptr;  // [chunks]
};

struct PreprocessArgs {
  gm::CameraParams camera;
  gm::GeometryParams geometry;
  bool exact_tile_test;
  bool warp_cooperative;
  bool exp2_alpha;
  int sh_degree;        // bands evaluated (the scene's, capped)
  int large_box_tiles;  // boxes of more tiles go to the warp-cooperative path
  int item_chunks;      // 32-bin chunks per work item of a deferred box (1 to 32)
  bool chunk_cull;      // skip chunks outside the view (flash geometry only)
  ChunkCullFrame chunk_frame;
};

// Fills the scene's chunk bounds (once per scene).
void launch_chunk_bounds(const DeviceScene& scene, ChunkBound* bounds, cudaStream_t stream);
// The bounds of `count` pages of a pooled scene: pages[k] = (chunk, members) (a device array).
void launch_page_bounds(const DeviceScene& scene, const uint2* pages, unsigned count, cudaStream_t stream);
// The chunk test of every chunk, a thread each: chunks wholly culled are counted, the others
// listed in buffers.chunk_list for preprocess, which then runs a grid over the list only.
void launch_chunk_list(const DeviceScene& scene, const FrameBuffers& buffers, const PreprocessArgs& args,
                       cudaStream_t stream);

// project (+ fused key emission when `fused`).
void launch_preprocess(const DeviceScene& scene, const FrameBuffers& buffers, const PreprocessArgs& args,
                       bool fused, cudaStream_t stream);
// Separate emission (3DGS duplicateWithKeys): writes the keys of every Gaussian at its offset.
void launch_duplicate(std::size_t gaussians, const FrameBuffers& buffers, const gm::CameraParams& camera,
                      bool exact_tile_test, cudaStream_t stream);
// CUB scratch bytes needed by scan and sort for these sizes.
std::size_t cub_temp_bytes_needed(std::size_t gaussians, std::uint64_t pairs);
// Inclusive scan pair_counts -> pair_offsets.
void launch_scan(std::size_t gaussians, const FrameBuffers& buffers, cudaStream_t stream);
// Radix sort of `pairs` keys (in buffers.key_format) over bits [0, end_bit); returns which
// buffer (0/1) holds the result.
int launch_sort(std::uint64_t pairs, int end_bit, const FrameBuffers& buffers, cudaStream_t stream);
// The sort of binned frames with compact keys, and what the ranges pass and the tile lists do
// for the others. launch_bin_pairs queues a counting pass, which turns the pairs per bin into
// bin ranges (and with a non-null `order` lists the bins fullest first, what launch_tile_order
// writes on the other paths), and a scatter pass, which puts each pair in its bin (unstable;
// key and value side by side in keys[1]). launch_bin_blocks then queues a block per bin: it
// sorts the bin by key (in shared memory up to `shared_pairs` pairs, at most
// kBinSortSharedPairsMax; a larger bin in its place in values[], through keys[1]), puts runs of
// equal keys in the exact order and writes its tiles' lists. Block b takes bin order[b] (the
// blend's order) or, with a null `order`, bin b. Fills tile_ranges (per bin), tile_lists and
// tile_values from keys[0] and pair_values. The pair count is read on the device, so the host
// may queue this before it knows the count; a frame whose emission overflowed a capacity comes
// out empty. bin_fill (and emitted_bin_counts) must be zero for the frame's bins; the bin
// blocks leave them so. Where emission counted the pairs (emitted_bin_counts), no counting
// pass runs: the scatter pass finds the bins' places itself, and `order` must be null.
// With `ready`, each bin block stores `frame_tag` in ready[bin] once its lists are written and
// lets the next kernel start early (programmatic dependent launch, sm_90): a blend launched
// with BlendArgs::bins_ready then runs beside the bin blocks, each of its blocks waiting for
// its own bin, instead of after the last of them.
void launch_bin_pairs(const FrameBuffers& buffers, std::uint32_t* order, cudaStream_t stream);
void launch_bin_blocks(int tiles_x, int tiles_y, const FrameBuffers& buffers, unsigned shared_pairs,
                       const std::uint32_t* order, std::uint32_t* ready, std::uint32_t frame_tag, cudaStream_t stream);
// Bins a frame may have for the bin sort: its passes count pairs per bin in shared memory (48
// KB; a 4K frame has 8,160 bins).
constexpr unsigned kBinSortMaxBins = 12000;
// Pairs a bin may hold to be sorted in shared memory (the default of launch_bin_blocks' shared_pairs).
constexpr unsigned kBinSortSharedPairsMax = 1024;
// The ranges of the `bins` bins from the sorted keys in buffer `which`, and runs of equal keys
// put in (depth, Gaussian id) order.
void launch_ranges(std::uint64_t pairs, std::uint64_t bins, const FrameBuffers& buffers, int which,
                   cudaStream_t stream);
// tile_order from the bin ranges: bins by descending bit length of their pair count (the
// order inside a class is immaterial: bins blend independently), so the fullest bins start
// first instead of wherever they lie in the image.
void launch_tile_order(std::uint64_t bins, const FrameBuffers& buffers, cudaStream_t stream);
// Binned frames: FrameBuffers::tile_lists and tile_values from the bin ranges and the sorted
// values in buffer `which` (after launch_ranges).
void launch_tile_lists(std::uint64_t pairs, int tiles_x, int tiles_y, const FrameBuffers& buffers, int which,
                       cudaStream_t stream);
// FrameCounters::tile_totals from the tile ranges, or the tile lists of a
// binned frame (statistics: run outside the timed stages).
void launch_tile_stats(std::uint64_t tiles, const FrameBuffers& buffers, cudaStream_t stream);

enum class BlendKernel { per_pixel, warp_tile, warp_tile_pipelined };
struct BlendArgs {
  int width, height, tiles_x, tiles_y;
  float background[3];
  BlendKernel kernel;
  bool exp2_alpha;
  bool half_blend;               // warp blend (exp2): RenderOptions::fp16_blend
  int region_width;              // warp blend: a warp's region, 16 x 4 or 8 x 8 pixels
  bool stop_bound;               // warp blend (exp2): no stop rule where no pixel can stop
  const std::uint32_t* values;   // sorted pair values (blend records; tile bits when binned)
  BinGrid bins;                  // warp blend: what tile_ranges and tile_order index (per pixel: tiles)
  const uint2* tile_ranges;
  const uint2* tile_lists;                 // binned: each tile's list (FrameBuffers::tile_lists)
  const std::uint32_t* tile_values[2];     // binned: the lists' records
  const std::uint32_t* tile_order;  // warp blend: blocks blend bin tile_order[b] (null: bin b), a tile each
  // Warp blend of a bin-sort frame: launched early beside the bin blocks (launch_bin_blocks),
  // a block waits until bins_ready[its bin] holds frame_tag (null: the lists are all written).
  const std::uint32_t* bins_ready;
  std::uint32_t frame_tag;
  const BlendGaussian* gaussians;
  float* image_rgb;              // float output, or
  unsigned long long surface;    // RGBA8 surface (when image_rgb is null)
  // Per-pixel kernel: the debug planes (FrameStats::pixel_depth, pixel_blended), width x
  // height each, or null.
  float* pixel_depth;
  std::uint32_t* pixel_blended;
};
void launch_blend(const BlendArgs& args, cudaStream_t stream);
// Blocks of the default warp blend (8 x 8 regions, pipelined, exp2, float output) that the
// device runs at once: one wave.
std::uint64_t blend_resident_blocks();

// Throws flashgs::Error naming `what` when `status` is not cudaSuccess.
void check_cuda(cudaError_t status, const char* what);

}  // namespace cuda
}  // namespace flashgs
