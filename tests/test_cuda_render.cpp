// The CUDA backend against the CPU backend: identical pair counts, images within a bound,
// deterministic bytes, odd sizes, a camera inside the scene, surfaces and tile counts.
// Every test skips itself when no CUDA device is present (ctest label "gpu").
#include <gtest/gtest.h>

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numeric>
#include <random>

#include "flashgs/backend_tuning.h"
#include "flashgs/cuda_renderer.h"
#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/renderer.h"
#include "flashgs/stress_scenes.h"
#include "test_support.h"

namespace flashgs {
namespace {

#define FLASHGS_REQUIRE_CUDA()                                                  \
  do {                                                                          \
    std::string why;                                                            \
    if (!::flashgs::cuda_available(&why)) GTEST_SKIP() << "no CUDA device: " << why; \
  } while (0)

// Image bound CUDA vs CPU: the same operations in the same order (the kernels are built with
// -fmad=false) except exp: glibc's expf vs CUDA's (2 ulp) in the exact path, exp2 of a
// pre-scaled form in the exp2 path (a few ulp of alpha); test::kExpUlp* says what that allows.

struct Result {
  Image image;
  FrameStats stats;
};

Result render(Renderer& r, const Camera& camera, const RenderOptions& options) {
  Result out;
  r.render(camera, options, out.image, &out.stats);
  return out;
}

// Every switch alone off, and the anti-aliased kernels (both algorithms at gsplat's epsilon,
// flash at Mip-Splatting's).
std::vector<RenderOptions> all_configs() {
  std::vector<RenderOptions> configs = single_switch_configs();
  for (RenderOptions o : {RenderOptions::baseline(), RenderOptions{}}) {
    o.kernel = SplatKernel::antialiased();
    configs.push_back(o);
  }
  RenderOptions mip;
  mip.kernel = SplatKernel::antialiased(kMipSplattingEpsilon);
  configs.push_back(mip);
  return configs;
}

// The CPU ignores the switches it does not honour: its image for a config is that of the
// config with those switches at their defaults.
std::string cpu_key(const RenderOptions& o) { return o.seen_by(Backend::cpu).label(); }

// The same pairs, and every Gaussian culled for the same reason.
void expect_same_counts(const std::string& what, const FrameStats& a, const FrameStats& b) {
  EXPECT_EQ(b.kv_pairs, a.kv_pairs) << what;
  EXPECT_EQ(b.visible, a.visible) << what;
  EXPECT_EQ(b.culled_near, a.culled_near) << what;
  EXPECT_EQ(b.culled_offscreen, a.culled_offscreen) << what;
  EXPECT_EQ(b.culled_low_opacity, a.culled_low_opacity) << what;
  EXPECT_EQ(b.culled_degenerate, a.culled_degenerate) << what;
}

void expect_match(const std::string& what, const Result& cpu, const Result& gpu) {
  expect_same_counts(what, cpu.stats, gpu.stats);
  EXPECT_EQ(gpu.stats.max_tile_pairs, cpu.stats.max_tile_pairs) << what << " (without tile counts requested)";
  const ImageDifference d = compare_images(cpu.image, gpu.image);
  const double typical = test::fraction_over(cpu.image, gpu.image, test::kExpUlpTypicalAbs);
  std::printf("%-58s kv %10llu  max abs %.2e  PSNR %6.1f dB  >1e-3: %.2e\n", what.c_str(),
              static_cast<unsigned long long>(gpu.stats.kv_pairs), d.max_abs, d.psnr_db, typical);
  EXPECT_EQ(d.non_finite, 0u) << what;
  EXPECT_LE(d.max_abs, test::kExpUlpMaxAbs) << what;
  EXPECT_LE(typical, test::kExpUlpTypicalFraction) << what;
  if (d.max_abs > test::kExpUlpMaxAbs || typical > test::kExpUlpTypicalFraction) {
    std::string stem = what;
    std::replace_if(stem.begin(), stem.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '_');
    test::dump_images("cuda_" + stem, cpu.image, gpu.image);
  }
}

// Every config on the GPU against the CPU, for one scene and a set of cameras.
void compare_scene(const std::string& name, std::shared_ptr<const Scene> scene, const std::vector<Camera>& cameras) {
  auto cpu = make_cpu_renderer();
  auto gpu = make_cuda_renderer();
  cpu->set_scene(scene);
  gpu->set_scene(scene);
  for (const Camera& camera : cameras) {
    std::map<std::string, Result> cpu_results;
    for (const RenderOptions& o : all_configs()) {
      const std::string key = cpu_key(o);
      if (!cpu_results.count(key)) cpu_results[key] = render(*cpu, camera, o);
      const Result g = render(*gpu, camera, o);
      expect_match(name + " " + camera.name + " " + std::to_string(camera.width) + "x" +
                       std::to_string(camera.height) + " " + o.label(),
                   cpu_results[key], g);
    }
  }
}

TEST(CudaVsCpu, RealScenesEveryConfig) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const auto cameras = test::load_shared_cameras(name);
    std::vector<Camera> picked = {cameras[0], cameras[20], cameras[40 % cameras.size()]};
    compare_scene(name, test::load_shared_scene(name), picked);
  }
}

TEST(CudaVsCpu, DemoSceneEveryConfig) {
  FLASHGS_REQUIRE_CUDA();
  const auto cameras = test::load_demo_cameras();
  compare_scene("demo", test::load_demo_scene(), {cameras[0], cameras[5].resized(1001, 563)});
}

// A camera at the centre of the scene's bounds, looking along +z: Gaussians behind, beside
// and straddling the near plane, and huge screen-space footprints.
Camera inside_camera(const Scene& scene, int width, int height) {
  float lo[3], hi[3];
  scene_bounds(scene, lo, hi);
  const float centre[3] = {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  Camera c = Camera::from_pose(width, height, 0.6f * width, 0.6f * width, identity, centre);
  c.name = "inside";
  return c;
}

// The demo scene copied 9 times on a grid: seen from the demo cameras, most chunks of
// 256 Gaussians lie wholly outside the view (or behind the camera).
std::shared_ptr<const Scene> tiled_demo_scene() {
  static const auto scene = std::make_shared<const Scene>(tile_scene(*test::load_demo_scene(), 9));
  return scene;
}

std::vector<Camera> chunk_cull_cameras(const Scene& scene) {
  const auto cameras = test::load_demo_cameras();
  return {cameras[0].resized(1001, 563), cameras[7].resized(640, 360), inside_camera(scene, 803, 451)};
}

// The chunk cull only skips work: with it off (FLASHGS_CHUNK_CULL=0) every image byte and
// every count is the same, and with it on chunks are actually culled.
TEST(CudaChunkCull, ChangesNothingButTheWork) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = tiled_demo_scene();
  setenv("FLASHGS_CHUNK_CULL", "0", 1);
  auto plain = make_cuda_renderer();
  setenv("FLASHGS_CHUNK_CULL", "1", 1);  // the tiled demo is below the size that culls by default
  auto culling = make_cuda_renderer();
  unsetenv("FLASHGS_CHUNK_CULL");
  plain->set_scene(scene);
  culling->set_scene(scene);
  std::uint64_t culled = 0;
  for (const Camera& camera : chunk_cull_cameras(*scene))
    for (const RenderOptions& o : all_configs()) {
      const std::string what = camera.name + " " + o.label();
      const Result a = render(*plain, camera, o);
      const Result b = render(*culling, camera, o);
      EXPECT_TRUE(a.image.rgb == b.image.rgb) << what;
      expect_same_counts(what, a.stats, b.stats);
      EXPECT_EQ(a.stats.culled_by_chunk, 0u) << what;
      if (o.is_baseline()) {
        EXPECT_EQ(b.stats.culled_by_chunk, 0u) << what << ": the baseline culls per Gaussian";
      }
      culled += b.stats.culled_by_chunk;
    }
  EXPECT_GT(culled, 0u) << "no chunk was culled: the test does not exercise the cull";
}

