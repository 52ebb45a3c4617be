// The CPU backend's SIMD blend against its scalar reference kernel and against itself without
// its span pruning, cancelling a render from another thread, and rendering at another
// resolution with the same renderer.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <future>
#include <random>
#include <thread>
#include <vector>

#ifdef FLASHGS_HAVE_HWY
#include <hwy/targets.h>
#endif

#include "cpu_frame.h"  // simd_alpha and its bound
#include "cpu_stages.h"
#include "flashgs/frame_params.h"
#include "flashgs/generators.h"
#include "flashgs/renderer.h"
#include "flashgs/stress_scenes.h"
#include "test_support.h"

namespace flashgs {
namespace {

// The SIMD kernel runs the scalar kernel's operations except alpha's exponential (an exp2 with
// a short polynomial, relative error under cpu::kSimdAlphaMaxRelError, vs glibc's expf): the
// image bound is test::kExpUlp*, the one CPU vs CUDA has.

struct Frame {
  Image image;
  FrameStats stats;
};

Frame render(const std::shared_ptr<const Scene>& scene, const Camera& camera, const RenderOptions& options,
             CpuBlend blend, int threads = 0) {
  auto renderer = make_cpu_renderer(threads, blend);
  renderer->set_scene(scene);
  Frame f;
  renderer->render(camera, options, f.image, &f.stats);
  return f;
}

void expect_simd_matches_scalar(const std::shared_ptr<const Scene>& scene, const Camera& camera,
                                const std::string& what) {
  for (const RenderOptions& options : {RenderOptions{}, RenderOptions::baseline()}) {
    const Frame scalar = render(scene, camera, options, CpuBlend::scalar);
    const Frame simd = render(scene, camera, options, CpuBlend::simd);
    const ImageDifference d = compare_images(scalar.image, simd.image);
    const double typical = test::fraction_over(scalar.image, simd.image, test::kExpUlpTypicalAbs);
    std::printf("%-24s %-8s %dx%d: SIMD vs scalar max abs %.2e, PSNR %.1f dB, >1e-3: %.2e\n", what.c_str(),
                options.label().c_str(), camera.width, camera.height, d.max_abs, d.psnr_db, typical);
    EXPECT_EQ(simd.stats.kv_pairs, scalar.stats.kv_pairs) << what;
    EXPECT_EQ(d.non_finite, 0u) << what;
    EXPECT_LE(d.max_abs, test::kExpUlpMaxAbs) << what << " " << options.label();
    EXPECT_LE(typical, test::kExpUlpTypicalFraction) << what << " " << options.label();
    if (d.max_abs > test::kExpUlpMaxAbs || typical > test::kExpUlpTypicalFraction)
      test::dump_images(what + "_" + options.label() + "_simd_vs_scalar", scalar.image, simd.image);
  }
}

TEST(CpuSimdBlend, NameSaysWhichKernelBlends) {
  EXPECT_NE(make_cpu_renderer(1, CpuBlend::scalar)->name().find("scalar blend"), std::string::npos);
  const std::string simd = make_cpu_renderer(1, CpuBlend::simd)->name();
  std::printf("%s\n", simd.c_str());
  EXPECT_NE(simd.find(" blend)"), std::string::npos) << simd;
}

// An odd size: partial tiles on the right and bottom edges, where lanes lie outside the image.
TEST(CpuSimdBlend, DemoSceneMatchesTheScalarKernel) {
  expect_simd_matches_scalar(test::load_demo_scene(), test::load_demo_cameras()[2].resized(333, 187), "demo");
  expect_simd_matches_scalar(test::load_demo_scene(), test::load_demo_cameras()[5].resized(640, 360), "demo");
}

// Each SIMD target this CPU can run (e.g. SSSE3 and SSE4 with 4 lanes, AVX2 with 8, and
// AVX-512 with 16 where present), forced one at a time, against the scalar kernel.
TEST(CpuSimdBlend, EveryTargetThisCpuRunsMatchesTheScalarKernel) {
#ifdef FLASHGS_HAVE_HWY
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[2].resized(333, 187);
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    const std::string name = make_cpu_renderer(1, CpuBlend::simd)->name();
    EXPECT_NE(name.find(hwy::TargetName(target)), std::string::npos) << name;
    expect_simd_matches_scalar(scene, camera, std::string("demo ") + hwy::TargetName(target));
  }
  hwy::SetSupportedTargetsForTest(0);  // back to what the CPU supports
#else
  GTEST_SKIP() << "built without Highway: the scalar kernel only";
#endif
}

// A crowd of Gaussians in front of a small camera: footprints from under a pixel to several
// tiles, opacities from faint to 1, so that each tile holds hundreds of them (several of the
// SIMD kernel's batches), consecutive ones share some vectors of pixels and not others, and
// pixels finish (T below 1e-4) at every point of a batch, many on a batch's first members.
std::shared_ptr<const Scene> crowded_scene() {
  auto scene = std::make_shared<Scene>();
  constexpr int kCount = 6000;
  std::uint32_t state = 12345;
  const auto uniform = [&state](float lo, float hi) {
    state = state * 1664525u + 1013904223u;
    return lo + (hi - lo) * static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
  };
  for (int i = 0; i < kCount; ++i) {
    const float z = uniform(-1.0f, 1.0f);
    scene->positions.insert(scene->positions.end(), {uniform(-1.2f, 1.2f), uniform(-0.8f, 0.8f), z});
    const float size = std::exp2(uniform(-7.0f, -2.0f));
    scene->scales.insert(scene->scales.end(), {size * uniform(0.3f, 1.0f), size * uniform(0.3f, 1.0f), size});
    const float qw = uniform(-1, 1), qx = uniform(-1, 1), qy = uniform(-1, 1), qz = uniform(-1, 1);
    const float norm = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz) + 1e-6f;
    scene->rotations.insert(scene->rotations.end(), {qw / norm, qx / norm, qy / norm, qz / norm});
    scene->opacities.push_back(i % 3 == 0 ? 1.0f : uniform(0.02f, 0.98f));
    scene->sh_dc.insert(scene->sh_dc.end(), {uniform(-1.7f, 1.7f), uniform(-1.7f, 1.7f), uniform(-1.7f, 1.7f)});
  }
  return scene;
}

