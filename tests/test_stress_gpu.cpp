// Stress cases on the CUDA backend, both algorithms, against the fp64 reference (the same
// judge and bounds as the CPU suite). Skips itself without a CUDA device (ctest label "gpu").
// On the device, also run it under compute-sanitizer for out-of-bounds accesses:
//   compute-sanitizer --tool memcheck ./tests/test_stress_gpu
#include <gtest/gtest.h>

#include "flashgs/cuda_renderer.h"
#include "stress_support.h"

namespace flashgs {
namespace {

class StressCuda : public ::testing::TestWithParam<test::StressParam> {};

TEST_P(StressCuda, MatchesReferenceDeterministically) {
  std::string why;
  if (!cuda_available(&why)) GTEST_SKIP() << "no CUDA device: " << why;
  const auto& [name, algorithm, antialiased] = GetParam();
  if (make_stress_case(name).huge && !test::huge_stress_enabled())
    GTEST_SKIP() << name << ": set FLASHGS_STRESS_HUGE=1 (or run `flashgs check --huge`)";
  const SplatKernel kernel = test::stress_kernel(GetParam());
  const test::StressData& d = test::stress_data(name, kernel);
  auto renderer = make_cuda_renderer();
  renderer->set_scene(d.scene);
  const StressResult r = run_stress_case(d.c, d.reference, *renderer, "cuda", algorithm, nullptr, nullptr, kernel);
  test::expect_stress_pass(r, d.c);
  std::printf("%-16s %-8s %-11s max|err| %.3e (bound %.2e), kv %llu\n", name.c_str(), r.algorithm.c_str(),
              r.kernel.c_str(),
              r.max_abs_error, r.bound, static_cast<unsigned long long>(r.kv_pairs));
}

INSTANTIATE_TEST_SUITE_P(AllCases, StressCuda, test::all_stress_params(), test::stress_param_name);

}  // namespace
}  // namespace flashgs
