// Randomised mutation fuzzing of the SPZ and SOG readers (chunks and LOD trees) under AddressSanitizer and UBSan:
// every mutated file must load to finite values or throw flashgs::Error, never crash, read out
// of bounds or take memory its data cannot justify.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "compressed_builders.h"
#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/scene_formats.h"

namespace flashgs {
namespace {

bool all_finite(const Scene& scene) {
  for (const std::vector<float>* values :
       {&scene.positions, &scene.scales, &scene.rotations, &scene.opacities, &scene.sh_dc, &scene.sh_rest})
    for (float v : *values)
      if (!std::isfinite(v)) return false;
  return true;
}

// Loads or is refused; counts which, and fails the test on a non-finite value.
template <typename Parse>
void expect_clean(Parse parse, int& loaded, int& rejected) {
  try {
    const Scene scene = parse();
    EXPECT_TRUE(all_finite(scene)) << "a loaded file holds a non-finite value";
    EXPECT_EQ(scene.positions.size(), scene.size() * 3);
    EXPECT_EQ(scene.sh_rest.size(), scene.size() * static_cast<std::size_t>(scene.sh_rest_per_gaussian()));
    ++loaded;
  } catch (const Error&) {
    ++rejected;
  }
}

// Byte flips, truncations, deletions and insertions; half of them in the first `hot` bytes,
// where the headers are.
std::string mutate(std::string s, std::mt19937& rng, std::size_t hot) {
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits && !s.empty(); ++e) {
    const std::size_t span = rng() % 2 ? std::min(hot, s.size()) : s.size();
    const std::size_t at = rng() % span;
    switch (rng() % 5) {
      case 0: s[at] = static_cast<char>(rng()); break;
      case 1: s.resize(at); break;
      case 2: s.erase(at, 1 + rng() % 16); break;
      case 3: s.insert(at, 1 + rng() % 8, static_cast<char>(rng())); break;
      default: s[at] = static_cast<char>(s[at] ^ (1 << (rng() % 8)));
    }
  }
  return s;
}

TEST(SpzFuzz, MutatedFilesLoadOrFailCleanly) {
  std::mt19937 rng(20241201);
  int loaded = 0, rejected = 0;
  for (int round = 0; round < 4000; ++round) {
    const std::uint32_t version = 1 + rng() % 4;
    const test::SpzContent content = test::random_spz(1 + rng() % 12, static_cast<int>(rng() % 4), version, rng);
    std::string file;
    if (version == 4) {
      file = mutate(test::spz_v4_file(content), rng, 32 + 6 * 16);
    } else if (rng() % 3 == 0) {  // stored without gzip
      file = mutate(test::spz_payload(content), rng, 16);
    } else if (rng() % 2) {  // a valid gzip stream around a mutated payload: the header and counts lie
      file = test::gzip(mutate(test::spz_payload(content), rng, 16));
    } else {  // the compressed bytes themselves
      file = mutate(test::spz_gzip_file(content), rng, 24);
    }
    std::vector<char> copy(file.begin(), file.end());  // exact size, so ASan sees any overread
    expect_clean([&] { return parse_spz(copy.data(), copy.size(), "fuzz.spz"); }, loaded, rejected);
  }
  std::printf("SPZ fuzz: %d loaded, %d refused\n", loaded, rejected);
  EXPECT_GT(loaded, 0);
  EXPECT_GT(rejected, 0);
}

TEST(SogFuzz, MutatedChunksLoadOrFailCleanly) {
  std::mt19937 rng(20241202);
  int loaded = 0, rejected = 0;
  std::vector<test::SogChunk> seeds;
  for (int bands = 0; bands <= 3; ++bands) seeds.push_back(test::random_sog_chunk(20 + 7 * bands, bands, rng));
  for (int bands = 0; bands <= 3; bands += 3) seeds.push_back(test::sog_version_1(test::random_sog_chunk(30, bands, rng)));
  for (int round = 0; round < 1000; ++round) {
    test::SogChunk chunk = seeds[rng() % seeds.size()];
    std::string meta = chunk.meta.dump();
    switch (rng() % 3) {
      case 0: meta = mutate(meta, rng, 200); break;  // the JSON text
      case 1: {                                     // one texture's bytes
        auto it = chunk.files.begin();
        std::advance(it, rng() % chunk.files.size());
        const std::string bytes = mutate(std::string(it->second.begin(), it->second.end()), rng, 40);
        it->second.assign(bytes.begin(), bytes.end());
        break;
      }
      default: {  // one texture in another's place
        auto a = chunk.files.begin(), b = chunk.files.begin();
        std::advance(a, rng() % chunk.files.size());
        std::advance(b, rng() % chunk.files.size());
        a->second = b->second;
      }
    }
    expect_clean([&] { return parse_sog(meta, chunk.source(), "fuzz/meta.json"); }, loaded, rejected);
  }
  std::printf("SOG fuzz: %d loaded, %d refused\n", loaded, rejected);
  EXPECT_GT(loaded, 0);
  EXPECT_GT(rejected, 0);
}

// The zipped bundle: mutated archives (headers, directory, entries) through the one entry point.
TEST(SogFuzz, MutatedBundlesLoadOrFailCleanly) {
  std::mt19937 rng(20241203);
  std::vector<std::string> seeds;
  for (int bands : {0, 2}) seeds.push_back(test::sog_bundle(test::random_sog_chunk(25, bands, rng)));
  int loaded = 0, rejected = 0;
  for (int round = 0; round < 1500; ++round) {
    const std::string file = mutate(seeds[rng() % seeds.size()], rng, 64);
    std::vector<char> copy(file.begin(), file.end());
    expect_clean([&] { return parse_scene_bytes(copy.data(), copy.size(), "fuzz.sog"); }, loaded, rejected);
  }
  std::printf("SOG bundle fuzz: %d loaded, %d refused\n", loaded, rejected);
  EXPECT_GT(loaded, 0);
  EXPECT_GT(rejected, 0);
}

// A random change to a LOD tree's leaves: ranges that move, grow, shrink, repeat or name
// another file or level; the readers must refuse any that no longer split the chunks exactly.
void spoil_tree(nlohmann::json& tree, std::mt19937& rng) {
  nlohmann::json& leaves = tree["children"];
  nlohmann::json& leaf = leaves[rng() % leaves.size()];
  nlohmann::json& range = leaf["lods"][rng() % 2 ? "0" : "1"];
  const auto any = [&rng]() -> nlohmann::json {
    switch (rng() % 4) {
      case 0: return static_cast<int>(rng() % 120) - 10;
      case 1: return std::uint64_t{1} << (rng() % 64);
      case 2: return "7";
      default: return static_cast<int>(rng() % 60);
    }
  };
  switch (rng() % 6) {
    case 0: range["offset"] = any(); break;
    case 1: range["count"] = any(); break;
    case 2: range["file"] = any(); break;
    case 3: leaves.push_back(leaf); break;  // the same ranges twice
    case 4: leaves.erase(rng() % leaves.size()); break;
    default: leaf["lods"][std::to_string(rng() % 4)] = range;
  }
}

TEST(SogLodFuzz, MutatedTreesLoadOrFailCleanly) {
  namespace fs = std::filesystem;
  std::mt19937 rng(20241203);
  const fs::path folder = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "fuzz_lod";
  fs::remove_all(folder);
  // Two levels of 40 and 12 Gaussians, each split between three leaves.
  const std::size_t counts[2] = {40, 12};
  for (int level = 0; level < 2; ++level) {
    const test::SogChunk chunk = test::random_sog_chunk(counts[level], level, rng);
    const fs::path dir = folder / (std::to_string(level) + "_0");
    fs::create_directories(dir);
    std::ofstream(dir / "meta.json") << chunk.meta.dump();
    for (const auto& [name, bytes] : chunk.files)
      std::ofstream(dir / name, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  }
  nlohmann::json good = {{"lodLevels", 2}, {"filenames", {"0_0/meta.json", "1_0/meta.json"}}};
  good["tree"]["children"] = nlohmann::json::array();
  const std::size_t splits[2][4] = {{0, 10, 25, 40}, {0, 4, 5, 12}};
  for (int leaf = 0; leaf < 3; ++leaf) {
    nlohmann::json lods;
    for (int level = 0; level < 2; ++level)
      lods[std::to_string(level)] = {{"file", level},
                                     {"offset", splits[level][leaf]},
                                     {"count", splits[level][leaf + 1] - splits[level][leaf]}};
    good["tree"]["children"].push_back({{"lods", lods}});
  }
  const std::string path = (folder / "lod-meta.json").string();
  int loaded = 0, rejected = 0;
  for (int round = 0; round < 600; ++round) {
    std::string text;
    if (round == 0) {
      text = good.dump();  // the seed itself loads
    } else if (rng() % 3) {
      nlohmann::json tree = good;
      for (int edits = 1 + static_cast<int>(rng() % 3); edits > 0; --edits) spoil_tree(tree["tree"], rng);
      text = tree.dump();
    } else {
      text = mutate(good.dump(), rng, 80);
    }
    std::ofstream(path, std::ios::trunc) << text;
    const int level = static_cast<int>(rng() % 2);
    expect_clean(
        [&] {
          const SogLodSet set = describe_sog_lod(path);
          const Scene scene = read_sog_lod(path, level);
          EXPECT_EQ(scene.size(), set.levels.at(level).gaussians);
          EXPECT_EQ(scene.size(), counts[level]) << text;  // a level that loads holds its chunk exactly
          return scene;
        },
        loaded, rejected);
  }
  std::printf("SOG LOD tree fuzz: %d loaded, %d refused\n", loaded, rejected);
  EXPECT_GT(loaded, 0);
  EXPECT_GT(rejected, 0);
}

}  // namespace
}  // namespace flashgs
