// SplatKernel's text forms: the one place the names "classic" and "antialiased" are spelled.
#include "flashgs/splat_kernel.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "flashgs/error.h"

namespace flashgs {
namespace {

constexpr const char* kClassicName = "classic";
constexpr const char* kAntialiasedName = "antialiased";

// The shortest decimal that reads back as the same float ("0.3", not "0.300000012").
std::string shortest_float_text(float v) {
  char text[32];
  for (int digits = 1; digits <= 9; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, static_cast<double>(v));
    if (std::strtof(text, nullptr) == v) break;
  }
  return text;
}

}  // namespace

std::string SplatKernel::spec() const {
  if (mode == KernelMode::classic) return kClassicName;
  if (epsilon == kGsplatAntialiasEpsilon) return kAntialiasedName;
  return std::string(kAntialiasedName) + "=" + shortest_float_text(epsilon);
}

std::string SplatKernel::description() const {
  if (mode == KernelMode::classic) return kClassicName;
  return std::string(kAntialiasedName) + " (eps " + shortest_float_text(epsilon) + ")";
}

bool operator==(const SplatKernel& a, const SplatKernel& b) {
  return a.mode == b.mode && (a.mode == KernelMode::classic || a.epsilon == b.epsilon);
}

SplatKernel next_trainer_kernel(const SplatKernel& k) {
  constexpr std::size_t count = sizeof kTrainerKernels / sizeof kTrainerKernels[0];
  for (std::size_t i = 0; i < count; ++i)
    if (kTrainerKernels[i] == k) return kTrainerKernels[(i + 1) % count];
  return kTrainerKernels[0];
}

SplatKernel parse_splat_kernel(const std::string& text, const std::string& what) {
  const std::string expected = "expected classic, antialiased or antialiased=EPS with 0 < EPS <= " +
                               shortest_float_text(kMaxAntialiasEpsilon);
  if (text == kClassicName) return SplatKernel::classic();
  if (text == kAntialiasedName) return SplatKernel::antialiased();
  const std::string prefix = std::string(kAntialiasedName) + "=";
  if (text.compare(0, prefix.size(), prefix) != 0)
    throw Error(what + " \"" + printable_file_text(text) + "\": " + expected);
  const std::string number = text.substr(prefix.size());
  char* end = nullptr;
  errno = 0;
  const float epsilon = number.empty() ? NAN : std::strtof(number.c_str(), &end);
  // A plain decimal: strtof alone would also take " 0.1", "0x1p-3" and "inf".
  const bool plain = number.find_first_not_of("0123456789.eE+-") == std::string::npos &&
                     !number.empty() && number[0] != '+' && number[0] != '-';
  const bool whole = plain && end == number.c_str() + number.size() && errno == 0;
  if (!whole || !(epsilon > 0.0f) || !(epsilon <= kMaxAntialiasEpsilon))
    throw Error(what + " \"" + printable_file_text(text) + "\": " + expected);
  return SplatKernel::antialiased(epsilon);
}

}  // namespace flashgs