Camera crowded_camera() {
  const float eye[3] = {0.0f, 0.0f, -3.0f}, target[3] = {0.0f, 0.0f, 0.0f}, up[3] = {0.0f, -1.0f, 0.0f};
  return look_at_camera(eye, target, up, 93, 61, 60.0f);  // partial tiles on two edges
}

// The SIMD kernel blends a batch of Gaussians vector by vector (cpu_blend_simd.cpp): on the
// crowded scene, on every target this CPU runs, it matches the scalar kernel within the
// bound, and its bytes are the same for any thread count.
TEST(CpuSimdBlend, CrowdedTilesMatchTheScalarKernelOnEveryTarget) {
  const auto scene = crowded_scene();
  const Camera camera = crowded_camera();
  const Frame scalar = render(scene, camera, RenderOptions{}, CpuBlend::scalar, 1);
  ASSERT_GT(scalar.stats.kv_pairs, 300u * 24u) << "hundreds of Gaussians in each of the 24 tiles";
#ifdef FLASHGS_HAVE_HWY
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
#else
  const std::vector<std::int64_t> targets = {0};
#endif
  for (const std::int64_t target : targets) {
#ifdef FLASHGS_HAVE_HWY
    hwy::SetSupportedTargetsForTest(target);
    const std::string what = std::string("crowded ") + hwy::TargetName(target);
#else
    const std::string what = "crowded";
#endif
    expect_simd_matches_scalar(scene, camera, what);
    const Frame one = render(scene, camera, RenderOptions{}, CpuBlend::simd, 1);
    for (const int threads : {2, 3})
      EXPECT_EQ(render(scene, camera, RenderOptions{}, CpuBlend::simd, threads).image.rgb, one.image.rgb)
          << what << ", " << threads << " threads";
  }
#ifdef FLASHGS_HAVE_HWY
  hwy::SetSupportedTargetsForTest(0);
#endif
}

