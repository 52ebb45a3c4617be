// The --kernel option (see kernel_option.h).
#include "kernel_option.h"

#include "flashgs/error.h"

namespace flashgs {

void KernelOption::add_to(CLI::App* command) {
  command->add_option("--kernel", text, kKernelOptionHelp)
      ->check(CLI::Validator(
          [](std::string& value) -> std::string {
            if (value == "auto") return "";
            try {
              parse_splat_kernel(value, "--kernel");
            } catch (const Error& e) {
              return e.what();
            }
            return "";
          },
          "auto|classic|antialiased[=EPS]", "KERNEL"));
}

std::optional<SplatKernel> KernelOption::chosen() const {
  if (text == "auto") return std::nullopt;
  return parse_splat_kernel(text, "--kernel");
}

SplatKernel KernelOption::resolve(const Scene& scene) const {
  return chosen().value_or(scene.trained_kernel.kernel);
}

}  // namespace flashgs