// Fused emission keeps a blend record per projected Gaussian, not per Gaussian. A renderer
// that starts with room for one record must grow them on its first frame and run it again,
// with every byte and count as a renderer that never had to, in every config (the baseline
// keeps its per-Gaussian records).
TEST(CudaRecords, GrowingFromOneRecordChangesNoByte) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = tiled_demo_scene();
  setenv("FLASHGS_INITIAL_RECORDS", "1", 1);
  auto growing = make_cuda_renderer();
  unsetenv("FLASHGS_INITIAL_RECORDS");
  auto roomy = make_cuda_renderer();  // the scene is below the default first capacity
  std::vector<Camera> cameras = chunk_cull_cameras(*scene);
  cameras.push_back(test::load_demo_cameras()[2].resized(320, 180));  // fewer than the last frame
  for (int pass = 0; pass < 2; ++pass) {  // the second pass starts with grown buffers
    growing->set_scene(scene);
    roomy->set_scene(scene);
    for (const Camera& camera : cameras)
      for (const RenderOptions& o : all_configs()) {
        const std::string what = "pass " + std::to_string(pass) + " " + camera.name + " " + o.label();
        const Result a = render(*roomy, camera, o);
        const Result b = render(*growing, camera, o);
        EXPECT_TRUE(a.image.rgb == b.image.rgb) << what;
        expect_same_counts(what, a.stats, b.stats);
      }
  }
}

// A tuning set in code (make_cuda_renderer(tuning), as `flashgs bench --set` makes renderers)
// reaches the backend as the same values through the environment do: every byte and count
// the same, and chunks culled in a scene below the size that culls by default.
TEST(CudaTuning, SetInCodeAsThroughTheEnvironment) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = tiled_demo_scene();
  const std::vector<std::string> settings = {"chunk_cull=1", "initial_records=1", "bin_sort=1", "sort_key_bits=24",
                                             "dense_tiles_first=1", "blend_stop_bound=0"};
  BackendTuning tuning;
  for (const std::string& setting : settings) apply_tuning_setting(tuning, setting, "test");
  auto in_code = make_cuda_renderer(tuning);
  for (const std::string& setting : settings) {
    const TuningKnob& knob = *find_tuning_knob(setting.substr(0, setting.find('=')));
    setenv(tuning_variable(knob).c_str(), setting.substr(setting.find('=') + 1).c_str(), 1);
  }
  auto from_environment = make_cuda_renderer();
  for (const TuningKnob& knob : kTuningKnobs) unsetenv(tuning_variable(knob).c_str());
  in_code->set_scene(scene);
  from_environment->set_scene(scene);
  std::uint64_t culled = 0;
  for (const Camera& camera : chunk_cull_cameras(*scene))
    for (const RenderOptions& o : all_configs()) {
      const std::string what = camera.name + " " + o.label();
      const Result a = render(*from_environment, camera, o);
      const Result b = render(*in_code, camera, o);
      EXPECT_TRUE(a.image.rgb == b.image.rgb) << what;
      expect_same_counts(what, a.stats, b.stats);
      EXPECT_EQ(a.stats.culled_by_chunk, b.stats.culled_by_chunk) << what;
      culled += b.stats.culled_by_chunk;
    }
  EXPECT_GT(culled, 0u) << "no chunk was culled: chunk_cull=1 did not reach the backend";
}

// The flash path's working memory follows the projected Gaussians: the tiled scene's first
// camera sees a fraction of it, and a renderer that starts with room for one record needs
// less by at least half the records of the Gaussians it does not see.
TEST(CudaRecords, MemoryFollowsTheProjectedGaussians) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = tiled_demo_scene();
  const Camera camera = chunk_cull_cameras(*scene).front();
  setenv("FLASHGS_INITIAL_RECORDS", "1", 1);
  auto growing = make_cuda_renderer();
  unsetenv("FLASHGS_INITIAL_RECORDS");
  auto roomy = make_cuda_renderer();
  growing->set_scene(scene);
  roomy->set_scene(scene);
  const Result a = render(*roomy, camera, RenderOptions{});
  const Result b = render(*growing, camera, RenderOptions{});
  auto cpu = make_cpu_renderer();
  cpu->set_scene(scene);
  const Result c = render(*cpu, camera, RenderOptions{});
  expect_same_counts("first frame, roomy", c.stats, a.stats);
  expect_same_counts("first frame, growing", c.stats, b.stats);
  std::printf("visible %llu of %zu (roomy %llu, cpu %llu): working memory %.1f MB (room for every Gaussian: %.1f MB)\n",
              static_cast<unsigned long long>(b.stats.visible), scene->size(),
              static_cast<unsigned long long>(a.stats.visible), static_cast<unsigned long long>(c.stats.visible),
              b.stats.device_memory_bytes / 1e6, a.stats.device_memory_bytes / 1e6);
  ASSERT_LT(b.stats.visible * 2, scene->size()) << "the camera sees too much of the scene for this test";
  const double unseen_record_bytes = static_cast<double>(scene->size() - b.stats.visible) * 48.0;
  EXPECT_GT(static_cast<double>(a.stats.device_memory_bytes) - static_cast<double>(b.stats.device_memory_bytes),
            unseen_record_bytes / 2);
  EXPECT_TRUE(a.image.rgb == b.image.rgb);
}

TEST(CudaVsCpu, TiledSceneWithChunkCull) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = tiled_demo_scene();
  setenv("FLASHGS_CHUNK_CULL", "1", 1);
  compare_scene("tiled demo", scene, chunk_cull_cameras(*scene));
  unsetenv("FLASHGS_CHUNK_CULL");
}

// The frames the sanitizer run uses (tools/device/gpu_check.sh runs this test under
// compute-sanitizer memcheck and racecheck): odd sizes, 4K, a camera inside the scene.
std::vector<Camera> sanitizer_cameras(const Scene& scene, const std::vector<Camera>& cameras) {
  std::vector<Camera> out = {cameras[0].resized(1001, 563), cameras[2].resized(17, 9),
                             cameras[4].resized(3840, 2160), inside_camera(scene, 1001, 563)};
  out[0].name = "1001x563";
  out[1].name = "17x9";
  out[2].name = "4K";
  return out;
}

TEST(CudaVsCpu, OddSizesAndInsideCamera) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  const std::string name = test::shared_scene_names().front();
  const auto scene = test::load_shared_scene(name);
  compare_scene(name, scene, sanitizer_cameras(*scene, test::load_shared_cameras(name)));
}

// Runs the sanitizer frames for every config, with surfaces and tile counts, but without the
// CPU comparison (memcheck makes each kernel 10-100x slower). Set FLASHGS_SANITIZER_SCENE.
TEST(CudaSanitizer, Frames) {
  FLASHGS_REQUIRE_CUDA();
  const char* name = std::getenv("FLASHGS_SANITIZER_SCENE");
  std::shared_ptr<const Scene> scene;
  std::vector<Camera> cameras;
  if (name && *name && !test::shared_scene_dir(name).empty()) {
    scene = test::load_shared_scene(name);
    cameras = test::load_shared_cameras(name);
  } else {
    scene = test::load_demo_scene();
    cameras = test::load_demo_cameras();
  }
  auto gpu = make_cuda_renderer();
  gpu->set_scene(scene);
  // FLASHGS_SANITIZER_QUICK: one config per distinct kernel (racecheck is slow).
  const bool quick = std::getenv("FLASHGS_SANITIZER_QUICK") != nullptr;
  for (const Camera& camera : sanitizer_cameras(*scene, cameras))
    for (RenderOptions o : all_configs()) {
      if (quick && !(o.is_baseline() || o.label() == "flash" || !o.pipelined_blend || !o.macro_bins))
        continue;
      o.collect_tile_counts = true;
      const Result r = render(*gpu, camera, o);
      EXPECT_EQ(count_non_finite(r.image), 0u);
      const std::uint64_t sum =
          std::accumulate(r.stats.tile_pair_counts.begin(), r.stats.tile_pair_counts.end(), std::uint64_t{0});
      EXPECT_EQ(sum, r.stats.kv_pairs) << camera.name << " " << o.label();
    }
  // The fp16 storage options (fp16_sh, fp16_shape, both), on the demo scene: it has higher
  // bands to read, the sanitizer's real scene (pc_biker) has none.
  auto demo_gpu = make_cuda_renderer();
  const auto demo = test::load_demo_scene();
  demo_gpu->set_scene(demo);
  std::vector<RenderOptions> precisions = fp16_configs();
  for (const RenderOptions& o : fp16_blend_configs()) precisions.push_back(o);
  precisions.push_back(RenderOptions{});  // and back: the scene is re-packed each time
  for (const Camera& camera : sanitizer_cameras(*demo, test::load_demo_cameras()))
    for (const RenderOptions& o : precisions) {
      const Result r = render(*demo_gpu, camera, o);
      EXPECT_EQ(count_non_finite(r.image), 0u) << camera.name << " " << o.label();
    }
}