// The SIMD kernel's alpha against opacity e^(-q/2) in double, over opacities from 1/255 to 1
// (log2 opacity in float, as the project stage stores it) and q from 0 to far beyond
// the Gaussian's reach: within kSimdAlphaMaxRelError wherever alpha >= 1/255, and below 1/255
// wherever the exact value is below 1/255 e^-0.001 (power_cut's margin, which lets the kernel
// skip the power_cut test). On every SIMD target this CPU runs.
void expect_simd_alpha_within_its_bound(const std::string& what) {
  constexpr int kOpacities = 256, kSteps = 4096;
  std::vector<float> q, log2_opacity;
  std::vector<double> exact;
  for (int i = 0; i < kOpacities; ++i) {
    const float opacity =
        i == kOpacities - 1 ? 1.0f : static_cast<float>(std::pow(255.0, -1.0 + double(i) / kOpacities));
    const float lo = std::log2(opacity);  // as the project stage stores it
    const double q_edge = 2.0 * std::log(255.0 * double(opacity));  // exact alpha = 1/255 there
    for (int k = 0; k <= kSteps; ++k) {
      q.push_back(static_cast<float>(q_edge * 1.01 * k / kSteps));
      log2_opacity.push_back(lo);
    }
    for (const float far : {100.0f, 1e4f, 1e30f, INFINITY}) {
      q.push_back(far);
      log2_opacity.push_back(lo);
    }
  }
  for (std::size_t i = 0; i < q.size(); ++i)
    exact.push_back(std::exp2(double(log2_opacity[i])) * std::exp(-0.5 * double(q[i])));
  std::vector<float> alpha(q.size());
  cpu::simd_alpha(q.data(), log2_opacity.data(), alpha.data(), q.size());
  double worst = 0.0;
  std::size_t out_of_bound = 0, let_through = 0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    if (exact[i] >= gm::kAlphaMin) {
      const double error = std::abs(double(alpha[i]) / exact[i] - 1.0);
      worst = std::max(worst, error);
      out_of_bound += !(error <= cpu::kSimdAlphaMaxRelError);
    } else if (exact[i] < gm::kAlphaMin * std::exp(-1e-3)) {
      let_through += !(alpha[i] < gm::kAlphaMin && alpha[i] >= 0.0f);
    }
  }
  std::printf("%-8s simd alpha: max relative error %.2e where alpha >= 1/255 (bound %.1e), %zu values\n",
              what.c_str(), worst, cpu::kSimdAlphaMaxRelError, q.size());
  EXPECT_EQ(out_of_bound, 0u) << what << ": worst " << worst;
  EXPECT_EQ(let_through, 0u) << what << ": values below power_cut passed 1/255";
}

// Runs check(target name) on every SIMD target this build has and this CPU runs (without
// Highway: once, "scalar"), then goes back to what the CPU supports.
void on_every_target(const std::function<void(const std::string&)>& check) {
#ifdef FLASHGS_HAVE_HWY
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    check(hwy::TargetName(target));
  }
  hwy::SetSupportedTargetsForTest(0);
#else
  check("scalar");
#endif
}

TEST(CpuSimdBlend, AlphaWithinItsBoundOnEveryTarget) { on_every_target(expect_simd_alpha_within_its_bound); }

