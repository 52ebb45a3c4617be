// The scene writers: every format written, read back through the one load entry point and
// written again as PLY, each attribute within the quantisation step its format states; the
// kernel marks carried; SPZ's axes; the SOG bundle equal to the SOG folder.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "flashgs/error.h"
#include "flashgs/io.h"
#include "flashgs/model_constants.h"
#include "flashgs/scene_formats.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& name) {
  const fs::path path = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "format_writers" / name;
  fs::create_directories(path.parent_path());
  return path.string();
}

// `n` random Gaussians at SH degree `degree`, their higher bands drawn from `prototypes`
// vectors (so that a palette of that many entries can hold them exactly), values inside every
// format's range (no clamping), marked as trained with the anti-aliased kernel.
Scene random_scene(std::size_t n, int degree, int prototypes, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto in = [&](float lo, float hi) { return lo + (hi - lo) * unit(rng); };
  Scene scene;
  scene.sh_degree = degree;
  const int rest = scene.sh_rest_per_gaussian();
  std::vector<float> table(static_cast<std::size_t>(prototypes * rest));
  for (float& v : table) v = in(-0.9f, 0.9f);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      scene.positions.push_back(in(-5, 5));
      scene.scales.push_back(std::exp(in(-6, 1)));
      scene.sh_dc.push_back(in(-1.5f, 1.5f));
    }
    float q[4], norm = 0;
    for (float& c : q) {
      c = in(-1, 1);
      norm += c * c;
    }
    for (float c : q) scene.rotations.push_back(c / std::sqrt(norm));
    scene.opacities.push_back(in(0, 1));
    const int p = static_cast<int>(rng() % static_cast<unsigned>(std::max(1, prototypes)));
    for (int c = 0; c < rest; ++c) scene.sh_rest.push_back(table[static_cast<std::size_t>(p * rest + c)]);
  }
  scene.trained_kernel = {SplatKernel::antialiased(), "test"};
  return scene;
}

// Writes `scene` as `name` (the name picks the format), reads it back, writes that as PLY and
// reads the PLY: what a user gets from PLY -> X -> PLY.
Scene through(const Scene& scene, const std::string& name, const SceneWriteOptions& options = {},
              const SceneReadOptions& read = {}) {
  const std::string path = scratch(name);
  save_scene_file(scene, path, options);
  const Scene back = load_scene_file(path, nullptr, nullptr, read);
  const std::string ply = scratch(name + ".back.ply");
  save_ply(back, ply);
  return load_ply(ply);
}

// The rotation as read back, turned to the written one's hemisphere (q and -q are one rotation).
std::vector<float> aligned_rotation(const Scene& original, const Scene& back, std::size_t i) {
  double dot = 0;
  for (int k = 0; k < 4; ++k) dot += double(original.rotations[i * 4 + k]) * back.rotations[i * 4 + k];
  std::vector<float> q(back.rotations.begin() + static_cast<std::ptrdiff_t>(i * 4),
                       back.rotations.begin() + static_cast<std::ptrdiff_t>(i * 4 + 4));
  if (dot < 0)
    for (float& c : q) c = -c;
  return q;
}

// Smallest-three: the three stored components within `half_step` (plus float rounding and the
// PLY's renormalisation); the rebuilt largest within a few steps.
void expect_rotations_within(const Scene& original, const Scene& back, double half_step, const std::string& what) {
  for (std::size_t i = 0; i < original.size(); ++i) {
    const float* q = &original.rotations[i * 4];
    int largest = 0;
    for (int k = 1; k < 4; ++k)
      if (std::abs(q[k]) > std::abs(q[largest])) largest = k;
    const std::vector<float> b = aligned_rotation(original, back, i);
    for (int k = 0; k < 4; ++k) {
      const double bound = k == largest ? 4 * half_step : half_step + 2e-6;
      ASSERT_LE(std::abs(double(b[k]) - q[k]), bound) << what << ": Gaussian " << i << " component " << k;
    }
  }
}

