// The CPU project stage's SIMD kernel against its scalar reference, byte for byte (cull reasons,
// footprints, blend data), on every SIMD target this CPU runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>

#ifdef FLASHGS_HAVE_HWY
#include <hwy/targets.h>
#endif

#include "cpu_frame.h"  // cpu::project and its kernels
#include "flashgs/frame_params.h"
#include "flashgs/renderer.h"
#include "flashgs/stress_scenes.h"
#include "test_support.h"

namespace flashgs {
namespace {

// What the project stage leaves for the next stages, for one scene, camera and options.
struct Projected {
  std::vector<std::uint8_t> cull;
  std::vector<gm::Footprint> footprints;
  std::vector<cpu::BlendGaussian> blend_data;
  std::size_t reasons[gm::kCullReasonCount] = {};  // Gaussians per cull reason
  std::size_t wrong_depth_bits = 0;  // visible Gaussians whose depth_bits are not their footprint's depth
};

Projected project(const Scene& scene, const Camera& camera, const RenderOptions& options, cpu::ProjectKernel kernel,
                  int threads) {
  cpu::Frame frame;
  frame.threads = threads;
  frame.camera = make_camera_params(camera);
  frame.geometry = make_geometry_params(options);
  FrameStats stats;
  cpu::project(scene, options, frame, stats, kernel);
  Projected p;
  const std::size_t n = scene.size();
  p.cull.assign(frame.cull.begin(), frame.cull.begin() + n);
  p.footprints.assign(frame.footprints.begin(), frame.footprints.begin() + n);
  p.blend_data.assign(frame.blend_data.begin(), frame.blend_data.begin() + n);
  for (const std::uint8_t reason : p.cull) p.reasons[reason]++;
  for (std::size_t i = 0; i < n; ++i)
    p.wrong_depth_bits += p.cull[i] == gm::kVisible && frame.depth_bits[i] != gm::depth_bits(p.footprints[i].depth);
  return p;
}

// The targets to compare: each one this CPU runs (forced in turn), or the one build there is.
std::vector<std::int64_t> targets() {
#ifdef FLASHGS_HAVE_HWY
  return hwy::SupportedAndGeneratedTargets();
#else
  return {0};
#endif
}

std::string target_name(std::int64_t target) {
#ifdef FLASHGS_HAVE_HWY
  return hwy::TargetName(target);
#else
  (void)target;
  return "no-highway";
#endif
}

void use_target(std::int64_t target) {
#ifdef FLASHGS_HAVE_HWY
  hwy::SetSupportedTargetsForTest(target);
#else
  (void)target;
#endif
}

// Counts of what the comparisons saw, so a test can check it compared something.
struct Totals {
  std::size_t compared = 0;
  std::size_t reasons[gm::kCullReasonCount] = {};  // Gaussians per cull reason (kVisible: visible)
  std::size_t visible() const { return reasons[gm::kVisible]; }
  std::size_t culled() const { return compared - visible(); }
};

// The SIMD kernel on every target gives the scalar kernel's bytes: the same cull reason for each
// Gaussian, and for the visible ones the same Footprint and BlendGaussian (and both kernels
// leave each visible Gaussian's depth bits for the depth sort).
void expect_same_bytes(const Scene& scene, const Camera& camera, const RenderOptions& options,
                       const std::string& what, Totals& totals) {
  const Projected scalar = project(scene, camera, options, cpu::ProjectKernel::scalar, 1);
  for (const std::int64_t target : targets()) {
    use_target(target);
    const Projected simd = project(scene, camera, options, cpu::ProjectKernel::simd, 2);
    std::size_t wrong_cull = 0, wrong_footprint = 0, wrong_blend = 0, first = scene.size();
    for (std::size_t i = 0; i < scene.size(); ++i) {
      bool same = scalar.cull[i] == simd.cull[i];
      wrong_cull += !same;
      if (same && scalar.cull[i] == gm::kVisible) {
        const bool footprint = std::memcmp(&scalar.footprints[i], &simd.footprints[i], sizeof(gm::Footprint)) == 0;
        const bool blend = std::memcmp(&scalar.blend_data[i], &simd.blend_data[i], sizeof(cpu::BlendGaussian)) == 0;
        wrong_footprint += !footprint;
        wrong_blend += !blend;
        same = footprint && blend;
      }
      if (!same && first == scene.size()) first = i;
    }
    const std::string where = what + " " + options.label() + " sh" + std::to_string(options.sh_degree_cap) +
                              " " + target_name(target);
    EXPECT_EQ(wrong_cull, 0u) << where << ": first at " << first << " (scalar " << int(scalar.cull[first])
                              << ", simd " << int(simd.cull[first]) << ")";
    EXPECT_EQ(wrong_footprint, 0u) << where << ": first at " << first;
    EXPECT_EQ(wrong_blend, 0u) << where << ": first at " << first;
    EXPECT_EQ(scalar.wrong_depth_bits, 0u) << where << " (scalar)";
    EXPECT_EQ(simd.wrong_depth_bits, 0u) << where;
    totals.compared += scene.size();
    for (int r = 0; r < gm::kCullReasonCount; ++r) totals.reasons[r] += scalar.reasons[r];
  }
  use_target(0);  // back to what the CPU supports
}

// The geometry configurations: the baseline, and flash with the opacity radius and the tight
// box each on and off (and another tau, which moves the low-opacity cull and the threshold).
std::vector<RenderOptions> geometry_configs() {
  std::vector<RenderOptions> configs{RenderOptions::baseline()};
  for (const bool opacity_radius : {true, false})
    for (const bool tight_bbox : {true, false}) {
      RenderOptions o;
      o.opacity_aware_radius = opacity_radius;
      o.tight_bbox = tight_bbox;
      configs.push_back(o);
    }
  RenderOptions other_tau;
  other_tau.tau = 0.05f;
  configs.push_back(other_tau);
  // The anti-aliased kernels (compensated opacity, another dilation), for both algorithms.
  for (const SplatKernel& kernel : {SplatKernel::antialiased(), SplatKernel::antialiased(kMipSplattingEpsilon)})
    for (RenderOptions o : {RenderOptions::baseline(), RenderOptions{}}) {
      o.kernel = kernel;
      configs.push_back(o);
    }
  return configs;
}

// Every geometry configuration at the scene's full SH, then every SH cap with and without fp16 SH,
// then the shapes as halves (fp16_shape) alone and with fp16 SH.
void expect_same_bytes_for_every_option(const Scene& scene, const Camera& camera, const std::string& what,
                                        Totals& totals) {
  for (const RenderOptions& options : geometry_configs()) expect_same_bytes(scene, camera, options, what, totals);
  for (int cap = 0; cap <= 3; ++cap)
    for (const bool fp16 : {false, true}) {
      RenderOptions o;
      o.sh_degree_cap = cap;
      o.fp16_sh = fp16;
      expect_same_bytes(scene, camera, o, what, totals);
    }
  for (const RenderOptions& o : fp16_configs())
    if (o.fp16_shape) expect_same_bytes(scene, camera, o, what, totals);
}

// The first n Gaussians of a scene.
Scene first_gaussians(const Scene& scene, std::size_t n) {
  Scene out;
  out.sh_degree = scene.sh_degree;
  const std::size_t rest_n = static_cast<std::size_t>(scene.sh_rest_per_gaussian());
  out.positions.assign(scene.positions.begin(), scene.positions.begin() + 3 * n);
  out.scales.assign(scene.scales.begin(), scene.scales.begin() + 3 * n);
  out.rotations.assign(scene.rotations.begin(), scene.rotations.begin() + 4 * n);
  out.opacities.assign(scene.opacities.begin(), scene.opacities.begin() + n);
  out.sh_dc.assign(scene.sh_dc.begin(), scene.sh_dc.begin() + 3 * n);
  out.sh_rest.assign(scene.sh_rest.begin(), scene.sh_rest.begin() + rest_n * n);
  return out;
}

// A camera at the centroid of the scene's Gaussians, looking along `camera`'s axis: most of the
// scene lies around and behind it (near culls, centres far outside the frustum).
Camera inside(const Scene& scene, Camera camera) {
  double sum[3] = {0, 0, 0};
  for (std::size_t i = 0; i < scene.size(); ++i)
    for (int k = 0; k < 3; ++k) sum[k] += scene.positions[i * 3 + k];
  for (int k = 0; k < 3; ++k) camera.position[k] = static_cast<float>(sum[k] / double(scene.size()));
  return camera;
}

TEST(CpuProjectSimd, DemoSceneGivesTheScalarBytes) {
  for (const std::int64_t target : targets()) std::printf("target %s\n", target_name(target).c_str());
  const auto scene = test::load_demo_scene();
  Totals totals;
  for (const int camera : {0, 2, 5}) {
    const Camera c = test::load_demo_cameras()[camera];
    expect_same_bytes_for_every_option(*scene, c, "demo cam" + std::to_string(camera), totals);
    expect_same_bytes_for_every_option(*scene, c.resized(333, 187), "demo 333x187", totals);
  }
  expect_same_bytes_for_every_option(*scene, inside(*scene, test::load_demo_cameras()[0]), "demo inside", totals);
  std::printf("demo: %zu Gaussians compared, %zu visible, %zu culled\n", totals.compared, totals.visible(),
              totals.culled());
  EXPECT_GT(totals.visible(), 0u);
  EXPECT_GT(totals.culled(), 0u);
}

// Sizes that are not a multiple of any lane count, and smaller than one vector: the tail.
TEST(CpuProjectSimd, EverySceneSizeGivesTheScalarBytes) {
  const auto demo = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[0];
  Totals totals;
  for (const std::size_t n : {1, 3, 7, 15, 17, 31, 1023, 1025, 2047, 2061})
    if (n <= demo->size())
      for (const RenderOptions& options : {RenderOptions{}, RenderOptions::baseline()})
        expect_same_bytes(first_gaussians(*demo, n), camera, options, "demo first " + std::to_string(n), totals);
  EXPECT_GT(totals.visible(), 0u);
}

TEST(CpuProjectSimd, StressScenesGiveTheScalarBytes) {
  Totals totals;
  for (const std::string& name : stress_case_names()) {
    StressCase c = make_stress_case(name);
    load_stress_scene(c);
    for (std::size_t k = 0; k < c.cameras.size(); ++k)
      for (const RenderOptions& options : geometry_configs())
        expect_same_bytes(c.scene, c.cameras[k], options, name + " cam" + std::to_string(k), totals);
  }
  std::printf("stress: %zu Gaussians compared, %zu visible, culled near %zu, offscreen %zu, low opacity %zu, "
              "degenerate %zu\n",
              totals.compared, totals.visible(), totals.reasons[gm::kCulledNear],
              totals.reasons[gm::kCulledOffscreen], totals.reasons[gm::kCulledLowOpacity],
              totals.reasons[gm::kCulledDegenerate]);
  for (int r = 0; r < gm::kCullReasonCount; ++r) EXPECT_GT(totals.reasons[r], 0u) << "no Gaussian with reason " << r;
}

TEST(CpuProjectSimd, RealScenesGiveTheScalarBytes) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const auto scene = test::load_shared_scene(name);
    const std::vector<Camera> cameras = test::load_shared_cameras(name);
    Totals totals;
    for (const std::size_t k : {std::size_t{0}, cameras.size() / 2})
      for (const RenderOptions& options : geometry_configs())
        expect_same_bytes(*scene, cameras[k], options, name + " cam" + std::to_string(k), totals);
    expect_same_bytes_for_every_option(*scene, inside(*scene, cameras[0]), name + " inside", totals);
    std::printf("%s: %zu Gaussians compared, %zu visible, %zu culled\n", name.c_str(), totals.compared,
                totals.visible(), totals.culled());
    EXPECT_GT(totals.visible(), 0u) << name;
  }
}