// The vector exact tile test (cpu_emit_simd.cpp) keeps the tiles the scalar test keeps, in
// the same order, on every target this CPU runs: footprints from a pixel to wider than the
// image, needles included (narrow boxes' tiles are packed across rows), on an odd-sized and a
// 1080p image (partial tiles at the edges).
void expect_exact_box_tiles_match_the_scalar_test(const std::string& what) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  const float eye[3] = {0.0f, 0.0f, -3.0f}, target[3] = {0.0f, 0.0f, 0.0f}, up[3] = {0.0f, -1.0f, 0.0f};
  std::uint64_t boxes = 0, wide_boxes = 0, narrow_tall_boxes = 0, kept = 0;
  for (const Camera& camera : {look_at_camera(eye, target, up, 93, 61, 60.0f), look_at_camera(eye, target, up, 1920, 1080, 60.0f)}) {
    const gm::CameraParams cam = make_camera_params(camera);
    const gm::GeometryParams geo = make_geometry_params(RenderOptions{});
    std::vector<std::uint32_t> vector_tiles, scalar_tiles;
    for (int n = 0; n < 4000; ++n) {
      const float position[3] = {4.0f * (uni(rng) - 0.5f), 3.0f * (uni(rng) - 0.5f), 2.0f * (uni(rng) - 0.5f)};
      const float scale[3] = {std::pow(10.0f, -3.0f + 3.5f * uni(rng)), std::pow(10.0f, -3.0f + 3.5f * uni(rng)),
                              std::pow(10.0f, -3.0f + 3.5f * uni(rng))};
      float quat[4], norm = 0.0f;
      for (float& q : quat) {
        q = normal(rng);
        norm += q * q;
      }
      for (float& q : quat) q /= std::sqrt(norm);
      gm::Footprint f;
      if (gm::project(cam, geo, position, scale, quat, 0.02f + 0.98f * uni(rng), f) != gm::kVisible) continue;
      ++boxes;
      wide_boxes += f.tile_x1 - f.tile_x0 > 16 ? 1 : 0;
      // Narrower than any vector and more tiles than one holds: packed across rows.
      narrow_tall_boxes += f.tile_x1 - f.tile_x0 < 4 && (f.tile_x1 - f.tile_x0) * (f.tile_y1 - f.tile_y0) > 16 ? 1 : 0;
      // Sentinels past the room the function asks for: it must not write there.
      const std::size_t room = cpu::exact_box_tiles_room(f);
      constexpr std::uint32_t kSentinel = 0xdeadbeefu;
      vector_tiles.assign(room + 64, kSentinel);
      const std::size_t count = cpu::exact_box_tiles(f, cam.width, cam.height, cam.tiles_x, vector_tiles.data());
      ASSERT_TRUE(std::all_of(vector_tiles.begin() + room, vector_tiles.end(),
                              [](std::uint32_t v) { return v == kSentinel; }))
          << what << ": wrote past its room (" << room << ")";
      vector_tiles.resize(count);
      scalar_tiles.clear();
      for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
        for (int tx = f.tile_x0; tx < f.tile_x1; ++tx)
          if (gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height))
            scalar_tiles.push_back(static_cast<std::uint32_t>(ty * cam.tiles_x + tx));
      kept += scalar_tiles.size();
      ASSERT_EQ(vector_tiles, scalar_tiles) << what << ": footprint " << n << " at " << f.mean_x << "," << f.mean_y;
    }
  }
  EXPECT_GT(boxes, 5000u) << what;
  EXPECT_GT(wide_boxes, 200u) << what << ": too few boxes wider than a vector";
  EXPECT_GT(narrow_tall_boxes, 50u) << what << ": too few narrow boxes of several vectors";
  EXPECT_GT(kept, 100000u) << what;
}

TEST(CpuSimdEmit, ExactBoxTilesAreTheScalarTestsOnEveryTarget) {
  on_every_target(expect_exact_box_tiles_match_the_scalar_test);
}

