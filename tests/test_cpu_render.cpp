// The CPU backend: flash vs baseline vs the fp64 reference, determinism, options, real scenes.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "flashgs/io.h"
#include "flashgs/reference_renderer.h"
#include "flashgs/renderer.h"
#include "test_support.h"

namespace flashgs {
namespace {

struct Frame {
  Image image;
  FrameStats stats;
};

Frame render(std::shared_ptr<const Scene> scene, const Camera& camera, const RenderOptions& options, int threads = 0) {
  auto renderer = make_cpu_renderer(threads);
  renderer->set_scene(std::move(scene));
  Frame f;
  renderer->render(camera, options, f.image, &f.stats);
  return f;
}

// Flash with tau = 1/255 removes only work that contributes nothing: >= 50 dB against the
// baseline on every real scene, with far fewer pairs.
TEST(CpuRealScenes, FlashMatchesBaselineWithFewerPairs) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const auto scene = test::load_shared_scene(name);
    const auto cameras = test::load_shared_cameras(name);
    // Far ring: the donut is smaller than the 0.2 near distance of the mid ring.
    for (int index : {0, 20})
      for (const SplatKernel& kernel : test::kernels()) {
        RenderOptions base_options = RenderOptions::baseline(), flash_options;
        base_options.kernel = flash_options.kernel = kernel;
        const Frame base = render(scene, cameras[index], base_options);
        const Frame flash = render(scene, cameras[index], flash_options);
        const ImageDifference d = compare_images(base.image, flash.image);
        std::printf("%-13s cam %2d %-15s: baseline %9llu pairs, flash %9llu (%.1f%% fewer); PSNR %.1f dB, max abs %.2e\n",
                    name.c_str(), index, kernel.spec().c_str(), static_cast<unsigned long long>(base.stats.kv_pairs),
                    static_cast<unsigned long long>(flash.stats.kv_pairs),
                    100.0 * (1.0 - double(flash.stats.kv_pairs) / double(base.stats.kv_pairs)), d.psnr_db, d.max_abs);
        EXPECT_GE(d.psnr_db, 50.0) << name << " camera " << index << " " << kernel.spec();
        EXPECT_EQ(d.non_finite, 0u);
        EXPECT_LT(flash.stats.kv_pairs, base.stats.kv_pairs / 2) << name;
        if (d.psnr_db < 50.0) test::dump_images(name + "_flash_vs_baseline", base.image, flash.image);
      }
  }
}

// Each geometry optimisation alone keeps the image; together they remove pairs. (Pair counts
// are not monotone per option: for opacity > 0.35 the opacity-aware extent reaches beyond
// 3 sigma, to every pixel where alpha >= tau, which the baseline's box cuts off.)
TEST(CpuOptions, EachOptimisationAloneKeepsTheImage) {
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[5].resized(640, 360);
  const Frame base = render(scene, camera, RenderOptions::baseline());
  const Frame all = render(scene, camera, RenderOptions{});
  EXPECT_LT(all.stats.kv_pairs, base.stats.kv_pairs);
  for (const RenderSwitch& sw : kRenderSwitches) {
    if (!sw.changes_pairs) continue;
    RenderOptions alone;
    for (const RenderSwitch& other : kRenderSwitches)
      if (other.changes_pairs) alone.*(other.member) = false;
    alone.*(sw.member) = true;
    const Frame f = render(scene, camera, alone);
    EXPECT_GE(compare_images(base.image, f.image).psnr_db, 50.0) << alone.label();
  }
}

TEST(CpuDeterminism, SameFrameTwiceAndAnyThreadCountGiveTheSameBytes) {
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[2].resized(333, 187);
  for (const RenderOptions& options : {RenderOptions{}, RenderOptions::baseline()}) {
    const Frame a = render(scene, camera, options, 2);
    const Frame b = render(scene, camera, options, 2);
    const Frame c = render(scene, camera, options, 1);
    const Frame d = render(scene, camera, options, 5);
    EXPECT_EQ(a.image.rgb, b.image.rgb);
    EXPECT_EQ(a.image.rgb, c.image.rgb);
    EXPECT_EQ(a.image.rgb, d.image.rgb);
    EXPECT_EQ(a.stats.kv_pairs, d.stats.kv_pairs);
  }
}

