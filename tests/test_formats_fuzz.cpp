// Randomised mutation fuzzing of the compressed PLY, .splat and .ksplat readers and of the recogniser
// that picks a reader (parse_scene_bytes), built with AddressSanitizer and UBSan: every
// mutated file loads to finite values or fails with one line naming the file, never a crash,
// an out-of-bounds read or an allocation larger than the file justifies.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/scene_formats.h"
#include "format_builders.h"

namespace flashgs {
namespace {

enum class Outcome { loaded, rejected };

Outcome try_parse(const std::string& bytes, const std::string& name) {
  // An exact-size heap copy, so ASan sees any read past the end.
  std::vector<char> copy(bytes.begin(), bytes.end());
  try {
    const Scene scene = parse_scene_bytes(copy.data(), copy.size(), name);
    for (const std::vector<float>* values :
         {&scene.positions, &scene.scales, &scene.rotations, &scene.opacities, &scene.sh_dc, &scene.sh_rest})
      for (float v : *values)
        if (!std::isfinite(v)) {
          ADD_FAILURE() << name << ": a loaded file holds a non-finite value";
          return Outcome::loaded;
        }
    // Nothing is made up: every Gaussian comes from bytes of the file.
    EXPECT_LE(scene.size(), bytes.size() / 16) << name;
    return Outcome::loaded;
  } catch (const Error& e) {
    const std::string message = e.what();
    // "<file>: ..." or, for a file inside an archive, "<file> -> <entry>: ...".
    EXPECT_TRUE(message.rfind(name + ": ", 0) == 0 || message.rfind(name + " -> ", 0) == 0)
        << "the message does not name the file: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "a message of more than one line: " << message;
    return Outcome::rejected;
  }
}

// Replaces the number after `key` (e.g. "element vertex ") with `value`.
void set_count(std::string& s, const std::string& key, const std::string& value) {
  const std::size_t at = s.find(key);
  if (at == std::string::npos) return;
  const std::size_t begin = at + key.size();
  const std::size_t end = s.find('\n', begin);
  if (end != std::string::npos) s.replace(begin, end - begin, value);
}

std::string mutate(const std::string& seed, std::mt19937& rng) {
  std::string s = seed;
  std::uniform_int_distribution<int> kind(0, 6), byte(0, 255);
  const char* absurd[] = {"0", "1", "255", "257", "4294967297", "18446744073709551615", "99999999999999999999", "-1"};
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !s.empty(); ++e) {
    const std::size_t header_end = s.find("end_header");
    // Half of the edits hit the header, where the structure is (if there is one).
    const std::size_t span = (rng() % 2 && header_end != std::string::npos) ? header_end + 11 : s.size();
    const std::size_t at = rng() % std::max<std::size_t>(span, 1);
    switch (kind(rng)) {
      case 0: s[at] = static_cast<char>(byte(rng)); break;                       // flip a byte
      case 1: s.resize(at); break;                                                // truncate
      case 2: s.erase(at, 1 + rng() % 16); break;                                 // delete a run
      case 3: s.insert(at, 1 + rng() % 8, static_cast<char>(byte(rng))); break;   // insert bytes
      case 4: set_count(s, "element vertex ", absurd[rng() % 8]); break;          // lie about counts
      case 5: set_count(s, "element chunk ", absurd[rng() % 8]); break;
      default: set_count(s, "element sh ", absurd[rng() % 8]); break;
    }
  }
  return s;
}

TEST(FormatsFuzz, MutatedCompressedPlyFilesLoadOrFailCleanly) {
  std::mt19937 rng(20261201);
  const std::vector<std::string> seeds = {test::compressed_ply_bytes(3), test::compressed_ply_bytes(300, 1),
                                          test::compressed_ply_bytes(257, 0, false),
                                          test::compressed_ply_bytes(20, 3)};
  int loaded = 0, rejected = 0;
  for (int i = 0; i < 20000; ++i)
    (try_parse(mutate(seeds[i % seeds.size()], rng), "fuzz.compressed.ply") == Outcome::loaded ? loaded
                                                                                               : rejected)++;
  std::printf("fuzz: %d mutated compressed PLYs loaded, %d rejected with an error\n", loaded, rejected);
  EXPECT_GT(rejected, 2000);
  EXPECT_GT(loaded, 100);  // byte flips in the data still decode
}

TEST(FormatsFuzz, MutatedSplatFilesLoadOrFailCleanly) {
  std::mt19937 rng(7);
  std::string seed;
  for (int i = 0; i < 40; ++i) {
    const float position[3] = {0.1f * i, 0, 2}, scale[3] = {0.01f, 0.02f, 0.03f};
    const std::uint8_t rgba[4] = {static_cast<std::uint8_t>(i), 128, 200, 255}, quat[4] = {255, 128, 128, 128};
    seed += test::splat_record(position, scale, rgba, quat);
  }
  // Floats that are NaN or Inf, and all-zero quaternions, appear once bytes are flipped.
  int loaded = 0, rejected = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string s = seed;
    for (int e = 1 + static_cast<int>(rng() % 8); e > 0; --e) {
      const std::size_t at = rng() % s.size();
      if (rng() % 8 == 0) s.resize(at);
      else s[at] = static_cast<char>(rng() % 4 == 0 ? 0xff : rng() & 0xff);
      if (s.empty()) break;
    }
    (try_parse(s, "fuzz.splat") == Outcome::loaded ? loaded : rejected)++;
  }
  std::printf("fuzz: %d mutated .splat files loaded, %d rejected with an error\n", loaded, rejected);
  EXPECT_GT(rejected, 1000);
  EXPECT_GT(loaded, 1000);
}

