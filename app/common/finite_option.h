// The CLI11 validator for number options, shared by the command-line tool and the viewer:
// CLI::Range lets NaN through (every comparison with it is false), so every float option uses
// this one instead.
#pragma once

#include <cmath>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

namespace flashgs {

// The value is a finite number in [low, high]. Applies to each element of a vector option.
inline CLI::Validator finite_in(double low, double high) {
  const std::string range = "[" + CLI::detail::to_string(low) + ", " + CLI::detail::to_string(high) + "]";
  return CLI::Validator(
      [low, high, range](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0') return "\"" + text + "\" is not a number";
        if (!std::isfinite(v)) return "\"" + text + "\" is not a finite number";
        if (v < low || v > high) return text + " is outside " + range;
        return "";
      },
      "FINITE in " + range, "FINITE");
}

}  // namespace flashgs