// OpenMP may grant fewer threads than a renderer asks for (OMP_THREAD_LIMIT, OMP_DYNAMIC, a
// render called inside another parallel region): the frame is still the single-thread one.
// Here each of two outer threads renders with 4 threads asked; with one active level allowed,
// every inner region gets one.
TEST(CpuDeterminism, FewerThreadsGrantedThanAskedGiveTheSameFrame) {
#ifdef _OPENMP
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[3].resized(320, 180);
  const Frame single = render(scene, camera, RenderOptions{}, 1);
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(1);
  std::vector<Frame> frames(2);
  int outer_team = 0;
#pragma omp parallel num_threads(2)
  {
    if (omp_get_thread_num() == 0) outer_team = omp_get_num_threads();  // one writer: no race
    frames[omp_get_thread_num()] = render(scene, camera, RenderOptions{}, 4);
  }
  omp_set_max_active_levels(levels);
  ASSERT_EQ(outer_team, 2) << "the outer region needs two threads for the inner ones to get one";
  for (const Frame& f : frames) {
    EXPECT_EQ(f.stats.kv_pairs, single.stats.kv_pairs);
    EXPECT_EQ(f.stats.visible, single.stats.visible);
    EXPECT_EQ(f.image.rgb, single.image.rgb);
  }
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

// A 65x65 camera at the origin looking down +z, focal length 64 px, the principal point at
// pixel (32, 32).
Camera axis_camera() {
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, origin[3] = {0, 0, 0};
  return Camera::from_pose(65, 65, 64.0f, 64.0f, identity, origin);
}

// Round Gaussians of world radius `sigma` at (x, 0, z) of the axis camera, grey, degree 0.
Scene round_gaussians(const std::vector<std::array<float, 2>>& x_and_z, float sigma, float opacity) {
  Scene scene;
  for (const auto& [x, z] : x_and_z) {
    scene.positions.insert(scene.positions.end(), {x, 0.0f, z});
    scene.scales.insert(scene.scales.end(), {sigma, sigma, sigma});
    scene.rotations.insert(scene.rotations.end(), {1.0f, 0.0f, 0.0f, 0.0f});
    scene.opacities.push_back(opacity);
    scene.sh_dc.insert(scene.sh_dc.end(), {0.3f, 0.3f, 0.3f});
  }
  return scene;
}

// The alpha 3DGS gives a round Gaussian of world radius sigma at (x, 0, z) at pixel offset
// (dx, 0) from its centre: its screen variance along x is sigma^2 (f / z)^2 (1 + (x / z)^2)
// (the projection's Jacobian) plus the classic 0.3 px^2 dilation.
double expected_alpha(double x, double z, double sigma, double opacity, double dx) {
  const double f = 64.0, var_x = sigma * sigma * (f / z) * (f / z) * (1.0 + (x / z) * (x / z)) + kClassicDilation;
  return std::min(0.99, opacity * std::exp(-0.5 * dx * dx / var_x));
}

Frame render_planes(const Scene& scene, const Camera& camera, RenderOptions options) {
  options.collect_pixel_planes = true;
  return render(std::make_shared<const Scene>(scene), camera, options);
}

std::size_t at(const Camera& camera, int x, int y) { return static_cast<std::size_t>(y) * camera.width + x; }

// Two Gaussians 16 pixels apart on screen, at depths 2 and 5 (screen sigma about 4 px): at each
// centre only that Gaussian blends; half-way both do, the near one first; a corner blends none.
TEST(CpuPixelPlanes, TwoGaussiansGiveTheirDepthAndCount) {
  const Camera camera = axis_camera();
  // Screen centres (24, 32) and (40, 32); world radii for 4 px at their depths.
  const double za = 2.0, zb = 5.0, xa = -8.0 * za / 64.0, xb = 8.0 * zb / 64.0;
  Scene scene = round_gaussians({{float(xa), float(za)}}, 0.125f, 0.8f);
  scene.append(round_gaussians({{float(xb), float(zb)}}, 0.3125f, 0.8f));
  for (const RenderOptions& options : {RenderOptions{}, RenderOptions::baseline()}) {
    const Frame f = render_planes(scene, camera, options);
    ASSERT_EQ(f.stats.pixel_depth.size(), 65u * 65u);
    ASSERT_EQ(f.stats.pixel_blended.size(), 65u * 65u);
    EXPECT_EQ(f.stats.pixel_blended[at(camera, 24, 32)], 1u);
    EXPECT_NEAR(f.stats.pixel_depth[at(camera, 24, 32)], za, 1e-5);
    EXPECT_EQ(f.stats.pixel_blended[at(camera, 40, 32)], 1u);
    EXPECT_NEAR(f.stats.pixel_depth[at(camera, 40, 32)], zb, 1e-5);
    // Half-way: w_a = alpha_a, w_b = alpha_b (1 - alpha_a).
    const double alpha_a = expected_alpha(xa, za, 0.125, 0.8, 8.0), alpha_b = expected_alpha(xb, zb, 0.3125, 0.8, 8.0);
    ASSERT_GT(alpha_a, 1.0 / 255.0);
    ASSERT_GT(alpha_b, 1.0 / 255.0);
    const double wa = alpha_a, wb = alpha_b * (1.0 - alpha_a);
    EXPECT_EQ(f.stats.pixel_blended[at(camera, 32, 32)], 2u);
    EXPECT_NEAR(f.stats.pixel_depth[at(camera, 32, 32)], (wa * za + wb * zb) / (wa + wb), 2e-3) << options.label();
    EXPECT_EQ(f.stats.pixel_blended[at(camera, 1, 1)], 0u);
    EXPECT_TRUE(std::isnan(f.stats.pixel_depth[at(camera, 1, 1)]));
  }
}

// Ten nearly opaque Gaussians stacked on the axis: transmittance 1 - 0.95, then 0.05^2, 0.05^3,
// and the fourth would take it below 1e-4, so the pixel stops after three: the count is 3 and
// the depth the first three's weighted mean, as the colour's walk.
TEST(CpuPixelPlanes, CountStopsWhereTheColourWalkStops) {
  const Camera camera = axis_camera();
  std::vector<std::array<float, 2>> stack;
  for (int k = 0; k < 10; ++k) stack.push_back({0.0f, 2.0f + float(k)});
  const Scene scene = round_gaussians(stack, 0.1f, 0.95f);
  const Frame f = render_planes(scene, camera, RenderOptions{});
  EXPECT_EQ(f.stats.pixel_blended[at(camera, 32, 32)], 3u);
  const double w[3] = {0.95, 0.95 * 0.05, 0.95 * 0.05 * 0.05};
  EXPECT_NEAR(f.stats.pixel_depth[at(camera, 32, 32)], (w[0] * 2 + w[1] * 3 + w[2] * 4) / (w[0] + w[1] + w[2]), 1e-4);
}

// On the demo scene: the frame with planes is the scalar kernel's colour image byte for byte,
// no pixel blends more Gaussians than its tile has pairs, depths lie between the near plane and
// the farthest Gaussian, and a pixel that blended nothing is the background.
TEST(CpuPixelPlanes, PlanesComeFromTheColourWalk) {
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[4].resized(320, 180);
  RenderOptions options;
  options.collect_tile_counts = true;
  options.background[2] = 0.25f;
  const Frame f = render_planes(*scene, camera, options);
  auto scalar = make_cpu_renderer(0, CpuBlend::scalar);
  scalar->set_scene(scene);
  Image plain;
  RenderOptions without = options;
  without.collect_pixel_planes = false;
  scalar->render(camera, without, plain, nullptr);
  EXPECT_EQ(f.image.rgb, plain.rgb);
  std::uint32_t most = 0;
  std::size_t empty = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const std::size_t p = at(camera, x, y);
      const std::uint32_t tile = (y / 16) * f.stats.tiles_x + x / 16;
      ASSERT_LE(f.stats.pixel_blended[p], f.stats.tile_pair_counts[tile]) << x << "," << y;
      most = std::max(most, f.stats.pixel_blended[p]);
      if (f.stats.pixel_blended[p] == 0) {
        ++empty;
        EXPECT_TRUE(std::isnan(f.stats.pixel_depth[p]));
        EXPECT_EQ(f.image.pixel(x, y)[2], 0.25f);
      } else {
        EXPECT_GT(f.stats.pixel_depth[p], 0.2f);
      }
    }
  EXPECT_GT(most, 10u);
  EXPECT_LT(empty, static_cast<std::size_t>(camera.width) * camera.height);
}

