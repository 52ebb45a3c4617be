// Helpers shared by the test suites: scene paths, cached scene loading, image dumps.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/scene.h"

// Whether the suites (and the binaries they run) are built with ThreadSanitizer
// (tools/tsan.sh) or AddressSanitizer (FLASHGS_SANITIZE).
#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
#define FLASHGS_TEST_SHADOW_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer) || __has_feature(address_sanitizer)
#define FLASHGS_TEST_SHADOW_SANITIZER 1
#endif
#endif
#ifndef FLASHGS_TEST_SHADOW_SANITIZER
#define FLASHGS_TEST_SHADOW_SANITIZER 0
#endif

// These sanitizers map their shadow memory up front, far past the address-space caps
// (RLIMIT_AS) that some tests set on a child process, which then dies in the sanitizer
// itself: those tests skip there.
#define SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER()                                             \
  if (FLASHGS_TEST_SHADOW_SANITIZER)                                                           \
  GTEST_SKIP() << "sanitizer build: this test caps the address space, which the sanitizer's shadow memory exceeds"

namespace flashgs::test {

// How many times slower code runs in those sanitizer builds: the CPU-time bounds that tell
// failing fast from rendering first scale by it (a process start alone takes ~1 s under TSan).
constexpr double kSanitizerSlowdown = FLASHGS_TEST_SHADOW_SANITIZER ? 10.0 : 1.0;
// CPU seconds (user + system) of the child processes that have finished so far.
double children_cpu_seconds();

// ../shared/scenes/<name>; empty when the folder is absent.
std::string shared_scene_dir(const std::string& name);
// ../shared/scenes/formats/<file> (the compressed samples: biker.compressed.ply, biker.spz,
// playbot_sog, ...); empty when it is absent.
std::string shared_format_file(const std::string& file);
// Names of the real scenes present (pc_biker, pc_guitar, ...); empty when none.
std::vector<std::string> shared_scene_names();
// The kernels every parity test covers: classic, gsplat's anti-aliased (eps 0.3) and
// Mip-Splatting's (eps 0.1).
std::vector<SplatKernel> kernels();
// Loads (once per process) the scene and its cameras.
std::shared_ptr<const Scene> load_shared_scene(const std::string& name);
std::vector<Camera> load_shared_cameras(const std::string& name);
// The bundled demo scene.
std::shared_ptr<const Scene> load_demo_scene();
std::vector<Camera> load_demo_cameras();
// The scene's Gaussians in another order: the k-th is scene.<arrays>[order[k]].
Scene permuted(const Scene& scene, const std::vector<std::uint32_t>& order);
// A random permutation of [0, n) (the same for the same seed).
std::vector<std::uint32_t> random_order(std::size_t n, unsigned seed);
// The bound between two renders that run the same operations except exp (CPU vs CUDA: glibc's
// expf vs CUDA's; SIMD vs scalar CPU blend: Highway's vs glibc's). Such an ulp can move an
// alpha across the 1/255 cut or a transmittance across 1e-4, which changes that pixel by at
// most alpha * T * colour <= 0.99 * 1e-2 for the T cut and 1/255 * colour for the alpha cut;
// colours reach ~1.3 on these scenes. Those flips are rare (a few pixels per frame): the max
// is bounded by 1/64 and nearly all values (99.99%) must be within 1e-3.
constexpr double kExpUlpMaxAbs = 1.0 / 64.0;
constexpr double kExpUlpTypicalAbs = 1e-3;
constexpr double kExpUlpTypicalFraction = 1e-4;
// Fraction of the values of `a` and `b` that differ by more than `tolerance`.
double fraction_over(const Image& a, const Image& b, double tolerance);
// Writes expected, actual and |difference| x 10 images to the test output folder.
void dump_images(const std::string& stem, const Image& expected, const Image& actual);

}  // namespace flashgs::test

// Skips the current test when ../shared/scenes is absent.
#define FLASHGS_REQUIRE_SHARED_SCENES()                                                     \
  do {                                                                                      \
    if (::flashgs::test::shared_scene_names().empty())                                      \
      GTEST_SKIP() << "../shared/scenes is absent: real-scene test skipped";                \
  } while (0)