void expect_opacities_within(const Scene& original, const Scene& back, const std::string& what) {
  for (std::size_t i = 0; i < original.size(); ++i)
    ASSERT_NEAR(back.opacities[i], original.opacities[i], 0.5 / 255 + 1e-6) << what << ": Gaussian " << i;
}

TEST(FormatWriters, CompressedPlyRoundTripIsWithinHalfAStepOfEachChunksRange) {
  const Scene scene = random_scene(1000, 3, 1000, 1);  // 4 chunks, the last one partial
  const Scene back = through(scene, "scene.compressed.ply");
  ASSERT_EQ(back.size(), scene.size());
  ASSERT_EQ(back.sh_degree, 3);
  EXPECT_TRUE(back.trained_kernel.kernel.compensates_opacity()) << "the PLY comment carries the kernel";
  const int bits[3] = {11, 10, 11};
  for (std::size_t first = 0; first < scene.size(); first += 256) {
    const std::size_t last = std::min(scene.size(), first + 256);
    for (int k = 0; k < 3; ++k) {
      float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
      for (std::size_t i = first; i < last; ++i) {
        const float v[3] = {scene.positions[i * 3 + k], std::log(scene.scales[i * 3 + k]),
                            float(0.5 + model::kShC0 * scene.sh_dc[i * 3 + k])};
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], v[a]), hi[a] = std::max(hi[a], v[a]);
      }
      const double steps = (1 << bits[k]) - 1;
      for (std::size_t i = first; i < last; ++i) {
        ASSERT_NEAR(back.positions[i * 3 + k], scene.positions[i * 3 + k], (hi[0] - lo[0]) / steps / 2 + 1e-5);
        ASSERT_NEAR(std::log(back.scales[i * 3 + k]), std::log(scene.scales[i * 3 + k]),
                    (hi[1] - lo[1]) / steps / 2 + 1e-5);
        ASSERT_NEAR(back.sh_dc[i * 3 + k], scene.sh_dc[i * 3 + k], (hi[2] - lo[2]) / 255 / 2 / model::kShC0 + 1e-5);
      }
    }
  }
  expect_rotations_within(scene, back, std::sqrt(2.0) / 1023 / 2, "compressed PLY");
  expect_opacities_within(scene, back, "compressed PLY");
  for (std::size_t v = 0; v < scene.sh_rest.size(); ++v)  // 8 bits over [-4, 4]
    ASSERT_NEAR(back.sh_rest[v], scene.sh_rest[v], 4.0 / 256 + 1e-6) << v;
}

// SPZ: positions to half a step of the fixed point the writer picks, log-scales to 1/32,
// colours to half a byte of 0.15 f_dc, SH to half of 1/128.
void expect_spz_bounds(const Scene& scene, const Scene& back, const std::string& what) {
  ASSERT_EQ(back.size(), scene.size()) << what;
  float largest = 0;
  for (float p : scene.positions) largest = std::max(largest, std::abs(p));
  int bits = 24;
  while (std::round(largest * std::ldexp(1.0, bits)) > (1 << 23) - 1) --bits;
  const double half_step = std::ldexp(0.5, -bits);
  for (std::size_t v = 0; v < scene.positions.size(); ++v) {
    ASSERT_NEAR(back.positions[v], scene.positions[v], half_step + 1e-6) << what << " " << v;
    ASSERT_NEAR(std::log(back.scales[v]), std::log(scene.scales[v]), 1.0 / 32 + 1e-5) << what << " " << v;
    ASSERT_NEAR(back.sh_dc[v], scene.sh_dc[v], 0.5 / 255 / 0.15 + 1e-5) << what << " " << v;
  }
  for (std::size_t v = 0; v < scene.sh_rest.size(); ++v)
    ASSERT_NEAR(back.sh_rest[v], scene.sh_rest[v], 0.5 / 128 + 1e-6) << what << " " << v;
  expect_rotations_within(scene, back, std::sqrt(0.5) / 511 / 2, what);
  expect_opacities_within(scene, back, what);
  EXPECT_TRUE(back.trained_kernel.kernel.compensates_opacity()) << what << ": the antialiased flag";
}