// A frame without the option carries no planes (they cost a pass over the pixels).
TEST(CpuPixelPlanes, OnlyWhenAsked) {
  const Frame f = render(test::load_demo_scene(), test::load_demo_cameras()[0].resized(64, 36), RenderOptions{});
  EXPECT_TRUE(f.stats.pixel_depth.empty());
  EXPECT_TRUE(f.stats.pixel_blended.empty());
}

TEST(CpuStats, TileCountsSumToThePairs) {
  const auto scene = test::load_demo_scene();
  RenderOptions options;
  options.collect_tile_counts = true;
  const Frame f = render(scene, test::load_demo_cameras()[0].resized(500, 300), options);
  ASSERT_EQ(f.stats.tile_pair_counts.size(), static_cast<std::size_t>(f.stats.tiles_x * f.stats.tiles_y));
  std::uint64_t sum = 0;
  std::uint32_t max = 0;
  for (std::uint32_t c : f.stats.tile_pair_counts) {
    sum += c;
    max = std::max(max, c);
  }
  EXPECT_EQ(sum, f.stats.kv_pairs);
  EXPECT_EQ(max, f.stats.max_tile_pairs);
  EXPECT_EQ(f.stats.visible + f.stats.culled_near + f.stats.culled_offscreen + f.stats.culled_low_opacity +
                f.stats.culled_degenerate,
            f.stats.gaussians);
}

