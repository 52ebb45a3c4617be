// Randomised mutation fuzzing of the PLY parser, built with AddressSanitizer and UBSan:
// every mutated file must either load to finite values or throw flashgs::Error, never crash
// or read out of bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "flashgs/error.h"
#include "flashgs/io.h"
#include "ply_builder.h"

namespace flashgs {
namespace {

enum class Outcome { loaded, rejected };

Outcome try_parse(const std::string& bytes) {
  // An exact-size heap copy, so ASan sees any read past the end.
  std::vector<char> copy(bytes.begin(), bytes.end());
  try {
    const Scene scene = parse_ply(copy.data(), copy.size(), "fuzz.ply");
    // What loads is what a renderer can use: every stored value a finite float.
    for (const std::vector<float>* values :
         {&scene.positions, &scene.scales, &scene.rotations, &scene.opacities, &scene.sh_dc, &scene.sh_rest})
      for (float v : *values)
        if (!std::isfinite(v)) {
          ADD_FAILURE() << "a loaded file holds a non-finite value";
          return Outcome::loaded;
        }
    return Outcome::loaded;
  } catch (const Error&) {
    return Outcome::rejected;
  }
}

std::string mutate(const std::string& seed, std::mt19937& rng) {
  std::string s = seed;
  std::uniform_int_distribution<int> kind(0, 6), byte(0, 255);
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !s.empty(); ++e) {
    const std::size_t header_end = s.find("end_header");
    // Half of the edits hit the header, where the structure is.
    const std::size_t span = (rng() % 2 && header_end != std::string::npos) ? header_end + 11 : s.size();
    const std::size_t at = rng() % std::max<std::size_t>(span, 1);
    switch (kind(rng)) {
      case 0: s[at] = static_cast<char>(byte(rng)); break;                  // flip a byte
      case 1: s.resize(at); break;                                           // truncate
      case 2: s.erase(at, 1 + rng() % 16); break;                            // delete a run
      case 3: s.insert(at, 1 + rng() % 8, static_cast<char>(byte(rng))); break;  // insert bytes
      case 4: s.insert(at, std::to_string(rng())); break;                    // insert a number
      case 5: {                                                              // change a count
        const std::size_t v = s.find("vertex ");
        if (v != std::string::npos) s.insert(v + 7, std::to_string(rng() % 100000));
        break;
      }
      default: {  // swap a property type
        const char* types[] = {"uchar", "double", "list uchar int", "int8", "float64", "bogus"};
        const std::size_t p = s.find("property float", rng() % std::max<std::size_t>(span, 1));
        if (p != std::string::npos) s.replace(p + 9, 5, types[rng() % 6]);
      }
    }
  }
  return s;
}

TEST(PlyFuzz, MutatedFilesLoadOrFailCleanly) {
  std::mt19937 rng(20241124);
  std::vector<std::string> seeds;
  for (int degree = 0; degree <= 3; ++degree) {
    test::PlyBuilder b = test::PlyBuilder::inria(degree, 7);
    seeds.push_back(b.bytes());
    b.format = "ascii";
    seeds.push_back(b.bytes());
    b.format = "binary_big_endian";
    seeds.push_back(b.bytes());
  }
  // Doubles, and other elements around the vertices (walked over by their declared size).
  test::PlyBuilder extra = test::PlyBuilder::inria(1, 7);
  for (auto& property : extra.properties) property.first = "double";
  extra.leading_elements = "element camera 1\nproperty float focal\n";
  extra.leading_data = std::string(4, '\x01');
  extra.trailing_elements = "element face 2\nproperty list uchar int vertex_indices\n";
  extra.trailing_data = std::string("\x01") + std::string(4, '\0') + "\x02" + std::string(8, '\0');
  seeds.push_back(extra.bytes());
  extra.format = "ascii";
  extra.leading_data = "1.5\n";
  extra.trailing_data = "1 0\n2 3 4\n";
  seeds.push_back(extra.bytes());
  int loaded = 0, rejected = 0;
  for (int i = 0; i < 30000; ++i) {
    const std::string input = mutate(seeds[i % seeds.size()], rng);
    (try_parse(input) == Outcome::loaded ? loaded : rejected)++;
  }
  std::printf("fuzz: %d mutated files loaded, %d rejected with an error\n", loaded, rejected);
  EXPECT_GT(rejected, 1000);
}

}  // namespace
}  // namespace flashgs