TEST(FormatWriters, SpzVersions3And4RoundTripWithinTheirSteps) {
  const Scene scene = random_scene(700, 3, 700, 2);
  for (int version : {3, 4}) {
    SceneWriteOptions options;
    options.spz_version = version;
    expect_spz_bounds(scene, through(scene, "v" + std::to_string(version) + ".spz", options),
                      "SPZ v" + std::to_string(version));
  }
  // Version 3 is one gzip stream, version 4 starts with the magic.
  std::ifstream v3(scratch("v3.spz"), std::ios::binary), v4(scratch("v4.spz"), std::ios::binary);
  char a[4] = {}, b[4] = {};
  v3.read(a, 4);
  v4.read(b, 4);
  EXPECT_EQ(std::string(a, 2), "\x1f\x8b");
  EXPECT_EQ(std::string(b, 4), "NGSP");
}

TEST(FormatWriters, SpzAxesAreChosenOnWritingAndOnReading) {
  const Scene scene = random_scene(300, 2, 300, 3);
  SceneWriteOptions plain;
  plain.spz_axes = SpzAxes::none;
  SceneReadOptions read_plain;
  read_plain.spz_axes = SpzAxes::none;
  // Each setting round-trips on its own...
  expect_spz_bounds(scene, through(scene, "niantic.spz"), "niantic axes");
  expect_spz_bounds(scene, through(scene, "plain.spz", plain, read_plain), "PLY axes");
  // ...and a file read with the other one is the scene turned 180 degrees about x.
  const Scene turned = load_scene_file(scratch("plain.spz"));
  for (std::size_t i = 0; i < scene.size(); ++i) {
    ASSERT_NEAR(turned.positions[i * 3], scene.positions[i * 3], 1e-3);
    ASSERT_NEAR(turned.positions[i * 3 + 1], -scene.positions[i * 3 + 1], 1e-3);
    ASSERT_NEAR(turned.positions[i * 3 + 2], -scene.positions[i * 3 + 2], 1e-3);
  }
  SpzAxes axes;
  EXPECT_TRUE(parse_spz_axes("none", axes) && axes == SpzAxes::none);
  EXPECT_FALSE(parse_spz_axes("opengl", axes));
}

// Index of the entry of `book` nearest to `v`.
float nearest(const std::vector<float>& book, float v) {
  float best = book[0];
  for (float b : book)
    if (std::abs(b - v) < std::abs(best - v)) best = b;
  return best;
}

