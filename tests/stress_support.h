// Shared by the stress suites (CPU and CUDA): each case built, loaded and referenced once per
// process and kernel, and the parameter list (every case x both algorithms x both kernels).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>

#include "flashgs/stress_check.h"
#include "flashgs/stress_scenes.h"

namespace flashgs::test {

struct StressData {
  StressCase c;
  LoadReport report;
  std::shared_ptr<const Scene> scene;
  StressReference reference;
};

// The 8192^2 and 16384^2 cases take minutes and gigabytes on the CPU: run only when asked.
inline bool huge_stress_enabled() {
  const char* v = std::getenv("FLASHGS_STRESS_HUGE");
  return v && *v && std::string(v) != "0";
}

inline const StressData& stress_data(const std::string& name, const SplatKernel& kernel = {}) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<StressData>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[name + "/" + kernel.spec()];
  if (!slot) {
    slot = std::make_unique<StressData>();
    slot->c = make_stress_case(name);
    slot->report = load_stress_scene(slot->c);
    slot->scene = std::make_shared<const Scene>(slot->c.scene);
    slot->reference = render_stress_reference(slot->c, kernel);
  }
  return *slot;
}

// A case, an algorithm, and whether the kernel is gsplat's anti-aliased one (else classic).
using StressParam = std::tuple<std::string, Algorithm, bool>;

inline SplatKernel stress_kernel(const StressParam& param) {
  return std::get<2>(param) ? SplatKernel::antialiased() : SplatKernel::classic();
}

inline std::string stress_param_name(const ::testing::TestParamInfo<StressParam>& info) {
  return std::get<0>(info.param) + "_" + algorithm_name(std::get<1>(info.param)) + "_" +
         stress_kernel(info.param).spec();
}

inline auto all_stress_params() {
  return ::testing::Combine(::testing::ValuesIn(stress_case_names()),
                            ::testing::Values(Algorithm::flash, Algorithm::baseline), ::testing::Bool());
}

// The judge's verdict as separate expectations, so a failure names what broke.
inline void expect_stress_pass(const StressResult& r, const StressCase& c) {
  if (!r.ran) {
    EXPECT_TRUE(c.huge && r.clear_error) << "exception: " << r.error;
    return;
  }
  EXPECT_EQ(r.non_finite, 0u) << "NaN/Inf pixels";
  EXPECT_TRUE(r.deterministic) << "two renders of the same frame differ";
  EXPECT_LE(r.max_abs_error, r.bound) << c.name << " (" << r.algorithm << ") vs fp64 reference; bound: "
                                      << c.bound_reason;
}

}  // namespace flashgs::test