TEST(FormatsFuzz, MutatedKsplatFilesLoadOrFailCleanly) {
  std::mt19937 rng(55);
  std::vector<std::string> seeds;
  for (int mode = 0; mode <= 2; ++mode) {
    std::vector<test::KsplatGaussian> gs(9);
    for (std::size_t i = 0; i < gs.size(); ++i) {
      gs[i].rotation[0] = 1;
      for (int k = 0; k < 3; ++k) gs[i].scale[k] = 0.25f, gs[i].position[k] = 0.1f * float(i);
      gs[i].rgba[3] = 200;
      gs[i].sh.assign(static_cast<std::size_t>(mode == 2 ? 9 : 0), 0.5f);
    }
    seeds.push_back(test::ksplat_file(gs, mode, mode == 2 ? 1 : 0));
  }
  int loaded = 0, rejected = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string s = seeds[i % seeds.size()];
    for (int e = 1 + static_cast<int>(rng() % 4); e > 0 && !s.empty(); --e) {
      // Half of the edits hit the main and section headers (the first 5120 bytes).
      const std::size_t at = rng() % (rng() % 2 ? std::min<std::size_t>(s.size(), 4096 + 64) : s.size());
      switch (rng() % 4) {
        case 0: s.resize(at); break;
        case 1: s[at] = static_cast<char>(rng()); break;
        default: s[std::min(s.size() - 1, at < 4096 ? at % 48 : at)] = static_cast<char>(rng());  // the header's fields
      }
    }
    (try_parse(s, "fuzz.ksplat") == Outcome::loaded ? loaded : rejected)++;
  }
  std::printf("fuzz: %d mutated .ksplat files loaded, %d rejected with an error\n", loaded, rejected);
  EXPECT_GT(rejected, 1000);
  EXPECT_GT(loaded, 1000);
}

TEST(FormatsFuzz, RandomBytesUnderAnyNameFailCleanly) {
  std::mt19937 rng(99);
  const char* names[] = {"fuzz.ply", "fuzz.splat", "fuzz.spz", "fuzz.compressed.ply", "fuzz", "fuzz.SPLAT", "fuzz.ksplat",
                         "fuzz.sog"};
  const char* prefixes[] = {"", "ply\n", "ply\r\n", "ply\nformat binary_little_endian 1.0\nelement chunk 1\n",
                            "\x1f\x8b\x08", "PK\x03\x04", "{\"version\":2"};
  int rejected = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string s = prefixes[rng() % 7];
    for (std::size_t n = rng() % 200; n > 0; --n) s.push_back(static_cast<char>(rng() & 0xff));
    rejected += try_parse(s, names[rng() % 8]) == Outcome::rejected;
  }
  EXPECT_GT(rejected, 10000);
}

}  // namespace
}  // namespace flashgs