// Each algorithm against the fp64 reference of its own rule sits within float rounding
// (measured: max abs 4e-6 for flash on the demo): flash against the unbounded image (it
// evaluates every pixel where alpha >= 1/255), the baseline against 3DGS's box in double.
// Against the unbounded image the baseline also loses what 3DGS's box cuts (see
// stress_scenes.cpp, kBoxCut: at most 0.99 e^-2 = 0.134 per Gaussian).
// The same holds for each kernel, the anti-aliased ones with their compensated opacity in the
// opacity-aware extent and the exact tile test.
void check_against_reference(const std::shared_ptr<const Scene>& scene, const Camera& camera, PixelWindow window,
                             const std::string& what, const SplatKernel& kernel) {
  RenderOptions in_kernel;
  in_kernel.kernel = kernel;
  const Image unbounded = render_reference(*scene, camera, in_kernel, window);
  const Image box_3dgs = render_reference(*scene, camera, in_kernel, window, ReferenceFootprint::box_3dgs);
  auto check = [&](RenderOptions options, const Image& reference, const char* rule, double min_psnr, double max_abs) {
    options.kernel = kernel;
    const Frame f = render(scene, camera, options);
    const Image crop = crop_image(f.image, window);
    const ImageDifference d = compare_images(reference, crop);
    std::printf("%-28s %-8s vs fp64 %-9s: PSNR %.1f dB, max abs %.2e, %.3f%% pixels > 1/255\n", what.c_str(),
                options.label().c_str(), rule, d.psnr_db, d.max_abs, 100.0 * d.fraction_over_1_255);
    EXPECT_GE(d.psnr_db, min_psnr) << what << " " << options.label() << " vs " << rule;
    EXPECT_LE(d.max_abs, max_abs) << what << " " << options.label() << " vs " << rule;
    if (d.psnr_db < min_psnr || d.max_abs > max_abs)
      test::dump_images(what + "_" + options.label() + "_" + rule, reference, crop);
  };
  check(RenderOptions{}, unbounded, "unbounded", 55.0, 2e-3);
  check(RenderOptions::baseline(), box_3dgs, "3DGS box", 55.0, 2e-3);
  check(RenderOptions::baseline(), unbounded, "unbounded", 40.0, 1e-1);
}