TEST(CudaDeterminism, SameFrameTwiceGivesTheSameBytes) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const auto scene = test::load_shared_scene(name);
    const Camera camera = test::load_shared_cameras(name)[20];
    auto gpu = make_cuda_renderer();
    gpu->set_scene(scene);
    for (const RenderOptions& o : all_configs()) {
      const Result a = render(*gpu, camera, o);
      const Result other = render(*gpu, camera.resized(640, 360), RenderOptions::baseline());
      const Result b = render(*gpu, camera, o);
      auto fresh = make_cuda_renderer();
      fresh->set_scene(scene);
      const Result c = render(*fresh, camera, o);
      EXPECT_EQ(a.image.rgb, b.image.rgb) << name << " " << o.label();
      EXPECT_EQ(a.image.rgb, c.image.rgb) << name << " " << o.label();
      EXPECT_EQ(a.stats.kv_pairs, b.stats.kv_pairs);
      (void)other;
    }
  }
}

// Which kernel emits a Gaussian's pairs, and in how large pieces, only moves work: a box
// above FLASHGS_LARGE_BOX_TILES (bins with macro bins) goes to warps after preprocess, in work
// items of FLASHGS_DEFERRED_ITEM_CHUNKS 32-bin chunks. With every box deferred (1: more than
// the list holds, so the preprocess kernel emits the rest itself), none (2^20), items of one
// chunk and of 32, every byte and count equals the defaults', with bins and with tiles, at
// 1080p and 4K (pc_biker has about a thousand boxes of 33 to 600 bins at 1080p, and at 4K
// some of the whole frame).
TEST(CudaDeferredEmission, WhereAndInWhatPiecesABoxIsEmittedChangesNoByte) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  RenderOptions tile_keys;
  tile_keys.macro_bins = false;
  struct Split {
    const char* large_box_tiles;
    const char* item_chunks;
  };
  for (const std::string& name : {std::string("pc_biker"), std::string("pc_playbot")}) {
    const auto scene = test::load_shared_scene(name);
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    auto standard = make_cuda_renderer();
    standard->set_scene(scene);
    for (const Split& s : {Split{"1", "1"}, Split{"1048576", "4"}, Split{"32", "1"}, Split{"32", "32"}}) {
      setenv("FLASHGS_LARGE_BOX_TILES", s.large_box_tiles, 1);
      setenv("FLASHGS_DEFERRED_ITEM_CHUNKS", s.item_chunks, 1);
      auto split = make_cuda_renderer();  // reads the variables once
      unsetenv("FLASHGS_LARGE_BOX_TILES");
      unsetenv("FLASHGS_DEFERRED_ITEM_CHUNKS");
      split->set_scene(scene);
      for (int index : {0, 10})
        for (const Camera& camera : {cameras[index].resized(1920, 1080), cameras[index].resized(3840, 2160)})
          for (const RenderOptions& o : {RenderOptions{}, tile_keys}) {
            const std::string what = name + " camera " + std::to_string(index) + " " + std::to_string(camera.width) +
                                     "x" + std::to_string(camera.height) + " " + o.label() + ", deferred above " +
                                     s.large_box_tiles + " in items of " + s.item_chunks;
            const Result a = render(*standard, camera, o);
            const Result b = render(*split, camera, o);
            expect_same_counts(what, a.stats, b.stats);
            EXPECT_EQ(a.stats.sorted_pairs, b.stats.sorted_pairs) << what;
            EXPECT_TRUE(a.image.rgb == b.image.rgb) << what;
          }
    }
  }
}

// The per-bin sort of binned frames (launch_bin_pairs, launch_bin_blocks; FLASHGS_BIN_SORT=1 on
// every frame) gives the blend the order of CUB's radix sort over the whole frame (=0) to the
// pair, whether a bin is sorted in shared memory or in global memory
// (FLASHGS_BIN_SORT_SHARED_PAIRS=0: every bin; 64: most of them), with 16-bit keys, whose runs of
// equal depth bins the bin sort puts in order itself, with the blend beside the bin blocks (the
// default on sm_90) or after them (FLASHGS_BIN_OVERLAP=0), with the bins in the dense-first
// order (FLASHGS_DENSE_TILES_FIRST=1: the bin blocks and the blend both take it, and the
// counting pass counts the pairs), and with the pairs counted per bin by emission (the default
// at 1080p and below; FLASHGS_EMIT_BIN_COUNTS=1 at every size) or by the counting pass (=0).
// Its frames are queued before the host knows the pair count: each renderer's first frame, and
// a first 4K frame after 1080p ones, overflow the pair buffers (and with FLASHGS_INITIAL_RECORDS
// the blend records), blend nothing, and run again.
TEST(CudaBinSort, SortsEachBinAsTheWholeFrameSortDoes) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  struct Setting {
    const char* shared_pairs;
    const char* key_bits;
    const char* initial_records;
    const char* overlap = "";
    const char* dense = "";
    const char* emit_counts = "";
  };
  for (const std::string& name : {std::string("pc_biker"), std::string("pc_playbot")}) {
    const auto scene = test::load_shared_scene(name);
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    setenv("FLASHGS_BIN_SORT", "0", 1);
    auto whole_frame = make_cuda_renderer();  // reads the variables once
    unsetenv("FLASHGS_BIN_SORT");
    whole_frame->set_scene(scene);
    for (const Setting& s : {Setting{"", "", ""}, Setting{"0", "", ""}, Setting{"64", "", ""}, Setting{"", "16", ""},
                             Setting{"0", "16", ""}, Setting{"", "", "1000"}, Setting{"", "", "", "0"},
                             Setting{"", "", "", "", "1"}, Setting{"0", "", "1000", "", "1"},
                             Setting{"", "", "", "", "", "0"}, Setting{"0", "", "1000", "", "", "0"},
                             Setting{"", "", "", "", "", "1"}, Setting{"0", "16", "1000", "", "", "1"}}) {
      setenv("FLASHGS_BIN_SORT", "1", 1);  // every frame, whether it pays or not
      if (*s.shared_pairs) setenv("FLASHGS_BIN_SORT_SHARED_PAIRS", s.shared_pairs, 1);
      if (*s.key_bits) setenv("FLASHGS_SORT_KEY_BITS", s.key_bits, 1);
      if (*s.initial_records) setenv("FLASHGS_INITIAL_RECORDS", s.initial_records, 1);
      if (*s.overlap) setenv("FLASHGS_BIN_OVERLAP", s.overlap, 1);
      if (*s.dense) setenv("FLASHGS_DENSE_TILES_FIRST", s.dense, 1);
      if (*s.emit_counts) setenv("FLASHGS_EMIT_BIN_COUNTS", s.emit_counts, 1);
      auto per_bin = make_cuda_renderer();
      unsetenv("FLASHGS_BIN_SORT");
      unsetenv("FLASHGS_BIN_SORT_SHARED_PAIRS");
      unsetenv("FLASHGS_SORT_KEY_BITS");
      unsetenv("FLASHGS_INITIAL_RECORDS");
      unsetenv("FLASHGS_BIN_OVERLAP");
      unsetenv("FLASHGS_DENSE_TILES_FIRST");
      unsetenv("FLASHGS_EMIT_BIN_COUNTS");
      per_bin->set_scene(scene);
      for (int index : {0, 10})
        for (const Camera& camera : {cameras[index].resized(1920, 1080), cameras[index].resized(3840, 2160),
                                     cameras[index].resized(333, 187)}) {
          const std::string what = name + " camera " + std::to_string(index) + " " + std::to_string(camera.width) +
                                   "x" + std::to_string(camera.height) + ", shared pairs '" + s.shared_pairs +
                                   "', key bits '" + s.key_bits + "', initial records '" + s.initial_records +
                                   "', overlap '" + s.overlap + "', dense first '" + s.dense +
                                   "', emission counts '" + s.emit_counts + "'";
          const Result a = render(*whole_frame, camera, RenderOptions{});
          const Result b = render(*per_bin, camera, RenderOptions{});
          expect_same_counts(what, a.stats, b.stats);
          EXPECT_EQ(a.stats.sorted_pairs, b.stats.sorted_pairs) << what;
          EXPECT_EQ(a.stats.max_tile_pairs, b.stats.max_tile_pairs) << what;
          EXPECT_TRUE(a.image.rgb == b.image.rgb) << what;
        }
    }
  }
}

