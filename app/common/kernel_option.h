// The --kernel option of the CLI and the viewer: "auto" (the kernel the scene file names, see
// Scene::trained_kernel) or a kernel that overrides it.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "flashgs/scene.h"
#include "flashgs/splat_kernel.h"

namespace flashgs {

constexpr const char* kKernelOptionHelp =
    "auto (the kernel the scene file names; classic when it names none), classic, antialiased "
    "(gsplat, eps 0.3) or antialiased=EPS (Mip-Splatting: 0.1)";

// Accepts a kernel (parse_splat_kernel) or `keyword` ("auto" here, "both" for `check`); a
// refusal is parse_splat_kernel's line, after CLI11's option name.
CLI::Validator kernel_validator(const std::string& keyword);

struct KernelOption {
  std::string text = "auto";
  // Adds --kernel; a value that is neither auto nor a kernel is refused while parsing.
  void add_to(CLI::App* command);
  // The kernel given, or nothing for auto.
  std::optional<SplatKernel> chosen() const;
  // The kernel to draw `scene` with.
  SplatKernel resolve(const Scene& scene) const;
};

}  // namespace flashgs