// The opacity terms are cached per scene (Frame::opacity_terms_of). A frame after the scene
// grew in place recomputes them: its results are a fresh frame's.
TEST(CpuProjectOpacityTerms, FollowASceneThatChangesSizeInPlace) {
  const auto demo = test::load_demo_scene();
  const Camera camera = test::load_demo_cameras()[0];
  const RenderOptions options;
  Scene scene = first_gaussians(*demo, 1000);
  cpu::Frame frame;
  frame.camera = make_camera_params(camera);
  frame.geometry = make_geometry_params(options);
  FrameStats stats;
  cpu::project(scene, options, frame, stats);
  scene = first_gaussians(*demo, 2000);  // the same address, more Gaussians
  for (float& opacity : scene.opacities) opacity *= 0.5f;
  cpu::project(scene, options, frame, stats);
  const Projected fresh = project(scene, camera, options, cpu::ProjectKernel::simd, 1);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < scene.size(); ++i)
    if (fresh.cull[i] == gm::kVisible)
      differ += std::memcmp(&fresh.blend_data[i], &frame.blend_data[i], sizeof(cpu::BlendGaussian)) != 0;
  EXPECT_GT(fresh.reasons[gm::kVisible], 0u);
  EXPECT_EQ(differ, 0u);
}

// A scene edited in place and set again (the same pointer, the same size): the renderer
// recomputes its opacity terms, and renders what a fresh renderer does.
TEST(CpuProjectOpacityTerms, FollowASceneSetAgainAfterAnEdit) {
  auto scene = std::make_shared<Scene>(*test::load_demo_scene());
  const Camera camera = test::load_demo_cameras()[0].resized(320, 180);
  auto renderer = make_cpu_renderer(1);
  renderer->set_scene(scene);
  Image before, after, fresh;
  renderer->render(camera, RenderOptions{}, before, nullptr);
  for (float& opacity : scene->opacities) opacity *= 0.5f;
  renderer->set_scene(scene);
  renderer->render(camera, RenderOptions{}, after, nullptr);
  auto other = make_cpu_renderer(1);
  other->set_scene(scene);
  other->render(camera, RenderOptions{}, fresh, nullptr);
  EXPECT_NE(before.rgb, fresh.rgb);  // the edit shows
  EXPECT_EQ(after.rgb, fresh.rgb);
}

}  // namespace
}  // namespace flashgs