// The compact keys (tile + a depth bin, ties put in order by the ranges pass) must give the
// blend exactly the order of the 64-bit keys (tile + the depth's float bits): same kernels on
// the same order, so the images are equal to the byte. Each key length FLASHGS_SORT_KEY_BITS
// offers: 32 bits (the default), 24 (one radix pass fewer, 11-13 bits of depth) and 16 (8 bits
// of depth: long runs of ties, which the ranges pass heap-sorts). Both resolutions: 4K leaves
// fewer bits for the depth bin, hence more ties.
TEST(CudaSortKeys, CompactKeysBlendInTheSameOrderAsFullKeys) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  RenderOptions full_keys;
  full_keys.minimal_sort_bits = false;
  for (const std::string& name : test::shared_scene_names()) {
    const auto scene = test::load_shared_scene(name);
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    for (const char* key_bits : {"", "24", "16"}) {
      if (*key_bits) setenv("FLASHGS_SORT_KEY_BITS", key_bits, 1);
      auto gpu = make_cuda_renderer();  // reads the variable once
      unsetenv("FLASHGS_SORT_KEY_BITS");
      gpu->set_scene(scene);
      for (int index : {0, 10, 20})
        for (const Camera& camera : {cameras[index].resized(1920, 1080), cameras[index].resized(3840, 2160)}) {
          const Result compact = render(*gpu, camera, RenderOptions{});
          const Result full = render(*gpu, camera, full_keys);
          EXPECT_EQ(compact.stats.kv_pairs, full.stats.kv_pairs) << name << " " << camera.name;
          EXPECT_TRUE(compact.image.rgb == full.image.rgb)
              << name << " camera " << index << " " << camera.width << "x" << camera.height << ", key bits "
              << (*key_bits ? key_bits : "32") << ": the compact keys changed the blend order";
        }
    }
  }
}

// The blend's tile order (fullest tiles first) must change no byte: every tile blended once,
// each by the same code. Another view is rendered in between, so that a tile the order missed
// would show that view's pixels, not the same frame's.
TEST(CudaTileOrder, DenseTilesFirstChangesNoByte) {
  FLASHGS_REQUIRE_CUDA();
  RenderOptions natural;
  natural.dense_tiles_first = false;
  auto check = [&natural](const std::string& name, std::shared_ptr<const Scene> scene, const std::vector<Camera>& cameras) {
    setenv("FLASHGS_DENSE_TILES_FIRST", "1", 1);  // on every frame, not only where it pays
    auto gpu = make_cuda_renderer();
    unsetenv("FLASHGS_DENSE_TILES_FIRST");
    gpu->set_scene(scene);
    for (std::size_t k = 0; k < cameras.size(); ++k) {
      const Camera& camera = cameras[k];
      const Result in_order = render(*gpu, camera, natural);
      render(*gpu, cameras[(k + 1) % cameras.size()].resized(camera.width, camera.height), RenderOptions{});
      const Result dense_first = render(*gpu, camera, RenderOptions{});
      EXPECT_EQ(in_order.stats.kv_pairs, dense_first.stats.kv_pairs) << name << " " << camera.name;
      EXPECT_TRUE(in_order.image.rgb == dense_first.image.rgb)
          << name << " " << camera.name << " " << camera.width << "x" << camera.height << ": the tile order changed the image";
    }
  };
  const auto demo = test::load_demo_scene();
  const auto demo_cameras = test::load_demo_cameras();
  check("demo", demo, {demo_cameras[0].resized(1001, 563), demo_cameras[3].resized(1001, 563),
                       inside_camera(*demo, 1001, 563)});
  for (const std::string& name : test::shared_scene_names()) {
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    check(name, test::load_shared_scene(name), {cameras[0].resized(1920, 1080), cameras[10].resized(1920, 1080)});
  }
}

// Macro bins (2x2 tiles per sort key) must change no byte and no tile's pair count, alone
// and with every other switch off in turn (each emission path, both blend loops), on odd sizes
// (bins over the image's edge), 4K and a camera inside the scene (huge boxes), while sorting
// fewer pairs than tile keys would.
TEST(CudaMacroBins, ChangeNoByteAndNoTileCount) {
  FLASHGS_REQUIRE_CUDA();
  // min_fullest_tile: the fullest tile must have at least this many pairs (2049: a bin that
  // takes more than one round of 2048 values in the tile-list pass's dense path).
  // fewer_sorted: bins must sort fewer pairs than tiles (not so where every Gaussian sits on a
  // bin corner, touching four bins).
  auto check = [](const std::string& name, std::shared_ptr<const Scene> scene, const std::vector<Camera>& cameras,
                  std::uint32_t min_fullest_tile = 0, bool fewer_sorted = true) {
    auto gpu = make_cuda_renderer();
    gpu->set_scene(scene);
    for (const Camera& camera : cameras)
      for (RenderOptions binned : all_configs()) {
        if (binned.is_baseline() || !binned.macro_bins) continue;
        binned.collect_tile_counts = true;
        RenderOptions per_tile = binned;
        per_tile.macro_bins = false;
        const Result a = render(*gpu, camera, per_tile);
        const Result b = render(*gpu, camera, binned);
        const std::string what = name + " " + camera.name + " " + std::to_string(camera.width) + "x" +
                                 std::to_string(camera.height) + " " + binned.label();
        expect_same_counts(what, a.stats, b.stats);
        EXPECT_EQ(a.stats.max_tile_pairs, b.stats.max_tile_pairs) << what;
        EXPECT_GE(b.stats.max_tile_pairs, min_fullest_tile) << what;
        EXPECT_TRUE(a.stats.tile_pair_counts == b.stats.tile_pair_counts) << what << ": tile counts differ";
        EXPECT_EQ(a.stats.sorted_pairs, a.stats.kv_pairs) << what;
        if (fewer_sorted && a.stats.kv_pairs > 0) {
          EXPECT_LT(b.stats.sorted_pairs, a.stats.kv_pairs) << what;
        }
        EXPECT_LE(b.stats.sorted_pairs, a.stats.kv_pairs) << what;
        EXPECT_TRUE(a.image.rgb == b.image.rgb) << what << ": macro bins changed the image";
      }
  };
  const auto demo = test::load_demo_scene();
  const auto demo_cameras = test::load_demo_cameras();
  check("demo", demo, {demo_cameras[0].resized(1001, 563), demo_cameras[3].resized(17, 9),
                       demo_cameras[5].resized(3840, 2160), inside_camera(*demo, 1001, 563)});
  for (const std::string& name : test::shared_scene_names()) {
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    const auto scene = test::load_shared_scene(name);
    check(name, scene, {cameras[0].resized(1001, 563), inside_camera(*scene, 1919, 1079)});
  }
  // Thousands of Gaussians over a few bins: bins of several thousand values.
  for (const char* name : {"stacked", "equal_depth"}) {
    const StressCase c = make_stress_case(name);
    check(name, std::make_shared<const Scene>(c.scene), c.cameras, 2049, false);
  }
}

// The warp blend leaves the stop rule out for the staged Gaussians that cannot take a pixel
// below the minimum T (blend.cu's stop bound); with the rule run everywhere
// (FLASHGS_BLEND_STOP_BOUND=0) every byte must be the same, on frames where pixels stop:
// opaque real scenes, hundreds of stacked layers, opacities at the cut.
TEST(CudaBlend, StopBoundKeepsEveryByte) {
  FLASHGS_REQUIRE_CUDA();
  const auto compare = [](const std::string& what, const std::shared_ptr<const Scene>& scene,
                          const std::vector<Camera>& cameras) {
    auto bounded = make_cuda_renderer();
    setenv("FLASHGS_BLEND_STOP_BOUND", "0", 1);
    auto everywhere = make_cuda_renderer();
    unsetenv("FLASHGS_BLEND_STOP_BOUND");
    bounded->set_scene(scene);
    everywhere->set_scene(scene);
    for (const Camera& camera : cameras) {
      const Result a = render(*bounded, camera, RenderOptions{});
      const Result b = render(*everywhere, camera, RenderOptions{});
      EXPECT_TRUE(a.image.rgb == b.image.rgb) << what << " " << camera.name;
    }
  };
  const auto demo = test::load_demo_scene();
  const auto demo_cameras = test::load_demo_cameras();
  compare("demo", demo, {demo_cameras[0].resized(1001, 563), demo_cameras[3].resized(1920, 1080)});
  for (const std::string& name : test::shared_scene_names()) {
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    const auto scene = test::load_shared_scene(name);
    compare(name, scene, {cameras[0], cameras[10].resized(3840, 2160), inside_camera(*scene, 1001, 563)});
  }
  for (const char* name : {"stacked", "equal_depth", "opacity_edges"}) {
    const StressCase c = make_stress_case(name);
    compare(name, std::make_shared<const Scene>(c.scene), c.cameras);
  }
}