TEST(FormatWriters, SogRoundTripDecodesToTheNearestCodebookEntries) {
  // 16 distinct SH vectors: the palette holds them exactly, only the codebook rounds them.
  const Scene scene = random_scene(2000, 3, 16, 4);
  const Scene back = through(scene, "sog/meta.json");
  ASSERT_EQ(back.size(), scene.size());
  ASSERT_EQ(back.sh_degree, 3);
  EXPECT_TRUE(back.trained_kernel.kernel.compensates_opacity()) << "meta.json's model carries the kernel";
  std::ifstream meta_file(scratch("sog/meta.json"));
  const nlohmann::json meta = nlohmann::json::parse(meta_file);
  EXPECT_EQ(meta.at("version"), 2);
  const auto scales = meta.at("scales").at("codebook").get<std::vector<float>>();
  const auto colours = meta.at("sh0").at("codebook").get<std::vector<float>>();
  const auto bands = meta.at("shN").at("codebook").get<std::vector<float>>();
  for (int k = 0; k < 3; ++k) {
    const double lo = meta.at("means").at("mins")[k], hi = meta.at("means").at("maxs")[k];
    const double half_step = (hi - lo) / 65535 / 2;  // in sign(x) ln(|x| + 1)
    for (std::size_t i = 0; i < scene.size(); ++i) {
      const double x = scene.positions[i * 3 + k];
      ASSERT_NEAR(back.positions[i * 3 + k], x, (std::abs(x) + 1) * std::expm1(half_step) + 1e-5) << i;
    }
  }
  for (std::size_t v = 0; v < scene.scales.size(); ++v) {
    ASSERT_NEAR(std::log(back.scales[v]), nearest(scales, std::log(scene.scales[v])), 1e-5) << v;
    ASSERT_NEAR(back.sh_dc[v], nearest(colours, scene.sh_dc[v]), 1e-6) << v;
  }
  for (std::size_t v = 0; v < scene.sh_rest.size(); ++v)
    ASSERT_NEAR(back.sh_rest[v], nearest(bands, scene.sh_rest[v]), 1e-6) << v;
  expect_rotations_within(scene, back, std::sqrt(2.0) / 255 / 2, "SOG");
  expect_opacities_within(scene, back, "SOG");

  // The zipped bundle holds the same textures: it decodes to the same Gaussians.
  save_scene_file(scene, scratch("scene.sog"));
  const Scene bundle = load_scene_file(scratch("scene.sog"));
  const Scene folder = load_scene_file(scratch("sog/meta.json"));
  EXPECT_EQ(bundle.positions, folder.positions);
  EXPECT_EQ(bundle.rotations, folder.rotations);
  EXPECT_EQ(bundle.sh_rest, folder.sh_rest);
  EXPECT_EQ(bundle.opacities, folder.opacities);
}

TEST(FormatWriters, TheNamePicksTheWriter) {
  EXPECT_EQ(writable_format_for("a/b.compressed.ply")->format, SceneFormat::compressed_ply);
  EXPECT_EQ(writable_format_for("a/b.PLY")->format, SceneFormat::inria_ply);
  EXPECT_EQ(writable_format_for("b.spz")->format, SceneFormat::spz);
  EXPECT_EQ(writable_format_for("b.sog")->format, SceneFormat::sog_bundle);
  EXPECT_EQ(writable_format_for("x/meta.json")->format, SceneFormat::sog);
  EXPECT_EQ(writable_format_for("b.splat")->format, SceneFormat::splat);
  EXPECT_EQ(writable_format_for("b.obj"), nullptr);
  const Scene scene = random_scene(10, 0, 1, 5);
  try {
    save_scene_file(scene, scratch("b.obj"));
    ADD_FAILURE() << "an unknown name was written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown scene format"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(scratch("b.obj")));
}

// Every real scene through every format and back to PLY, each within its format's bounds
// where they are fixed steps (SOG's codebooks are checked above).
TEST(FormatWriters, RealScenesRoundTripThroughEveryFormat) {
  const std::string dir = test::shared_scene_dir("kacytran_try");
  if (dir.empty()) GTEST_SKIP() << "../shared/scenes is absent";
  for (const std::string& name : {"kacytran_try", "pc_guitar"}) {
    const Scene scene = *test::load_shared_scene(name);
    SceneWriteOptions options;
    const Scene spz = through(scene, name + ".spz", options);
    ASSERT_EQ(spz.size(), scene.size()) << name;
    const Scene cply = through(scene, name + ".compressed.ply");
    ASSERT_EQ(cply.size(), scene.size()) << name;
    expect_opacities_within(scene, cply, name + " compressed PLY");
    expect_opacities_within(scene, spz, name + " SPZ");
    const Scene sog = through(scene, name + ".sog");
    ASSERT_EQ(sog.size(), scene.size()) << name;
    expect_opacities_within(scene, sog, name + " SOG");
    EXPECT_EQ(sog.sh_degree, scene.sh_degree) << name;
  }
}

}  // namespace
}  // namespace flashgs
