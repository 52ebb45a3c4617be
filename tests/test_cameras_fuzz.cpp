// Randomised mutation fuzzing of the cameras.json parser, built with AddressSanitizer and
// UBSan: every mutated file must either load to usable cameras or throw flashgs::Error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/io.h"

namespace flashgs {
namespace {

const char* const kSeed = R"([
 {"id": 0, "img_name": "00000.png", "width": 1920, "height": 1080,
  "position": [0.5, -1.25, 3.0], "rotation": [[1, 0, 0], [0, 0, -1], [0, 1, 0]], "fx": 1111.5, "fy": 1111.5},
 {"id": 1, "img_name": "caf\u00e9", "width": 64, "height": 32,
  "position": [1e3, 2, 3], "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "fx": 50, "fy": 40}
])";

// Text that JSON holds but a camera should not: extreme numbers, other types, control characters.
const char* const kInsertions[] = {"1e300", "-1e300", "1e-300", "1e-45", "0", "-0", "65537", "1.5", "null", "true",
                                   "[]", "{}", "\"\\u0000\\u001b[2J\"", "[1,2]", "1e999", "\"\\ud800\"", ",", "]"};

std::string mutate(const std::string& seed, std::mt19937& rng) {
  std::string s = seed;
  std::uniform_int_distribution<int> kind(0, 5), byte(0, 255);
  const int edits = 1 + static_cast<int>(rng() % 3);
  for (int e = 0; e < edits && !s.empty(); ++e) {
    const std::size_t at = rng() % s.size();
    switch (kind(rng)) {
      case 0: s[at] = static_cast<char>(byte(rng)); break;  // flip a byte
      case 1: s.resize(at); break;                           // truncate
      case 2: s.erase(at, 1 + rng() % 8); break;             // delete a run
      case 3: s.insert(at, kInsertions[rng() % std::size(kInsertions)]); break;
      default: {  // replace a number with an extreme value
        const std::size_t digit = s.find_first_of("0123456789", at);
        if (digit == std::string::npos) break;
        const std::size_t end = s.find_first_not_of("0123456789.e-", digit);
        s.replace(digit, end - digit, kInsertions[rng() % 8]);
      }
    }
  }
  return s;
}

// What a loaded camera must satisfy for the renderer: finite floats, positive normal focal
// lengths, a sane size and a printable name.
void expect_usable(const Camera& c, const std::string& input) {
  bool finite = std::isnormal(c.fx) && std::isnormal(c.fy) && c.fx > 0 && c.fy > 0;
  for (float v : c.rotation) finite = finite && std::isfinite(v);
  for (float v : c.position) finite = finite && std::isfinite(v);
  EXPECT_TRUE(finite) << input;
  EXPECT_TRUE(c.width >= 1 && c.width <= 65536 && c.height >= 1 && c.height <= 65536) << input;
  for (char ch : c.name) EXPECT_GE(static_cast<unsigned char>(ch), 0x20) << input;
}

TEST(CamerasFuzz, MutatedFilesLoadOrFailCleanly) {
  ASSERT_EQ(parse_cameras(kSeed, "seed.json").size(), 2u);
  std::mt19937 rng(20261201);
  int loaded = 0, rejected = 0;
  for (int i = 0; i < 20000; ++i) {
    const std::string input = mutate(kSeed, rng);
    try {
      for (const Camera& c : parse_cameras(input, "fuzz.json")) expect_usable(c, input);
      ++loaded;
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind("fuzz.json: ", 0), 0u) << message;
      for (char ch : message) EXPECT_GE(static_cast<unsigned char>(ch), 0x20) << message;
      ++rejected;
    }
    if (HasFailure()) break;  // one failing input is enough to read
  }
  std::printf("fuzz: %d mutated camera files loaded, %d rejected with an error\n", loaded, rejected);
  EXPECT_GT(loaded, 1000);
  EXPECT_GT(rejected, 1000);
}

}  // namespace
}  // namespace flashgs