// Same tile counts as the CPU, tile by tile.
TEST(CudaStats, TileCountsMatchTheCpu) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[3].resized(800, 450);
  auto cpu = make_cpu_renderer();
  auto gpu = make_cuda_renderer();
  cpu->set_scene(scene);
  gpu->set_scene(scene);
  for (RenderOptions o : {RenderOptions{}, RenderOptions::baseline()}) {
    o.collect_tile_counts = true;
    const Result c = render(*cpu, camera, o);
    const Result g = render(*gpu, camera, o);
    EXPECT_EQ(c.stats.tile_pair_counts, g.stats.tile_pair_counts) << o.label();
    EXPECT_EQ(c.stats.max_tile_pairs, g.stats.max_tile_pairs) << o.label();
    std::vector<std::uint32_t> again;
    gpu->download_tile_counts(again);
    EXPECT_EQ(again, g.stats.tile_pair_counts);
    EXPECT_GT(g.stats.device_memory_bytes, 0u);
    EXPECT_GE(g.stats.device_peak_bytes, g.stats.device_memory_bytes);
    EXPECT_GT(g.stats.times.total_ms, 0.0);
  }
}

// The debug planes of a CUDA frame (the per-pixel kernel, whatever the algorithm) against the
// CPU's (the scalar kernel's walk): the same count at all but the pixels where expf's ulps put
// a Gaussian on the other side of 1/255 or of the stop rule (at most 1e-4 of them, off by at
// most 2), the same depth within 1e-4 relative where the counts agree, and the same colour
// bound as the colour frames.
void expect_same_planes(const std::string& what, const Result& cpu, const Result& gpu) {
  ASSERT_EQ(gpu.stats.pixel_depth.size(), cpu.stats.pixel_depth.size()) << what;
  ASSERT_EQ(gpu.stats.pixel_blended.size(), cpu.stats.pixel_blended.size()) << what;
  ASSERT_FALSE(cpu.stats.pixel_blended.empty()) << what;
  std::size_t count_differs = 0, depth_differs = 0;
  for (std::size_t i = 0; i < cpu.stats.pixel_blended.size(); ++i) {
    const std::uint32_t c = cpu.stats.pixel_blended[i], g = gpu.stats.pixel_blended[i];
    if (c != g) {
      ++count_differs;
      EXPECT_LE(std::max(c, g) - std::min(c, g), 2u) << what << " pixel " << i;
      continue;
    }
    const float zc = cpu.stats.pixel_depth[i], zg = gpu.stats.pixel_depth[i];
    if (c == 0) {
      EXPECT_TRUE(std::isnan(zg)) << what << " pixel " << i;
    } else if (!(std::abs(zc - zg) <= 1e-4f * zc)) {
      ++depth_differs;
    }
  }
  const double pixels = double(cpu.stats.pixel_blended.size());
  std::printf("%-40s count differs at %zu, depth at %zu of %.0f pixels\n", what.c_str(), count_differs,
              depth_differs, pixels);
  EXPECT_LE(double(count_differs), 1e-4 * pixels + 1) << what;
  EXPECT_LE(double(depth_differs), 1e-4 * pixels + 1) << what;
  const ImageDifference d = compare_images(cpu.image, gpu.image);
  EXPECT_LE(d.max_abs, test::kExpUlpMaxAbs) << what;
}

TEST(CudaPixelPlanes, MatchTheCpuPlanesOnTheDemoScene) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  auto cpu = make_cpu_renderer();
  auto gpu = make_cuda_renderer();
  cpu->set_scene(scene);
  gpu->set_scene(scene);
  const auto cameras = test::load_demo_cameras();
  for (const Camera& camera : {cameras[0], cameras[5].resized(1001, 563)})
    for (RenderOptions o : {RenderOptions{}, RenderOptions::baseline()}) {
      o.collect_pixel_planes = true;
      const Result c = render(*cpu, camera, o);
      const Result g = render(*gpu, camera, o);
      expect_same_planes("demo " + camera.name + " " + o.label(), c, g);
    }
}

TEST(CudaPixelPlanes, MatchTheCpuPlanesOnRealScenes) {
  FLASHGS_REQUIRE_CUDA();
  FLASHGS_REQUIRE_SHARED_SCENES();
  auto cpu = make_cpu_renderer();
  auto gpu = make_cuda_renderer();
  for (const std::string& name : test::shared_scene_names()) {
    const auto real = test::load_shared_scene(name);
    cpu->set_scene(real);
    gpu->set_scene(real);
    RenderOptions o;
    o.collect_pixel_planes = true;
    const Camera camera = test::load_shared_cameras(name)[0];
    expect_same_planes(name + " " + o.label(), render(*cpu, camera, o), render(*gpu, camera, o));
  }
}

// Planes on every output of the CUDA backend: a host frame with the flash path's switches
// that the per-pixel kernel leaves out (exp2, macro bins, the half blend) gives the planes of
// the plain flash frame, and a frame without the option carries none.
TEST(CudaPixelPlanes, SameWhateverTheFlashSwitches) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  auto gpu = make_cuda_renderer();
  gpu->set_scene(scene);
  const Camera camera = test::load_demo_cameras()[2].resized(640, 360);
  RenderOptions plain;
  plain.exp2_alpha = plain.macro_bins = false;
  plain.collect_pixel_planes = true;
  const Result reference = render(*gpu, camera, plain);
  RenderOptions half = plain;
  half.exp2_alpha = half.macro_bins = half.fp16_blend = true;
  const Result g = render(*gpu, camera, half);
  EXPECT_EQ(g.stats.pixel_blended, reference.stats.pixel_blended);
  EXPECT_EQ(g.image.rgb, reference.image.rgb);
  const Result none = render(*gpu, camera, RenderOptions{});
  EXPECT_TRUE(none.stats.pixel_depth.empty());
  EXPECT_TRUE(none.stats.pixel_blended.empty());
}

// Stage times from the stage events, on both sort paths: stages that meet with nothing queued
// between them share an event (a bin-sort frame has no ranges stage of its own), and every
// stage read must come from events that were recorded (an elapsed time of an unrecorded event
// throws).
TEST(CudaStats, StageTimesAddUpOnBothSortPaths) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[3].resized(800, 450);
  for (const char* bin_sort : {"1", "0"}) {
    setenv("FLASHGS_BIN_SORT", bin_sort, 1);
    auto gpu = make_cuda_renderer();  // reads the variable once
    unsetenv("FLASHGS_BIN_SORT");
    gpu->set_scene(scene);
    for (int frame = 0; frame < 3; ++frame) {  // both event sets, and a frame after each
      const StageTimes t = render(*gpu, camera, RenderOptions{}).stats.times;
      const std::string what = std::string("bin sort ") + bin_sort + ", frame " + std::to_string(frame);
      EXPECT_GT(t.project_ms, 0.0) << what;
      EXPECT_GT(t.sort_ms, 0.0) << what;
      EXPECT_GT(t.blend_ms, 0.0) << what;
      EXPECT_GE(t.ranges_ms, 0.0) << what;
      if (*bin_sort == '1') {
        EXPECT_EQ(t.ranges_ms, 0.0) << what;
      }
      EXPECT_DOUBLE_EQ(t.total_ms, t.project_ms + t.emit_ms + t.sort_ms + t.ranges_ms + t.blend_ms) << what;
    }
  }
}

// An empty frame (camera looking away) is the background, with no pairs.
TEST(CudaEdgeCases, EmptyFrameAndEmptyScene) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  Camera camera = test::load_demo_cameras()[0].resized(64, 48);
  for (int k = 0; k < 9; ++k) camera.rotation[k] = -camera.rotation[k];  // looks the other way
  for (int k : {0, 1, 2}) camera.rotation[3 + k] = -camera.rotation[3 + k];  // keep det = +1
  auto gpu = make_cuda_renderer();
  gpu->set_scene(scene);
  RenderOptions o;
  o.background[0] = 0.25f;
  o.background[1] = 0.5f;
  o.background[2] = 1.0f;
  Result r = render(*gpu, camera, o);
  EXPECT_EQ(r.stats.kv_pairs, 0u);
  for (std::size_t i = 0; i < r.image.rgb.size(); i += 3) {
    ASSERT_EQ(r.image.rgb[i], 0.25f);
    ASSERT_EQ(r.image.rgb[i + 2], 1.0f);
  }
  gpu->set_scene(std::make_shared<Scene>());
  r = render(*gpu, camera, o);
  EXPECT_EQ(r.stats.kv_pairs, 0u);
  EXPECT_EQ(r.image.rgb[1], 0.5f);
}