// FLASHGS_CPU_SIMD caps the SIMD target (e.g. AVX2 on an AVX-512 host); a name the build or
// the CPU lacks gets one line naming it and the best target; unset again, the best target.
TEST(CpuSimdTarget, TheEnvironmentCapsTheTarget) {
#ifdef FLASHGS_HAVE_HWY
  const std::string best = make_cpu_renderer(1, CpuBlend::simd)->name();
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    setenv("FLASHGS_CPU_SIMD", hwy::TargetName(target), 1);
    const std::string name = make_cpu_renderer(1, CpuBlend::simd)->name();
    EXPECT_NE(name.find(std::string(hwy::TargetName(target)) + " blend"), std::string::npos) << name;
  }
  setenv("FLASHGS_CPU_SIMD", "NO_SUCH_TARGET", 1);
  testing::internal::CaptureStderr();
  const std::string fallback = make_cpu_renderer(1, CpuBlend::simd)->name();
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("cpu_simd=NO_SUCH_TARGET (FLASHGS_CPU_SIMD): not a SIMD target"), std::string::npos) << said;
  EXPECT_EQ(fallback, best);
  unsetenv("FLASHGS_CPU_SIMD");
  EXPECT_EQ(make_cpu_renderer(1, CpuBlend::simd)->name(), best);
#else
  GTEST_SKIP() << "built without Highway: the scalar kernel only";
#endif
}

TEST(CpuSimdBlend, RealScenesMatchTheScalarKernel) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const Camera camera = test::load_shared_cameras(name)[0];
    expect_simd_matches_scalar(test::load_shared_scene(name), camera.resized(camera.width / 2, camera.height / 2),
                               name);
  }
}

// The SIMD kernel visits a slot only where a Gaussian's row span meets it, with margins of its
// own, much tighter than the scalar kernel's (cpu_blend_simd.cpp): the spans must hold every
// pixel that passes the exact test, so that the bytes are those of the kernel without pruning,
// on every SIMD target, for both algorithms, with 2 threads. A grey background: the
// transmittance left after the last Gaussian shows too.
void expect_span_pruning_changes_no_byte(const Scene& scene, const Camera& camera, const std::string& what) {
  on_every_target([&](const std::string& target) {
    for (RenderOptions options : {RenderOptions{}, RenderOptions::baseline()}) {
      options.background[0] = 0.25f;
      options.background[1] = 0.5f;
      options.background[2] = 0.75f;
      cpu::Frame frame;
      FrameStats stats;
      test::build_tile_lists(scene, camera, options, 2, frame, stats);
      const std::size_t floats = static_cast<std::size_t>(camera.width) * camera.height * 3;
      std::vector<float> pruned(floats, -1.0f), unpruned(floats, -2.0f);
      cpu::blend(options, frame, cpu::BlendKernel::simd, nullptr, pruned.data());
      cpu::blend(options, frame, cpu::BlendKernel::simd_unpruned, nullptr, unpruned.data());
      std::size_t differ = 0;
      for (std::size_t i = 0; i < floats; ++i) differ += std::memcmp(&pruned[i], &unpruned[i], sizeof(float)) != 0;
      EXPECT_EQ(differ, 0u) << what << " " << options.label() << " " << target << ": values that pruning changed, of "
                            << floats << " (" << stats.kv_pairs << " pairs)";
    }
  });
}

// Needles, a camera inside a Gaussian, far origins, opacities at the cut, stacked and
// equal-depth Gaussians, tiny images; the demo scene at an odd size (partial tiles).
TEST(CpuSimdBlend, SpanPruningChangesNoByte) {
  for (const std::string& name : stress_case_names()) {
    StressCase c = make_stress_case(name);
    if (c.huge) continue;
    load_stress_scene(c);
    expect_span_pruning_changes_no_byte(c.scene, c.cameras.at(0), name);
  }
  expect_span_pruning_changes_no_byte(*test::load_demo_scene(), test::load_demo_cameras()[2].resized(333, 187), "demo");
}

TEST(CpuSimdBlend, SpanPruningChangesNoByteOnRealScenes) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    const Camera& camera = cameras[cameras.size() > 1 ? 1 : 0];  // another view than the test above
    expect_span_pruning_changes_no_byte(*test::load_shared_scene(name), camera.resized(camera.width / 2, camera.height / 2),
                                        name);
  }
}