TEST(CpuVsReference, DemoSceneWholeFrame) {
  for (const SplatKernel& kernel : test::kernels())
    check_against_reference(test::load_demo_scene(), test::load_demo_cameras()[1].resized(160, 90), {0, 0, 160, 90},
                            "demo 160x90", kernel);
}

TEST(CpuVsReference, RealSceneCrops) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const Camera camera = test::load_shared_cameras(name)[0];
    const PixelWindow centre{camera.width / 2 - 24, camera.height / 2 - 24, 48, 48};
    // Off centre, where small distant Gaussians (3DGS's smallest boxes) are common.
    const PixelWindow off_centre{camera.width * 3 / 8, camera.height * 3 / 8, 48, 48};
    for (const SplatKernel& kernel : test::kernels()) {
      check_against_reference(test::load_shared_scene(name), camera, centre, name + " centre 48x48", kernel);
      check_against_reference(test::load_shared_scene(name), camera, off_centre, name + " off-centre 48x48", kernel);
    }
  }
}

// The exact ellipse-tile test alone removes pairs on top of the tight box and the opacity
// extent: tiles of the box that the ellipse's corners miss (FlashGS section 4).
TEST(CpuOptions, ExactTileTestRemovesPairs) {
  const auto scene = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[0].resized(640, 360);
  for (const SplatKernel& kernel : test::kernels()) {
    RenderOptions with, without;
    with.kernel = without.kernel = kernel;
    without.exact_tile_test = false;
    const Frame with_test = render(scene, camera, with);
    const Frame box_only = render(scene, camera, without);
    std::printf("demo 640x360: %llu pairs with the exact test, %llu with the box alone\n",
                static_cast<unsigned long long>(with_test.stats.kv_pairs),
                static_cast<unsigned long long>(box_only.stats.kv_pairs));
    EXPECT_LT(double(with_test.stats.kv_pairs), 0.9 * double(box_only.stats.kv_pairs));
    EXPECT_EQ(with_test.image.rgb, box_only.image.rgb) << "the tiles removed held no pixel with alpha >= tau";
  }
}

// A degree-3 scene capped at degree 0 renders exactly like the same scene stored without
// its higher bands: the cap really leaves the SH work out.
TEST(CpuShDegree, CapEqualsAStrippedScene) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  const std::string name = "kacytran_try";
  if (test::shared_scene_dir(name).empty()) GTEST_SKIP() << name << " absent";
  const auto full = test::load_shared_scene(name);
  ASSERT_EQ(full->sh_degree, 3);
  auto stripped = std::make_shared<Scene>(*full);
  stripped->sh_degree = 0;
  stripped->sh_rest.clear();
  const Camera camera = test::load_shared_cameras(name)[3].resized(480, 270);
  RenderOptions capped;
  capped.sh_degree_cap = 0;
  const Frame a = render(full, camera, capped), b = render(stripped, camera, RenderOptions{});
  EXPECT_EQ(a.image.rgb, b.image.rgb);
  const Frame c = render(full, camera, RenderOptions{});
  EXPECT_GT(compare_images(a.image, c.image).max_abs, 1e-3) << "degree 3 must change the colours";
}