// render_to_surface writes the same pixels, as RGBA8, as render() gives as floats (exact, and
// with the half blend, whose surface kernel is a template instance of its own).
void check_surface_matches_float_image(const RenderOptions& options) {
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[1].resized(333, 187);
  auto gpu = make_cuda_renderer();
  gpu->set_scene(scene);
  const Result f = render(*gpu, camera, options);
  cudaChannelFormatDesc desc = cudaCreateChannelDesc(8, 8, 8, 8, cudaChannelFormatKindUnsigned);
  cudaArray_t array = nullptr;
  ASSERT_EQ(cudaMallocArray(&array, &desc, camera.width, camera.height, cudaArraySurfaceLoadStore), cudaSuccess);
  cudaResourceDesc res{};
  res.resType = cudaResourceTypeArray;
  res.res.array.array = array;
  cudaSurfaceObject_t surface = 0;
  ASSERT_EQ(cudaCreateSurfaceObject(&surface, &res), cudaSuccess);
  FrameStats stats;
  gpu->render_to_surface(camera, options, surface, &stats);
  ASSERT_EQ(cudaStreamSynchronize(static_cast<cudaStream_t>(gpu->stream())), cudaSuccess);
  std::vector<unsigned char> rgba(std::size_t(camera.width) * camera.height * 4);
  ASSERT_EQ(cudaMemcpy2DFromArray(rgba.data(), camera.width * 4, array, 0, 0, camera.width * 4, camera.height,
                                  cudaMemcpyDeviceToHost),
            cudaSuccess);
  EXPECT_EQ(stats.kv_pairs, f.stats.kv_pairs);
  int worst = 0;
  for (std::size_t p = 0; p < std::size_t(camera.width) * camera.height; ++p) {
    for (int ch = 0; ch < 3; ++ch) {
      const float v = std::min(1.0f, std::max(0.0f, f.image.rgb[p * 3 + ch]));
      const int expected = static_cast<int>(v * 255.0f + 0.5f);
      worst = std::max(worst, std::abs(expected - rgba[p * 4 + ch]));
    }
    EXPECT_EQ(rgba[p * 4 + 3], 255);
  }
  EXPECT_LE(worst, 0) << options.label();
  cudaDestroySurfaceObject(surface);
  cudaFreeArray(array);
}

TEST(CudaSurface, MatchesTheFloatImage) {
  FLASHGS_REQUIRE_CUDA();
  check_surface_matches_float_image(RenderOptions{});
  RenderOptions half;
  half.fp16_blend = true;
  check_surface_matches_float_image(half);
}

// A surface smaller than the frame (or not RGBA8) is refused before anything is written.
TEST(CudaSurface, TooSmallOrWrongFormatIsAnError) {
  FLASHGS_REQUIRE_CUDA();
  auto gpu = make_cuda_renderer();
  gpu->set_scene(test::load_demo_scene());
  const Camera camera = test::load_demo_cameras()[1].resized(333, 187);
  auto expect_refused = [&](cudaChannelFormatDesc desc, int width, int height, const char* why) {
    cudaArray_t array = nullptr;
    ASSERT_EQ(cudaMallocArray(&array, &desc, width, height, cudaArraySurfaceLoadStore), cudaSuccess);
    cudaResourceDesc res{};
    res.resType = cudaResourceTypeArray;
    res.res.array.array = array;
    cudaSurfaceObject_t surface = 0;
    ASSERT_EQ(cudaCreateSurfaceObject(&surface, &res), cudaSuccess);
    try {
      gpu->render_to_surface(camera, RenderOptions{}, surface, nullptr);
      ADD_FAILURE() << "a " << width << "x" << height << " surface was accepted for a 333x187 frame";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    cudaDestroySurfaceObject(surface);
    cudaFreeArray(array);
  };
  const cudaChannelFormatDesc rgba8 = cudaCreateChannelDesc(8, 8, 8, 8, cudaChannelFormatKindUnsigned);
  expect_refused(rgba8, 332, 187, "smaller than");
  expect_refused(rgba8, 333, 100, "smaller than");
  expect_refused(cudaCreateChannelDesc(32, 0, 0, 0, cudaChannelFormatKindFloat), 333, 187, "not RGBA8");
  // The renderer still works afterwards.
  EXPECT_GT(render(*gpu, camera, RenderOptions{}).stats.kv_pairs, 0u);
}

// Frames queued without waiting (render_queued, as `flashgs bench` times them) do the work of
// waited ones: queued frames of one view and then of a larger one (whose buffers grow while a
// frame is in flight) count the pairs of a fresh renderer's frames and report stage times that
// add up, and waited frames after them give a fresh renderer's bytes.
TEST(CudaQueued, FramesQueuedBackToBackLeaveTheSameFrames) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  const Camera small = test::load_demo_cameras()[1].resized(333, 187);
  const Camera large = test::load_demo_cameras()[3].resized(1001, 563);
  for (const RenderOptions& o : {RenderOptions{}, RenderOptions::baseline()}) {
    auto fresh = make_cuda_renderer();
    fresh->set_scene(scene);
    const Result want_small = render(*fresh, small, o);
    const Result want_large = render(*fresh, large, o);
    auto gpu = make_cuda_renderer();
    gpu->set_scene(scene);
    const std::pair<const Camera*, const Result*> frames[] = {
        {&small, &want_small}, {&small, &want_small}, {&small, &want_small}, {&large, &want_large}, {&large, &want_large}};
    for (const auto& [camera, want] : frames) {
      FrameStats stats;
      gpu->render_queued(*camera, o, &stats);
      EXPECT_EQ(stats.sorted_pairs, want->stats.sorted_pairs) << o.label() << " " << camera->width;
      EXPECT_EQ(stats.visible, want->stats.visible) << o.label() << " " << camera->width;
      const StageTimes& t = stats.times;
      EXPECT_GT(t.project_ms, 0.0) << o.label();
      EXPECT_GT(t.blend_ms, 0.0) << o.label();
      EXPECT_DOUBLE_EQ(t.total_ms, t.project_ms + t.emit_ms + t.sort_ms + t.ranges_ms + t.blend_ms) << o.label();
    }
    const Result got_large = render(*gpu, large, o);
    EXPECT_EQ(got_large.image.rgb, want_large.image.rgb) << o.label();
    EXPECT_EQ(got_large.stats.kv_pairs, want_large.stats.kv_pairs) << o.label();
    FrameStats stats;
    gpu->render_queued(small, o, &stats);
    const Result got_small = render(*gpu, small, o);
    EXPECT_EQ(got_small.image.rgb, want_small.image.rgb) << o.label();
  }
}

// The upload's spatial order (flashgs/spatial_order.h) moves Gaussians in memory only. The demo
// scene with a copy of some Gaussians in other colours (pairs of equal depth, which blend in
// scene order), shuffled: uploaded in spatial order and as stored, every byte and count is the
// same, and both match the CPU. By default only scenes of 2^18 Gaussians and more are put in
// spatial order (the order's 4 bytes per Gaussian on the device show which were).
std::unique_ptr<CudaRenderer> renderer_with_spatial_order(const char* mode, std::shared_ptr<const Scene> scene) {
  if (mode) setenv("FLASHGS_SPATIAL_ORDER", mode, 1);
  auto gpu = make_cuda_renderer();  // reads the variable once
  unsetenv("FLASHGS_SPATIAL_ORDER");
  gpu->set_scene(std::move(scene));
  return gpu;
}

