// The --kernel option (see kernel_option.h).
#include "kernel_option.h"

#include "flashgs/error.h"

namespace flashgs {

CLI::Validator kernel_validator(const std::string& keyword) {
  return CLI::Validator(
      [keyword](std::string& value) -> std::string {
        if (value == keyword) return "";
        try {
          parse_splat_kernel(value, "");
        } catch (const Error& e) {
          // CLI11 names the option before this: the text without parse_splat_kernel's own prefix.
          const std::string text = e.what();
          return text.substr(text.find_first_not_of(' ')) + ", or " + keyword;
        }
        return "";
      },
      keyword + "|classic|antialiased[=EPS]", "KERNEL");
}

void KernelOption::add_to(CLI::App* command) {
  command->add_option("--kernel", text, kKernelOptionHelp)->check(kernel_validator("auto"));
}

std::optional<SplatKernel> KernelOption::chosen() const {
  if (text == "auto") return std::nullopt;
  return parse_splat_kernel(text, "--kernel");
}

SplatKernel KernelOption::resolve(const Scene& scene) const {
  return chosen().value_or(scene.trained_kernel.kernel);
}

}  // namespace flashgs
