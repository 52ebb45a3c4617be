// The CLI11 validators for number options, shared by the command-line tool and the viewer:
// CLI::Range lets NaN through (every comparison with it is false), so every float option uses
// finite_in instead, and every integer option whole_number.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

#include "flashgs/error.h"

namespace flashgs {

// "[0, 3.40282e+38]": %g keeps a bound like FLT_MAX short (in full it is 39 digits, DBL_MAX 309).
inline std::string range_text(double low, double high) {
  char text[64];
  std::snprintf(text, sizeof text, "[%g, %g]", low, high);
  return text;
}

// The value is a finite number in [low, high]. Applies to each element of a vector option.
inline CLI::Validator finite_in(double low, double high) {
  const std::string range = range_text(low, high);
  return CLI::Validator(
      [low, high, range](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        const std::string shown = "\"" + printable_file_text(text) + "\"";  // typed by the user
        if (text.empty() || *end != '\0') return shown + " is not a number";
        if (!std::isfinite(v)) return shown + " is not a finite number";
        if (v < low || v > high) return printable_file_text(text) + " is outside " + range;
        return "";
      },
      "FINITE in " + range, "FINITE");
}

// The value is a whole number written in decimal digits only: CLI11 would read "" as 0 and
// "0x1" as 1, rendering a camera the user did not name. Put it before any range check.
inline CLI::Validator whole_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty()) return "the value is empty; expected a whole number";
        if (text.find_first_not_of("0123456789") != std::string::npos)
          return "\"" + printable_file_text(text) + "\" is not a whole number (decimal digits only)";
        return "";
      },
      "DIGITS", "DIGITS");
}

}  // namespace flashgs