TEST(CudaSpatialOrder, MovesGaussiansInMemoryOnly) {
  FLASHGS_REQUIRE_CUDA();
  Scene scene = *test::load_demo_scene();
  Scene twins = test::permuted(scene, test::random_order(200, 5));
  for (float& c : twins.sh_dc) c = 1.0f - c;
  scene.append(twins);
  const auto shuffled = std::make_shared<Scene>(test::permuted(scene, test::random_order(scene.size(), 9)));
  auto ordered = renderer_with_spatial_order("1", shuffled), stored = renderer_with_spatial_order("0", shuffled);
  auto by_default = renderer_with_spatial_order(nullptr, shuffled);
  auto cpu = make_cpu_renderer();
  cpu->set_scene(shuffled);
  const std::vector<Camera> cameras = test::load_demo_cameras();
  for (const Camera& camera : {cameras[1].resized(333, 187), cameras[3].resized(1001, 563)}) {
    for (const RenderOptions& o : {RenderOptions{}, RenderOptions::baseline()}) {
      const std::string what = o.label() + " " + std::to_string(camera.width);
      const Result a = render(*ordered, camera, o), b = render(*stored, camera, o);
      EXPECT_EQ(a.image.rgb, b.image.rgb) << what;
      expect_same_counts(what, a.stats, b.stats);
      EXPECT_EQ(a.stats.scene_device_bytes, b.stats.scene_device_bytes + 4 * shuffled->size()) << what;
      EXPECT_EQ(render(*by_default, camera, o).stats.scene_device_bytes, b.stats.scene_device_bytes) << what;
      expect_match("spatial order, " + what, render(*cpu, camera, o), a);
    }
  }
  // Nine copies, shuffled: 270k Gaussians in no spatial order, which the default puts in order.
  // The fp16 storages have other element sizes. (Each array fits one staging chunk here; the
  // next test covers uploads of many chunks.)
  const auto large = std::make_shared<Scene>(tile_scene(*test::load_demo_scene(), 9));
  const auto large_shuffled = std::make_shared<Scene>(test::permuted(*large, test::random_order(large->size(), 4)));
  by_default = renderer_with_spatial_order(nullptr, large_shuffled);
  stored = renderer_with_spatial_order("0", large_shuffled);
  const Camera camera = cameras[2].resized(640, 360);
  std::vector<RenderOptions> storages = fp16_configs();
  storages.insert(storages.begin(), RenderOptions{});
  for (const RenderOptions& o : storages) {
    const Result a = render(*by_default, camera, o), b = render(*stored, camera, o);
    EXPECT_EQ(a.image.rgb, b.image.rgb) << o.label();
    expect_same_counts("nine copies, " + o.label(), a.stats, b.stats);
    EXPECT_EQ(a.stats.scene_device_bytes, b.stats.scene_device_bytes + 4 * large_shuffled->size()) << o.label();
  }
}

// A reordered upload of many staging chunks (32 MB each, SceneUploader) scatters every chunk to
// its own places: 2.3M shuffled Gaussians of SH degree 3 take 2 chunks of positions, rotations
// and scales (16 bytes each) and 14 of SH bands (192 bytes; 7 as halves), and the frames are
// the bytes of the same scene uploaded as stored.
TEST(CudaSpatialOrder, ScattersUploadsOfManyChunks) {
  FLASHGS_REQUIRE_CUDA();
  const Scene demo = *test::load_demo_scene();
  const int copies = static_cast<int>(2300000 / demo.size()) + 1;
  Scene scene = tile_scene(demo, copies);
  scene.sh_degree = 3;
  scene.sh_rest.resize(scene.size() * scene.sh_rest_per_gaussian());
  std::mt19937 random(11);
  std::uniform_real_distribution<float> coefficient(-0.3f, 0.3f);
  for (float& c : scene.sh_rest) c = coefficient(random);
  const auto shuffled = std::make_shared<Scene>(test::permuted(scene, test::random_order(scene.size(), 6)));
  auto by_default = renderer_with_spatial_order(nullptr, shuffled);
  auto stored = renderer_with_spatial_order("0", shuffled);
  const std::vector<Camera> cameras = test::load_demo_cameras();
  std::vector<RenderOptions> storages = fp16_configs();
  storages.insert(storages.begin(), RenderOptions{});
  for (const Camera& camera : {cameras[0].resized(641, 359), cameras[2].resized(640, 360)})
    for (const RenderOptions& o : storages) {
      const std::string what = o.label() + " camera " + camera.name;
      const Result a = render(*by_default, camera, o), b = render(*stored, camera, o);
      EXPECT_GT(a.stats.kv_pairs, 0u) << what;
      EXPECT_EQ(a.image.rgb, b.image.rgb) << what;
      expect_same_counts(what, a.stats, b.stats);
      EXPECT_EQ(a.stats.scene_device_bytes, b.stats.scene_device_bytes + 4 * shuffled->size()) << what;
    }
}

// A scene that cannot fit in GPU memory is a flashgs::Error, not a crash, and the old scene
// stays usable. The GPU is first filled with ballast so that a 2M-Gaussian scene cannot fit.
TEST(CudaEdgeCases, SceneTooLargeIsAnError) {
  FLASHGS_REQUIRE_CUDA();
  auto gpu = make_cuda_renderer();
  const auto demo = test::load_demo_scene();
  gpu->set_scene(demo);
  const Camera camera = test::load_demo_cameras()[0].resized(320, 180);
  render(*gpu, camera, RenderOptions{});  // frame buffers exist before the ballast
  std::vector<void*> ballast;
  for (std::size_t chunk = std::size_t{1} << 30; chunk >= (std::size_t{1} << 20);) {
    void* p = nullptr;
    if (cudaMalloc(&p, chunk) == cudaSuccess) ballast.push_back(p);
    else {
      cudaGetLastError();
      chunk /= 2;
    }
  }
  const std::size_t n = 2000000;  // 2M x 56 B = 112 MB, more than the ballast left
  auto big = std::make_shared<Scene>();
  big->positions.assign(n * 3, 0.0f);
  big->scales.assign(n * 3, 0.01f);
  big->rotations.assign(n * 4, 0.0f);
  for (std::size_t i = 0; i < n; ++i) big->rotations[i * 4] = 1.0f;
  big->opacities.assign(n, 0.5f);
  big->sh_dc.assign(n * 3, 0.0f);
  try {
    gpu->set_scene(big);
    ADD_FAILURE() << "set_scene of 2M Gaussians succeeded with the GPU full";
  } catch (const Error& e) {
    std::printf("expected error: %s\n", e.what());
    EXPECT_NE(std::string(e.what()).find("out of GPU memory"), std::string::npos);
  }
  for (void* p : ballast) cudaFree(p);
  const Result r = render(*gpu, camera, RenderOptions{});
  EXPECT_GT(r.stats.kv_pairs, 0u);
}

// The fp16 storage options: the GPU stores the higher SH bands as halves (fp16_sh: 8 bytes per
// 4 coefficients instead of 16) and each Gaussian's rotation, scale and opacity as one record
// of halves (fp16_shape: 40 bytes per Gaussian instead of 56), and evaluates the same half
// values as the CPU, so CUDA matches the CPU within the usual bound with the same pairs;
// switching an option on one renderer re-packs the scene, and fp32 -> fp16 -> fp32 gives the
// bytes of fresh renderers.
void check_fp16(const std::string& name, std::shared_ptr<const Scene> scene, const Camera& camera) {
  auto cpu = make_cpu_renderer();
  cpu->set_scene(scene);
  auto fresh = [&](const RenderOptions& o) {
    auto gpu = make_cuda_renderer();
    gpu->set_scene(scene);
    return render(*gpu, camera, o);
  };
  const std::uint64_t groups_of_4 = (static_cast<std::uint64_t>(scene->sh_rest_per_gaussian()) + 3) / 4;
  const Result fp32_fresh = fresh(RenderOptions{});
  for (const RenderOptions& fp16 : fp16_configs()) {
    const std::string what = name + " " + fp16.label();
    auto toggled = make_cuda_renderer();
    toggled->set_scene(scene);
    const Result fp32_first = render(*toggled, camera, RenderOptions{});
    const Result half = render(*toggled, camera, fp16);
    const Result fp32_again = render(*toggled, camera, RenderOptions{});
    expect_match(what, render(*cpu, camera, fp16), half);
    EXPECT_GT(compare_images(fp32_first.image, half.image).max_abs, 0.0) << what << " changed nothing";
    EXPECT_EQ(fp32_first.image.rgb, fp32_fresh.image.rgb) << what;
    EXPECT_EQ(fp32_again.image.rgb, fp32_first.image.rgb) << what << ": fp32 after fp16";
    EXPECT_EQ(half.image.rgb, fresh(fp16).image.rgb) << what;
    // Fewer bytes by exactly what the option packs; the rest of the scene unchanged.
    const std::uint64_t saved = scene->size() * ((fp16.fp16_sh ? groups_of_4 * 8 : 0) + (fp16.fp16_shape ? 16 : 0));
    EXPECT_EQ(fp32_first.stats.scene_device_bytes - half.stats.scene_device_bytes, saved)
        << what << ": fp32 " << fp32_first.stats.scene_device_bytes << " B, fp16 " << half.stats.scene_device_bytes
        << " B";
    EXPECT_EQ(fp32_again.stats.scene_device_bytes, fp32_first.stats.scene_device_bytes) << what;
  }
}

