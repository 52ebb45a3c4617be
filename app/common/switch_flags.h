// The --no-<switch> flags of the CLI and the viewer, one per row of kRenderSwitches (options.h).
#pragma once

#include <array>
#include <iterator>

#include <CLI/CLI.hpp>

#include "flashgs/options.h"

namespace flashgs {

struct SwitchFlags {
  std::array<bool, std::size(kRenderSwitches)> off{};  // per table row: its --no- flag was given
  void add_to(CLI::App* command);
  // Turns off every switch whose flag was given.
  void apply(RenderOptions* options) const;
};

}  // namespace flashgs
