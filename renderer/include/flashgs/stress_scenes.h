// Stress scenes: badly conditioned and extreme inputs, each with the error bound it must meet.
#pragma once

#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/reference_renderer.h"
#include "flashgs/scene.h"

namespace flashgs {

struct StressCase {
  std::string name;
  std::string description;  // what the case exercises
  Scene scene;              // empty for file cases until load_stress_scene()
  std::vector<Camera> cameras;
  // Raw PLY bytes for the cases that must go through the loader (NaN, Inf, zero quaternion,
  // logits and log-scales that overflow): written to a file and read back with load_ply.
  std::string raw_ply;
  // Where the fp64 reference is evaluated; empty: the whole image. Big images use windows
  // because the reference costs pixels x Gaussians.
  std::vector<PixelWindow> windows;
  // Largest |image - fp64 reference| allowed, per algorithm, and why (see stress_scenes.cpp).
  double bound_flash = 0;
  double bound_baseline = 0;
  std::string bound_reason;
  // Needs a lot of memory / time (8192^2, 16384^2): skipped by the CI tests, run by
  // `flashgs check --huge` and by the tests when FLASHGS_STRESS_HUGE=1.
  bool huge = false;
};

// Every case name, in a fixed order.
std::vector<std::string> stress_case_names();
// Builds one case; throws flashgs::Error on an unknown name (the message lists the names).
StressCase make_stress_case(const std::string& name);
// For raw_ply cases: writes raw_ply to a temporary file, loads it with load_ply into
// case.scene (what a user's file goes through) and returns the loader's report. For the
// others: does nothing and returns an empty report.
LoadReport load_stress_scene(StressCase& stress_case);

}  // namespace flashgs