// The half blend (fp16_blend) changes only the blend's arithmetic: the same pairs and counts,
// the same bytes twice and from a fresh renderer, an image within kFp16BlendMinPsnr of the
// exact blend's (53.1 to 72.8 dB on an H200, 2026-12-04, kacytran_try the lowest), and on
// the CPU, which does not honour it, exactly the CPU's flash image. Without the prefetch it is
// the same kernel loop (the same bytes); without exp2 alpha or for the baseline it is ignored.
constexpr double kFp16BlendMinPsnr = 45.0;

void check_fp16_blend(const std::string& name, std::shared_ptr<const Scene> scene, const Camera& camera) {
  auto gpu = make_cuda_renderer();
  gpu->set_scene(scene);
  auto cpu = make_cpu_renderer();
  cpu->set_scene(scene);
  for (const RenderOptions& half_options : fp16_blend_configs()) {
    RenderOptions exact_options = half_options;
    exact_options.fp16_blend = false;
    const std::string what = name + " " + half_options.label();
    const Result exact = render(*gpu, camera, exact_options);
    const Result half = render(*gpu, camera, half_options);
    expect_same_counts(what, exact.stats, half.stats);
    EXPECT_EQ(count_non_finite(half.image), 0u) << what;
    const ImageDifference d = compare_images(exact.image, half.image);
    EXPECT_GT(d.max_abs, 0.0) << what << " changed nothing";
    EXPECT_GT(d.psnr_db, kFp16BlendMinPsnr) << what << ": max abs " << d.max_abs;
    std::printf("%s: %.1f dB against the exact blend, max abs %.4f\n", what.c_str(), d.psnr_db, d.max_abs);
    EXPECT_EQ(render(*gpu, camera, half_options).image.rgb, half.image.rgb) << what;
    auto fresh = make_cuda_renderer();
    fresh->set_scene(scene);
    EXPECT_EQ(render(*fresh, camera, half_options).image.rgb, half.image.rgb) << what;
    EXPECT_EQ(render(*cpu, camera, half_options).image.rgb, render(*cpu, camera, exact_options).image.rgb) << what;
    RenderOptions unpipelined = half_options;
    unpipelined.pipelined_blend = false;
    EXPECT_EQ(render(*gpu, camera, unpipelined).image.rgb, half.image.rgb) << what << " without the prefetch";
  }
  // Where there is no exp2 loop, the option changes nothing.
  RenderOptions no_exp2, baseline = RenderOptions::baseline();
  no_exp2.exp2_alpha = false;
  for (RenderOptions o : {no_exp2, baseline}) {
    const Result exact = render(*gpu, camera, o);
    o.fp16_blend = true;
    EXPECT_EQ(render(*gpu, camera, o).image.rgb, exact.image.rgb) << name << " " << o.label();
  }
}

TEST(CudaFp16Blend, CloseToTheExactBlendWithTheSamePairs) {
  FLASHGS_REQUIRE_CUDA();
  check_fp16_blend("demo", test::load_demo_scene(), test::load_demo_cameras()[5].resized(1001, 563));
  for (const std::string& name : test::shared_scene_names())
    check_fp16_blend(name, test::load_shared_scene(name), test::load_shared_cameras(name)[0]);
}

TEST(CudaFp16, MatchesTheCpuAndTogglesLikeFreshRenderers) {
  FLASHGS_REQUIRE_CUDA();
  check_fp16("demo", test::load_demo_scene(), test::load_demo_cameras()[5].resized(1001, 563));
  for (const std::string& name : test::shared_scene_names())
    check_fp16(name, test::load_shared_scene(name), test::load_shared_cameras(name)[0]);
}

}  // namespace
}  // namespace flashgs

namespace flashgs {
namespace {

// The tiled demo scene cut into parts of uneven lengths (none a multiple of the 256-Gaussian
// page), as a streamed cut names ranges of its chunk files.
std::vector<ScenePart> uneven_parts(std::shared_ptr<const Scene> scene) {
  std::vector<ScenePart> parts;
  std::mt19937 random(7);
  std::uniform_int_distribution<std::size_t> length(1, 19000);
  for (std::size_t first = 0; first < scene->size();) {
    const std::size_t count = std::min(scene->size() - first, length(random));
    parts.push_back(ScenePart{first, scene, first, count});  // the key: the first Gaussian
    first += count;
  }
  return parts;
}

float max_difference(const Image& a, const Image& b) {
  if (a.rgb.size() != b.rgb.size()) return INFINITY;
  float worst = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) worst = std::max(worst, std::fabs(a.rgb[i] - b.rgb[i]));
  return worst;
}

// Parts drawn from the GPU pool give the frame of the same parts assembled into one scene, to
// the byte (pairs of equal depth blend in the parts' order wherever their pages are), as the
// drawn set changes: parts kept, dropped, reordered, evicted under a tiny cap, uploaded again.
TEST(CudaSceneParts, DrawTheFrameOfTheAssembledScene) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = tiled_demo_scene();
  const std::vector<ScenePart> all = uneven_parts(scene);
  ASSERT_GT(all.size(), 20u);
  std::vector<ScenePart> alternate, reversed;
  for (std::size_t k = 0; k < all.size(); k += 2) alternate.push_back(all[k]);
  reversed.assign(all.rbegin(), all.rend());
  reversed.resize(reversed.size() / 2);
  struct Step {
    const char* name;
    const std::vector<ScenePart>* parts;
    std::uint64_t resident_bytes;
  };
  const Step steps[] = {{"all", &all, 0},
                        {"every other", &alternate, 0},
                        {"half, reversed", &reversed, 0},
                        {"every other under a tiny cap", &alternate, 1},
                        {"all again", &all, 1}};
  auto pooled = make_cuda_renderer();
  for (const Step& step : steps) {
    pooled->set_scene_parts(*step.parts, step.resident_bytes);
    auto whole = make_cuda_renderer();
    whole->set_scene(assemble_scene_parts(*step.parts));
    for (const Camera& camera : chunk_cull_cameras(*scene)) {
      const std::string what = std::string(step.name) + " " + camera.name;
      const Result a = render(*pooled, camera, RenderOptions{});
      const Result b = render(*whole, camera, RenderOptions{});
      EXPECT_EQ(a.stats.kv_pairs, b.stats.kv_pairs) << what;
      EXPECT_EQ(a.stats.visible, b.stats.visible) << what;
      // Every drawn Gaussian is counted once, and nothing else the pool holds.
      EXPECT_EQ(a.stats.gaussians, scene_parts_size(*step.parts)) << what;
      EXPECT_EQ(a.stats.visible + a.stats.culled_near + a.stats.culled_offscreen + a.stats.culled_low_opacity +
                    a.stats.culled_degenerate,
                a.stats.gaussians)
          << what;
      EXPECT_TRUE(a.image.rgb == b.image.rgb) << what << ": max |difference| " << max_difference(a.image, b.image);
    }
  }
}

// A pooled scene is drawn through its page list, which only flash with fused emission in full
// precision reads: other configurations are refused with a line saying so (which
// scene_parts_refusal tells beforehand), and a scene set whole afterwards renders as in a fresh
// renderer.
TEST(CudaSceneParts, RefuseTheBaselineAndGiveWayToAWholeScene) {
  FLASHGS_REQUIRE_CUDA();
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[3].resized(333, 211);
  auto gpu = make_cuda_renderer();
  EXPECT_EQ(gpu->scene_parts_refusal(RenderOptions{}), "");
  EXPECT_NE(gpu->scene_parts_refusal(RenderOptions::baseline()).find("not by the baseline"), std::string::npos);
  gpu->set_scene_parts(uneven_parts(scene), 0);
  Image image;
  try {
    gpu->render(camera, RenderOptions::baseline(), image, nullptr);
    ADD_FAILURE() << "the baseline drew a pooled scene";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not by the baseline"), std::string::npos) << e.what();
  }
  gpu->set_scene(scene);
  auto fresh = make_cuda_renderer();
  fresh->set_scene(scene);
  for (const RenderOptions& o : {RenderOptions{}, RenderOptions::baseline()})
    EXPECT_EQ(render(*gpu, camera, o).image.rgb, render(*fresh, camera, o).image.rgb) << o.label();
}

}  // namespace
}  // namespace flashgs
