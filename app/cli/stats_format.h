// Text formatting of FrameStats for the CLI.
#pragma once

#include <string>

#include "flashgs/stats.h"

namespace flashgs::cli {

std::string format_stats(const FrameStats& stats);

}  // namespace flashgs::cli