TEST(CpuRealScenes, DonutTwinFilesRenderTheSameImage) {
  const std::string dir = test::shared_scene_dir("v3dg_donut");
  if (dir.empty()) GTEST_SKIP() << "../shared/scenes/v3dg_donut is absent";
  auto original = std::make_shared<Scene>(load_ply(dir + "/original_mip_splatting.ply"));
  const Camera camera = test::load_shared_cameras("v3dg_donut")[0].resized(640, 360);
  const Frame a = render(original, camera, RenderOptions{});
  const Frame b = render(test::load_shared_scene("v3dg_donut"), camera, RenderOptions{});
  const ImageDifference d = compare_images(a.image, b.image);
  EXPECT_LT(d.max_abs, 1e-4);
  EXPECT_EQ(a.stats.kv_pairs, b.stats.kv_pairs);
}

// The fp16 storage options use values rounded to halves (relative error <= 2^-11 each): the
// image must change (the option is applied) but stay this close to the fp64 reference.
// fp16_sh changes colours only, so the pairs stay; fp16_shape changes footprints, so a few
// Gaussians may meet other tiles (20 of 1.56M pairs on pc_playbot). Measured (camera 0, two
// 48x48 windows per scene; fp32 reaches 100 to 141 dB): fp16_sh 89.9 to 107 dB on the real
// scenes, 91 dB on the demo; fp16_shape 75.9 to 89.9 dB, 85.7 on the demo; both as fp16_shape.
// The bounds leave about 10 dB of margin.
struct Fp16Case {
  const char* name;
  RenderOptions options;
  double min_psnr_db;
  bool keeps_pairs;
};

std::vector<Fp16Case> fp16_cases() {
  std::vector<Fp16Case> cases;
  for (const RenderOptions& o : fp16_configs())
    cases.push_back({o.fp16_shape ? (o.fp16_sh ? "fp16_all" : "fp16_shape") : "fp16_sh", o,
                     o.fp16_shape ? 65.0 : 80.0, !o.fp16_shape});
  return cases;
}

void check_fp16(const std::string& name, const std::shared_ptr<const Scene>& scene, const Camera& camera,
                const std::vector<PixelWindow>& windows) {
  const Frame exact = render(scene, camera, RenderOptions{});
  for (const Fp16Case& c : fp16_cases()) {
    const Frame half = render(scene, camera, c.options);
    const ImageDifference change = compare_images(exact.image, half.image);
    EXPECT_GT(change.max_abs, 0.0) << name << ": " << c.name << " changed nothing";
    if (c.keeps_pairs) {
      EXPECT_EQ(half.stats.kv_pairs, exact.stats.kv_pairs) << name << ": only the colours may change";
    }
    for (const PixelWindow& w : windows) {
      const Image reference = render_reference(*scene, camera, RenderOptions{}, w);
      const ImageDifference d32 = compare_images(reference, crop_image(exact.image, w));
      const ImageDifference d16 = compare_images(reference, crop_image(half.image, w));
      std::printf("%-13s %dx%d at (%d, %d): vs fp64 fp32 %.1f dB, %s %.1f dB (max abs %.2e); vs fp32 frame %.1f dB, "
                  "pairs %llu vs %llu\n",
                  name.c_str(), w.width, w.height, w.x0, w.y0, d32.psnr_db, c.name, d16.psnr_db, d16.max_abs,
                  change.psnr_db, static_cast<unsigned long long>(half.stats.kv_pairs),
                  static_cast<unsigned long long>(exact.stats.kv_pairs));
      EXPECT_GE(d16.psnr_db, c.min_psnr_db) << name << " " << c.name;
      if (d16.psnr_db < c.min_psnr_db)
        test::dump_images(name + "_" + c.name + "_vs_fp64", reference, crop_image(half.image, w));
    }
  }
}

TEST(CpuFp16, ChangesTheImageWithinItsBoundOfTheReference) {
  check_fp16("demo", test::load_demo_scene(), test::load_demo_cameras()[1].resized(160, 90), {{0, 0, 160, 90}});
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const Camera camera = test::load_shared_cameras(name)[0];
    check_fp16(name, test::load_shared_scene(name), camera,
               {{camera.width / 2 - 24, camera.height / 2 - 24, 48, 48},
                {camera.width * 3 / 8, camera.height * 3 / 8, 48, 48}});
  }
}

}  // namespace
}  // namespace flashgs