// The largest scene there is: pc_playbot when present, else the demo scene at 500k Gaussians.
std::shared_ptr<const Scene> large_scene(Camera& camera) {
  if (!test::shared_scene_dir("pc_playbot").empty()) {
    camera = test::load_shared_cameras("pc_playbot")[0].resized(1920, 1080);
    return test::load_shared_scene("pc_playbot");
  }
  camera = test::load_demo_cameras()[0].resized(1920, 1080);
  return std::make_shared<Scene>(make_demo_scene(500000));
}

// A flag set by another thread while a long frame renders (1080p, scalar blend: about a
// second) stops it at the next check: the render returns early, says so, and the renderer
// then renders the next frame completely.
TEST(CpuCancel, FlagSetFromAnotherThreadStopsTheRender) {
  Camera camera;
  const auto scene = large_scene(camera);
  auto renderer = make_cpu_renderer(0, CpuBlend::scalar);
  renderer->set_scene(scene);
  std::atomic<bool> cancel{false};
  renderer->set_cancel_flag(&cancel);

  Frame full;
  renderer->render(camera, RenderOptions{}, full.image, &full.stats);
  ASSERT_FALSE(full.stats.cancelled);

  std::promise<void> started;
  std::future<void> render_started = started.get_future();
  Frame cut;
  std::thread worker([&] {
    started.set_value();
    renderer->render(camera, RenderOptions{}, cut.image, &cut.stats);
  });
  render_started.wait();
  cancel.store(true);
  worker.join();
  std::printf("complete frame %.0f ms (blend %.0f); cancelled frame returned after %.0f ms\n",
              full.stats.times.total_ms, full.stats.times.blend_ms, cut.stats.times.total_ms);
  EXPECT_TRUE(cut.stats.cancelled);
  EXPECT_LT(cut.stats.times.total_ms, 0.5 * full.stats.times.total_ms);

  cancel.store(false);
  Frame again;
  renderer->render(camera, RenderOptions{}, again.image, &again.stats);
  EXPECT_FALSE(again.stats.cancelled);
  EXPECT_EQ(again.image.rgb, full.image.rgb);
}

// A flag already set stops the render at its first check, before the blend.
TEST(CpuCancel, FlagSetBeforeTheRenderStopsItBeforeTheBlend) {
  auto renderer = make_cpu_renderer(2);
  renderer->set_scene(test::load_demo_scene());
  std::atomic<bool> cancel{true};
  renderer->set_cancel_flag(&cancel);
  Frame f;
  renderer->render(test::load_demo_cameras()[0].resized(320, 180), RenderOptions{}, f.image, &f.stats);
  EXPECT_TRUE(f.stats.cancelled);
  EXPECT_EQ(f.stats.times.blend_ms, 0.0);
  renderer->set_cancel_flag(nullptr);
  renderer->render(test::load_demo_cameras()[0].resized(320, 180), RenderOptions{}, f.image, &f.stats);
  EXPECT_FALSE(f.stats.cancelled);
}

// The viewer's progressive path: a coarse frame (Camera::resized), the full one, a coarse one
// again, all from one renderer whose buffers grow and are reused: each is the frame a fresh
// renderer gives.
TEST(CpuResolution, ReducedAndFullFramesFromOneRendererMatchFreshRenderers) {
  const auto scene = test::load_demo_scene();
  const Camera full = test::load_demo_cameras()[4].resized(640, 360);
  const Camera coarse = full.resized(160, 90);
  auto renderer = make_cpu_renderer(2);
  renderer->set_scene(scene);
  for (const Camera* camera : {&coarse, &full, &coarse}) {
    Frame reused;
    renderer->render(*camera, RenderOptions{}, reused.image, &reused.stats);
    const Frame fresh = render(scene, *camera, RenderOptions{}, CpuBlend::simd, 2);
    ASSERT_EQ(reused.image.width, camera->width);
    ASSERT_EQ(reused.image.height, camera->height);
    EXPECT_EQ(reused.image.rgb, fresh.image.rgb) << camera->width << "x" << camera->height;
    EXPECT_EQ(reused.stats.kv_pairs, fresh.stats.kv_pairs);
  }
}

}  // namespace
}  // namespace flashgs
