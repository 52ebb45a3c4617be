// The --no-<switch> flags (see switch_flags.h).
#include "switch_flags.h"

#include <string>

namespace flashgs {

void SwitchFlags::add_to(CLI::App* command) {
  for (std::size_t k = 0; k < off.size(); ++k) {
    const RenderSwitch& s = kRenderSwitches[k];
    const std::string scope = s.honoured_by(Backend::cpu) ? "flash" : "CUDA flash";
    command->add_flag(std::string("--no-") + s.cli_name, off[k], "turn off (" + scope + "): " + s.help);
  }
}

void SwitchFlags::apply(RenderOptions* options) const {
  for (std::size_t k = 0; k < off.size(); ++k)
    if (off[k]) options->*(kRenderSwitches[k].member) = false;
}

}  // namespace flashgs
