// SPZ and SOG v2 readers: the shared samples against their INRIA twins (values and CPU images),
// every SOG LOD level, hand-checked values, and hostile files (one clear message each).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "compressed_builders.h"
#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"
#include "flashgs/renderer.h"
#include "flashgs/scene_formats.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

// ../shared/scenes/formats, the compressed samples (see its README); empty when absent.
std::string formats_dir() {
  const fs::path dir = fs::path(FLASHGS_SHARED_SCENES) / "formats";
  return fs::exists(dir / "biker.spz") ? dir.string() : std::string();
}

// Skips a test whose sample or twin is absent.
#define REQUIRE_SAMPLES(twin)                                                                 \
  do {                                                                                        \
    if (formats_dir().empty() || test::shared_scene_dir(twin).empty())                        \
      GTEST_SKIP() << "../shared/scenes/formats or " << twin << " is absent: sample test skipped"; \
  } while (0)

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Image render_small(std::shared_ptr<const Scene> scene, const Camera& camera) {
  auto renderer = make_cpu_renderer();
  renderer->set_scene(std::move(scene));
  Image image;
  renderer->render(camera, RenderOptions{}, image, nullptr);
  return image;
}

// The rotation error of two unit quaternions, sign-free (q and -q are one rotation).
double quaternion_error(const float* a, const float* b) {
  double same = 0, opposite = 0;
  for (int k = 0; k < 4; ++k) {
    same = std::max(same, double(std::abs(a[k] - b[k])));
    opposite = std::max(opposite, double(std::abs(a[k] + b[k])));
  }
  return std::min(same, opposite);
}

// The message of the flashgs::Error that `load` throws; fails the test when none is thrown.
template <typename Load>
std::string error_of(Load load) {
  try {
    load();
  } catch (const LoadCancelled&) {
    ADD_FAILURE() << "cancelled instead of refused";
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "the hostile input loaded";
  return "";
}

// ---------------------------------------------------------------- SPZ against its twin

// biker.spz (version 4) holds pc_biker's Gaussians in the same order, quantised: positions to
// 2^-fractional_bits (error <= half a step), log scales to 1/16, opacity to 1/255, f_dc to
// 1/(255 * 0.15), each clamped to its byte's range; rotations as smallest-three with 9 bits.
TEST(SpzTwin, BikerMatchesPcBikerWithinTheQuantisation) {
  REQUIRE_SAMPLES("pc_biker");
  const auto start = std::chrono::steady_clock::now();
  LoadReport report;
  const Scene spz = read_spz(formats_dir() + "/biker.spz", &report);
  std::printf("biker.spz decoded in %.3f s\n", seconds_since(start));
  const auto twin = test::load_shared_scene("pc_biker");
  ASSERT_EQ(spz.size(), twin->size());
  ASSERT_EQ(spz.sh_degree, twin->sh_degree);
  EXPECT_EQ(report.vertices_in_file, twin->size());
  const double position_step = 1.0 / 4096;  // the file's 12 fractional bits
  double position = 0, log_scale = 0, opacity = 0, dc = 0, rotation = 0;
  for (std::size_t i = 0; i < spz.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const std::size_t j = i * 3 + k;
      position = std::max(position, double(std::abs(spz.positions[j] - twin->positions[j])));
      const double twin_log = std::clamp(std::log(double(twin->scales[j])), -10.0, -10.0 + 255.0 / 16);
      log_scale = std::max(log_scale, std::abs(std::log(double(spz.scales[j])) - twin_log));
      const double twin_dc = std::clamp(double(twin->sh_dc[j]), -0.5 / 0.15, 0.5 / 0.15);
      dc = std::max(dc, std::abs(spz.sh_dc[j] - twin_dc));
    }
    opacity = std::max(opacity, double(std::abs(spz.opacities[i] - twin->opacities[i])));
    rotation = std::max(rotation, quaternion_error(&spz.rotations[i * 4], &twin->rotations[i * 4]));
  }
  std::printf("largest errors: position %.3g (bound %.3g), log scale %.3g (1/32), opacity %.3g (0.5/255), "
              "f_dc %.3g (%.3g), quaternion component %.3g\n",
              position, position_step / 2, log_scale, opacity, dc, 0.5 / (255 * 0.15), rotation);
  EXPECT_LE(position, position_step / 2 + 1e-5);
  EXPECT_LE(log_scale, 1.0 / 32 + 1e-5);
  EXPECT_LE(opacity, 0.5 / 255 + 1e-6);
  EXPECT_LE(dc, 0.5 / (255 * 0.15) + 1e-5);
  // 9-bit magnitudes in [0, 1/sqrt 2]: half a step is 6.9e-4 per stored component; the rebuilt
  // largest one and the renormalisation at most double that.
  EXPECT_LE(rotation, 1.5e-3);
}

TEST(SpzTwin, BikerRendersLikePcBiker) {
  REQUIRE_SAMPLES("pc_biker");
  const auto spz = std::make_shared<const Scene>(read_spz(formats_dir() + "/biker.spz"));
  const Camera camera = test::load_shared_cameras("pc_biker").at(0).resized(160, 120);
  const ImageDifference d = compare_images(render_small(spz, camera), render_small(test::load_shared_scene("pc_biker"), camera));
  std::printf("biker.spz vs pc_biker at 160x120: PSNR %.1f dB, max |difference| %.3g\n", d.psnr_db, d.max_abs);
  EXPECT_EQ(d.non_finite, 0u);
  EXPECT_GE(d.psnr_db, 35.0);
}

// The same attribute bytes in a gzip stream (versions 1-3) decode to the same Gaussians.
TEST(SpzTwin, BikerAsGzipVersion3DecodesLikeVersion4) {
  REQUIRE_SAMPLES("pc_biker");
  const std::string path = formats_dir() + "/biker.spz";
  test::SpzContent content = test::spz_v4_content(read_regular_file(path));
  content.version = 3;
  const std::string gz = test::spz_gzip_file(content);
  const Scene v3 = parse_spz(gz.data(), gz.size(), "biker-v3.spz");
  const Scene v4 = read_spz(path);
  EXPECT_EQ(v3.positions, v4.positions);
  EXPECT_EQ(v3.rotations, v4.rotations);
  EXPECT_EQ(v3.scales, v4.scales);
  EXPECT_EQ(v3.opacities, v4.opacities);
  EXPECT_EQ(v3.sh_dc, v4.sh_dc);
}

// ---------------------------------------------------------------- SPZ by hand

// One Gaussian whose bytes are chosen so each value is known: x = 1 (4096 at 12 bits),
// y = -0.5 stored (+0.5 once flipped to PLY axes), z = 0; opacity 255; colour 128; scale
// byte 160 (log 0); rotation: largest = w (index 3), the rest 0, i.e. identity.
TEST(Spz, DecodesHandCheckedValuesInPlyAxes) {
  test::SpzContent c;
  c.count = 1;
  c.sh_degree = 1;
  c.attribute[0] = {0x00, 0x10, 0x00, 0x00, 0xf8, 0xff, 0x00, 0x00, 0x00};  // 4096, -2048, 0
  c.attribute[1] = {255};
  c.attribute[2] = {128, 128, 128};
  c.attribute[3] = {160, 160, 176};
  c.attribute[4] = {0x00, 0x00, 0x00, 0xc0};  // largest index 3 in the top two bits
  c.attribute[5] = {128, 128, 128, 192, 192, 192, 64, 64, 64};  // SH1: 0, +0.5, -0.5 per channel
  for (const std::string& file : {test::spz_gzip_file(c), test::spz_v4_file(c)}) {
    const Scene s = parse_spz(file.data(), file.size(), "hand.spz");
    ASSERT_EQ(s.size(), 1u);
    EXPECT_FLOAT_EQ(s.positions[0], 1.0f);
    EXPECT_FLOAT_EQ(s.positions[1], 0.5f);
    EXPECT_FLOAT_EQ(s.positions[2], 0.0f);
    EXPECT_FLOAT_EQ(s.opacities[0], 1.0f);
    EXPECT_NEAR(s.sh_dc[0], (128 / 255.0 - 0.5) / 0.15, 1e-6);
    EXPECT_FLOAT_EQ(s.scales[0], 1.0f);
    EXPECT_NEAR(s.scales[2], std::exp(1.0), 1e-5);
    EXPECT_EQ(s.rotations, (std::vector<float>{1, 0, 0, 0}));
    // Basis functions y and z change sign with the axes, x does not.
    EXPECT_FLOAT_EQ(s.sh_rest[0], -0.0f);
    EXPECT_FLOAT_EQ(s.sh_rest[3], -0.5f);
    EXPECT_FLOAT_EQ(s.sh_rest[6], -0.5f);
  }
}

TEST(Spz, IsRecognisedByItsMagicInsideTheGzipStream) {
  std::mt19937 rng(2);
  const test::SpzContent c = test::random_spz(3, 0, 3, rng);
  const std::string spz = test::spz_gzip_file(c), v4 = test::spz_v4_file(c), other_gzip = test::gzip("hello, world");
  EXPECT_TRUE(looks_like_spz(spz.data(), spz.size()));
  EXPECT_TRUE(looks_like_spz(v4.data(), v4.size()));
  EXPECT_FALSE(looks_like_spz(other_gzip.data(), other_gzip.size()));
  EXPECT_FALSE(looks_like_spz("ply\n", 4));
}

TEST(Spz, EveryVersionReadsRandomContent) {
  std::mt19937 rng(7);
  for (std::uint32_t version = 1; version <= 4; ++version)
    for (int degree = 0; degree <= 3; ++degree) {
      const test::SpzContent c = test::random_spz(50, degree, version, rng);
      const std::string file = version == 4 ? test::spz_v4_file(c) : test::spz_gzip_file(c);
      const Scene s = parse_spz(file.data(), file.size(), "random.spz");
      EXPECT_EQ(s.size(), 50u) << "version " << version;
      EXPECT_EQ(s.sh_degree, degree);
      for (std::size_t i = 0; i < s.size(); ++i) {
        const float* q = &s.rotations[i * 4];
        EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-5);
      }
    }
}

// The header's antialiased flag (bit 0) names gsplat's anti-aliased kernel, in every version.
TEST(Spz, AntialiasedFlagNamesTheKernel) {
  std::mt19937 rng(11);
  for (std::uint32_t version : {2u, 3u, 4u})
    for (std::uint8_t flags : {std::uint8_t{0}, std::uint8_t{1}}) {
      test::SpzContent c = test::random_spz(20, 0, version, rng);
      c.flags = flags;
      const std::string file = version == 4 ? test::spz_v4_file(c) : test::spz_gzip_file(c);
      const Scene s = parse_spz(file.data(), file.size(), "flag.spz");
      EXPECT_EQ(s.trained_kernel.kernel, flags ? SplatKernel::antialiased() : SplatKernel::classic()) << version;
      EXPECT_EQ(s.trained_kernel.marked(), flags != 0) << version;
    }
}

TEST(Spz, ReportsProgressAndStopsWhenCancelled) {
  std::mt19937 rng(3);
  const test::SpzContent c = test::random_spz(100000, 1, 3, rng);
  const std::string file = test::spz_gzip_file(c);
  LoadProgress progress;
  parse_spz(file.data(), file.size(), "progress.spz", nullptr, &progress);
  EXPECT_EQ(progress.bytes_done.load(), file.size());
  EXPECT_EQ(progress.bytes_total.load(), file.size());
  EXPECT_EQ(progress.gaussians_done.load(), 100000u);
  EXPECT_EQ(progress.gaussians_total.load(), 100000u);
  LoadProgress cancelled;
  cancelled.cancel_requested = true;
  EXPECT_THROW(parse_spz(file.data(), file.size(), "progress.spz", nullptr, &cancelled), LoadCancelled);
}

// ---------------------------------------------------------------- SPZ hostile input

struct HostileSpz {
  const char* what;
  std::string bytes;
  const char* expected;  // part of the message
};

TEST(Spz, HostileFilesGetOneClearMessage) {
  std::mt19937 rng(11);
  const test::SpzContent good = test::random_spz(64, 1, 3, rng);
  const std::string gz = test::spz_gzip_file(good);
  std::vector<HostileSpz> cases = {
      {"empty", "", "empty"},
      {"a PLY", "ply\nformat ascii 1.0\n", "not an SPZ file"},
      {"truncated gzip", gz.substr(0, gz.size() / 2), "truncated"},
      {"gzip of junk", std::string("\x1f\x8b") + std::string(100, 'x'), "gzip"},
  };
  {  // A bomb: 10 Gaussians declared, 64 MB of zeros after them.
    test::SpzContent bomb = test::random_spz(10, 0, 3, rng);
    bomb.attribute[5].assign(64 << 20, 0);
    cases.push_back({"gzip bomb", test::spz_gzip_file(bomb), "gzip bomb"});
  }
  {
    test::SpzContent lie = good;
    lie.count = 0xffffffffu;
    cases.push_back({"absurd count", test::spz_gzip_file(lie), "cannot hold"});
    lie.count = 1000;
    cases.push_back({"count larger than the data", test::spz_gzip_file(lie), "truncated"});
  }
  {
    test::SpzContent bad = good;
    bad.version = 9;
    cases.push_back({"unknown version", test::spz_gzip_file(bad), "version 9"});
    bad = good;
    bad.sh_degree = 7;
    cases.push_back({"SH degree 7", test::spz_gzip_file(bad), "SH degree 7"});
  }
  {
    std::string wrong_magic = test::spz_payload(good);
    wrong_magic[0] = 'X';
    cases.push_back({"wrong magic in the gzip", test::gzip(wrong_magic), "NGSP"});
  }
  const std::string v4 = test::spz_v4_file(good);
  cases.push_back({"truncated v4", v4.substr(0, v4.size() - 100), "truncated"});
  cases.push_back({"v4 with junk after it", v4 + "junk", "junk"});
  {
    std::string toc = v4;
    toc[19] = '\x7f';  // the table of contents far past the end
    cases.push_back({"v4 table of contents outside", toc, "table of contents"});
    std::string sizes = v4;
    sizes[32 + 8] ^= 1;  // the positions' uncompressed size
    cases.push_back({"v4 stream size lies", sizes, "declares"});
    std::string frame = v4;
    frame[32 + 6 * 16 + 6] ^= 0x55;  // inside the first zstd frame's header
    cases.push_back({"v4 corrupt zstd", frame, "positions"});
  }
  for (const HostileSpz& c : cases) {
    const std::string message = error_of([&] { parse_spz(c.bytes.data(), c.bytes.size(), "bad.spz"); });
    EXPECT_EQ(message.rfind("bad.spz: ", 0), 0u) << c.what << ": " << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << c.what;
  }
}

// A gzip stream whose own header is corrupt is an SPZ file that is corrupt, not "no scene file".
TEST(Spz, CorruptGzipHeaderIsSaidSo) {
  std::mt19937 rng(5);
  std::string file = test::spz_gzip_file(test::random_spz(4, 0, 3, rng));
  file[2] = 7;  // the compression method: 8 is deflate
  EXPECT_TRUE(looks_like_spz(file.data(), file.size()));
  const std::string message = error_of([&] { parse_scene_bytes(file.data(), file.size(), "bad.spz"); });
  EXPECT_EQ(message.rfind("bad.spz: ", 0), 0u) << message;
  EXPECT_NE(message.find("gzip data is corrupt"), std::string::npos) << message;
}

// A zstd frame (one raw block of `data`) whose header asks for a window of 2^window_log bytes.
std::string zstd_frame_with_window(const std::vector<std::uint8_t>& data, int window_log) {
  std::string frame = "\x28\xb5\x2f\xfd";
  frame.push_back(0);                                         // no content size, no checksum
  frame.push_back(static_cast<char>((window_log - 10) << 3));  // window descriptor: exponent only
  const std::uint32_t block = static_cast<std::uint32_t>(data.size()) << 3 | 1;  // raw, last
  for (int i = 0; i < 3; ++i) frame.push_back(static_cast<char>(block >> (8 * i) & 0xff));
  return frame + std::string(data.begin(), data.end());
}

// The 128 MB window limit is a size limit, and the message says so.
TEST(Spz, ZstdWindowAboveTheLimitIsSaidTooLarge) {
  std::mt19937 rng(6);
  const test::SpzContent c = test::random_spz(3, 0, 4, rng);
  const std::string good = test::spz_v4_file(c);
  // Replace the positions' frame (the first) by one of the same bytes that asks for 256 MB.
  const auto u64 = [&good](std::size_t at) {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = v << 8 | static_cast<unsigned char>(good[at + i]);
    return v;
  };
  const std::size_t frames_at = 32 + 5 * 16, first = static_cast<std::size_t>(u64(32));
  for (int window_log : {27, 28}) {
    const std::string frame = zstd_frame_with_window(c.attribute[0], window_log);
    std::string file = good.substr(0, frames_at) + frame + good.substr(frames_at + first);
    for (int i = 0; i < 8; ++i) file[32 + i] = static_cast<char>(std::uint64_t(frame.size()) >> (8 * i) & 0xff);
    if (window_log == 27) {  // at the limit: read
      EXPECT_EQ(parse_spz(file.data(), file.size(), "window.spz").size(), 3u);
      continue;
    }
    const std::string message = error_of([&] { parse_spz(file.data(), file.size(), "window.spz"); });
    EXPECT_NE(message.find("window larger than the 128 MB"), std::string::npos) << message;
    EXPECT_EQ(message.find("corrupt"), std::string::npos) << message;
  }
}

// ---------------------------------------------------------------- SOG against its twin

std::string playbot() { return formats_dir() + "/playbot_sog"; }

// LOD 0 of playbot_sog is pc_playbot: the same Gaussians in the same order, values equal (the
// rotation and opacity to float rounding, as the twin stores them before normalising).
TEST(SogTwin, PlaybotLod0IsPcPlaybot) {
  REQUIRE_SAMPLES("pc_playbot");
  const auto start = std::chrono::steady_clock::now();
  const Scene sog = read_sog(playbot() + "/0_0");
  std::printf("playbot_sog/0_0 decoded in %.3f s\n", seconds_since(start));
  const auto twin = test::load_shared_scene("pc_playbot");
  ASSERT_EQ(sog.size(), twin->size());
  ASSERT_EQ(sog.sh_degree, twin->sh_degree);
  EXPECT_EQ(sog.positions, twin->positions);
  EXPECT_EQ(sog.scales, twin->scales);
  EXPECT_EQ(sog.sh_dc, twin->sh_dc);
  EXPECT_EQ(sog.sh_rest, twin->sh_rest);
  double rotation = 0, opacity = 0;
  for (std::size_t i = 0; i < sog.size(); ++i) {
    rotation = std::max(rotation, quaternion_error(&sog.rotations[i * 4], &twin->rotations[i * 4]));
    opacity = std::max(opacity, double(std::abs(sog.opacities[i] - twin->opacities[i])));
  }
  std::printf("largest differences: quaternion component %.3g, opacity %.3g\n", rotation, opacity);
  EXPECT_LE(rotation, 2.5e-7);
  EXPECT_LE(opacity, 1.2e-7);
}

TEST(SogTwin, PlaybotLod0RendersLikePcPlaybot) {
  REQUIRE_SAMPLES("pc_playbot");
  const auto sog = std::make_shared<const Scene>(read_sog(playbot() + "/0_0/meta.json"));
  const Camera camera = test::load_shared_cameras("pc_playbot").at(0).resized(160, 120);
  const ImageDifference d =
      compare_images(render_small(sog, camera), render_small(test::load_shared_scene("pc_playbot"), camera));
  std::printf("playbot_sog LOD 0 vs pc_playbot at 160x120: PSNR %.1f dB, max |difference| %.3g\n", d.psnr_db,
              d.max_abs);
  EXPECT_LE(d.max_abs, 1e-5);
}

TEST(SogLod, PlaybotDescribesSevenLevelsAndEachLoadsItsCount) {
  REQUIRE_SAMPLES("pc_playbot");
  const SogLodSet set = describe_sog_lod(playbot());
  ASSERT_EQ(set.levels.size(), 7u);
  std::size_t previous = std::numeric_limits<std::size_t>::max();
  for (const SogLodLevel& level : set.levels) {
    const auto start = std::chrono::steady_clock::now();
    LoadReport report;
    const Scene scene = read_sog_lod(set.path, level.level, &report);
    std::printf("level %d: %zu Gaussians, SH %d, decoded in %.3f s\n", level.level, scene.size(), scene.sh_degree,
                seconds_since(start));
    EXPECT_EQ(scene.size(), level.gaussians);
    EXPECT_EQ(scene.sh_degree, level.sh_degree);
    EXPECT_LT(level.gaussians, previous) << "levels go from fine to coarse";
    previous = level.gaussians;
    // Every Gaussian lies inside the tree's bound.
    for (std::size_t i = 0; i < scene.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        ASSERT_GE(scene.positions[i * 3 + k], set.bounds_min[k] - 1e-4f) << "level " << level.level;
        ASSERT_LE(scene.positions[i * 3 + k], set.bounds_max[k] + 1e-4f) << "level " << level.level;
      }
  }
  const Scene finest = read_sog_lod(playbot() + "/lod-meta.json", 0);
  EXPECT_EQ(finest.positions, read_sog(playbot() + "/0_0").positions);
}

TEST(SogLod, DefaultLevelIsTheFinestThatFits) {
  SogLodSet set;
  for (int level = 0; level < 3; ++level) set.levels.push_back({level, std::size_t(1000) >> level, 2, {}});
  const std::uint64_t finest = sog_lod_level_bytes(set.levels[0]), middle = sog_lod_level_bytes(set.levels[1]);
  EXPECT_EQ(choose_sog_lod_level(set, 0), 0);  // unknown memory: the finest
  EXPECT_EQ(choose_sog_lod_level(set, 2 * finest), 0);
  EXPECT_EQ(choose_sog_lod_level(set, 2 * finest - 1), 1);
  EXPECT_EQ(choose_sog_lod_level(set, 2 * middle - 1), 2);
  // None fits: refused with the figures, not the coarsest taken anyway.
  set.path = "set/lod-meta.json";
  const std::string message = error_of([&] { choose_sog_lod_level(set, 1); });
  EXPECT_EQ(message.rfind("set/lod-meta.json: no level fits", 0), 0u) << message;
  EXPECT_NE(message.find("250 Gaussians"), std::string::npos) << message;
}

// ---------------------------------------------------------------- SOG by hand

// One Gaussian with chosen pixels: position t = 1 (65535) on x, 0 on y, 0x8000/65535 on z
// through the log-domain range; quaternion mode 252 (rot_0 = w omitted) with the stored
// x = y = z at byte 128; codebook entries by index.
TEST(Sog, DecodesHandCheckedValues) {
  std::mt19937 rng(1);
  test::SogChunk chunk = test::random_sog_chunk(1, 0, rng, 4);
  auto pixel = [&](const char* file, std::uint8_t r, std::uint8_t g, std::uint8_t b, std::uint8_t a) {
    test::SogTexture t{4, 1, std::vector<std::uint8_t>(16, 0)};
    t.rgba[0] = r, t.rgba[1] = g, t.rgba[2] = b, t.rgba[3] = a;
    chunk.files[file] = test::lossless_webp(t);
  };
  pixel("means_l.webp", 0xff, 0x00, 0x00, 255);
  pixel("means_u.webp", 0xff, 0x00, 0x80, 255);
  pixel("quats.webp", 128, 128, 128, 252);
  pixel("scales.webp", 0, 255, 51, 255);
  pixel("sh0.webp", 0, 255, 3, 51);
  const Scene s = chunk.parse();
  ASSERT_EQ(s.size(), 1u);
  auto unlog = [](double n) { return n < 0 ? -(std::exp(-n) - 1) : std::exp(n) - 1; };
  EXPECT_FLOAT_EQ(s.positions[0], float(unlog(1.0)));   // maxs[0]
  EXPECT_FLOAT_EQ(s.positions[1], float(unlog(-2.0)));  // mins[1]
  EXPECT_FLOAT_EQ(s.positions[2], float(unlog(-0.5 + 2.5 * (0x8000 / 65535.0))));
  const double c = (128 / 255.0 - 0.5) * 2 / std::sqrt(2.0);
  const double w = std::sqrt(1 - 3 * c * c);
  EXPECT_NEAR(s.rotations[0], w, 1e-6);
  EXPECT_NEAR(s.rotations[1], c, 1e-6);
  EXPECT_FLOAT_EQ(s.scales[0], float(std::exp(-8.0)));
  EXPECT_FLOAT_EQ(s.scales[1], float(std::exp(-1.0)));
  EXPECT_FLOAT_EQ(s.scales[2], float(std::exp(-8.0 + 7.0 * 51 / 255)));
  EXPECT_FLOAT_EQ(s.sh_dc[0], -2.0f);
  EXPECT_FLOAT_EQ(s.sh_dc[1], 3.0f);
  EXPECT_FLOAT_EQ(s.opacities[0], 51 / 255.0f);
}

TEST(Sog, ReadsRandomChunksOfEveryBandCount) {
  std::mt19937 rng(5);
  for (int bands = 0; bands <= 3; ++bands) {
    const test::SogChunk chunk = test::random_sog_chunk(300, bands, rng);
    const Scene s = chunk.parse();
    EXPECT_EQ(s.size(), 300u);
    EXPECT_EQ(s.sh_degree, bands);
  }
}

// A chunk on disk: progress counts its texture bytes and Gaussians, and a cancel request stops it.
// meta.json's optional "model" names the kernel; an unknown one is refused with one line.
TEST(Sog, ModelEntryNamesTheKernel) {
  std::mt19937 rng(12);
  test::SogChunk chunk = test::random_sog_chunk(10, 0, rng);
  EXPECT_FALSE(chunk.parse().trained_kernel.marked());
  chunk.meta["model"] = "antialiased";
  EXPECT_EQ(chunk.parse().trained_kernel.kernel, SplatKernel::antialiased());
  chunk.meta["model"] = "default";
  const Scene classic = chunk.parse();
  EXPECT_EQ(classic.trained_kernel.kernel, SplatKernel::classic());
  EXPECT_TRUE(classic.trained_kernel.marked());
  chunk.meta["model"] = "2dgs";
  const std::string message = error_of([&] { chunk.parse(); });
  EXPECT_EQ(message.rfind("chunk/meta.json: ", 0), 0u) << message;
  EXPECT_NE(message.find("model"), std::string::npos) << message;
}

TEST(Sog, ReportsProgressAndStopsWhenCancelled) {
  std::mt19937 rng(17);
  const test::SogChunk chunk = test::random_sog_chunk(70000, 1, rng);
  const fs::path folder = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "sog_progress";
  fs::create_directories(folder);
  std::ofstream(folder / "meta.json") << chunk.meta.dump();
  std::uint64_t texture_bytes = 0;
  for (const auto& [name, bytes] : chunk.files) {
    std::ofstream(folder / name, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    texture_bytes += bytes.size();
  }
  LoadProgress progress;
  EXPECT_EQ(read_sog(folder.string(), nullptr, &progress).size(), 70000u);
  EXPECT_EQ(progress.bytes_total.load(), texture_bytes);
  EXPECT_EQ(progress.bytes_done.load(), texture_bytes);
  EXPECT_EQ(progress.gaussians_total.load(), 70000u);
  EXPECT_EQ(progress.gaussians_done.load(), 70000u);
  LoadProgress cancelled;
  cancelled.cancel_requested = true;
  EXPECT_THROW(read_sog(folder.string(), nullptr, &cancelled), LoadCancelled);
}

// ---------------------------------------------------------------- SOG hostile input

TEST(Sog, HostileChunksGetOneClearMessage) {
  std::mt19937 rng(9);
  const test::SogChunk good = test::random_sog_chunk(100, 1, rng);
  struct Case {
    const char* what;
    std::function<void(test::SogChunk&)> spoil;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"missing texture", [](test::SogChunk& c) { c.files.erase("quats.webp"); }, "quats.webp: cannot open"},
      {"texture of the wrong size",
       [](test::SogChunk& c) { c.files["means_u.webp"] = test::lossless_webp({4, 4, std::vector<std::uint8_t>(64, 1)}); },
       "means_u.webp: the image is 4x4"},
      {"palette of the wrong size",
       [](test::SogChunk& c) { c.files["shN_centroids.webp"] = c.files["sh0.webp"]; }, "SH palette needs"},
      {"not a WebP", [](test::SogChunk& c) { c.files["sh0.webp"] = {'P', 'N', 'G'}; }, "sh0.webp: not a WebP"},
      {"truncated WebP",
       [](test::SogChunk& c) { c.files["scales.webp"].resize(c.files["scales.webp"].size() / 2); }, "scales.webp"},
      {"lossy WebP",
       [](test::SogChunk& c) { c.files["means_l.webp"] = test::lossy_webp({12, 12, std::vector<std::uint8_t>(576, 9)}); },
       "lossy"},
      {"bad quaternion mode",
       [](test::SogChunk& c) { c.files["quats.webp"] = c.files["sh0.webp"]; }, "quaternion mode"},
      {"label beyond the palette", [](test::SogChunk& c) { c.meta["shN"]["count"] = 1;
         c.files["shN_centroids.webp"] = test::lossless_webp({192, 1, std::vector<std::uint8_t>(768, 0)});
         c.files["shN_labels.webp"] = test::lossless_webp({12, 9, std::vector<std::uint8_t>(432, 255)}); },
       "palette label"},
      {"version 3", [](test::SogChunk& c) { c.meta["version"] = 3; }, "SOG version 3"},
      {"count 0", [](test::SogChunk& c) { c.meta["count"] = 0; }, "count"},
      {"absurd count", [](test::SogChunk& c) { c.meta["count"] = 1e15; }, "count"},
      {"short codebook", [](test::SogChunk& c) { c.meta["scales"]["codebook"].erase(0); }, "scales.codebook"},
      {"infinite codebook entry", [](test::SogChunk& c) { c.meta["sh0"]["codebook"][3] = 1e300; }, "sh0.codebook[3]"},
      {"no means", [](test::SogChunk& c) { c.meta.erase("means"); }, "no \"means\""},
      {"path in a file name", [](test::SogChunk& c) { c.meta["quats"]["files"][0] = "../quats.webp"; }, "plain file name"},
      {"three bands of one", [](test::SogChunk& c) { c.meta["shN"]["bands"] = 3; }, "SH palette needs"},
  };
  for (const Case& c : cases) {
    test::SogChunk chunk = good;
    c.spoil(chunk);
    const std::string message = error_of([&] { chunk.parse(); });
    EXPECT_EQ(message.rfind("chunk/", 0), 0u) << c.what << ": " << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
  }
  const std::string not_json = error_of([&] { parse_sog("{\"version\": 2,", good.source(), "chunk/meta.json"); });
  EXPECT_NE(not_json.find("chunk/meta.json: meta.json is not valid JSON"), std::string::npos) << not_json;
}

// A LOD set on disk whose lod-meta.json is spoilt in each way in turn.
TEST(SogLod, HostileLodMetaGetsOneClearMessage) {
  std::mt19937 rng(13);
  const fs::path folder = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "hostile_lod";
  fs::create_directories(folder / "0_0");
  const test::SogChunk chunk = test::random_sog_chunk(50, 0, rng);
  std::ofstream(folder / "0_0" / "meta.json") << chunk.meta.dump();
  for (const auto& [name, bytes] : chunk.files)
    std::ofstream(folder / "0_0" / name, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  const nlohmann::json good = {
      {"lodLevels", 1},
      {"filenames", {"0_0/meta.json"}},
      {"tree", {{"bound", {{"min", {-9, -9, -9}}, {"max", {9, 9, 9}}}},
                {"children", {{{"lods", {{"0", {{"file", 0}, {"offset", 0}, {"count", 20}}}}}},
                              {{"lods", {{"0", {{"file", 0}, {"offset", 20}, {"count", 30}}}}}}}}}}};
  const std::string path = (folder / "lod-meta.json").string();
  std::ofstream(path) << good.dump();
  LoadProgress progress;
  EXPECT_EQ(read_sog_lod(path, 0, nullptr, &progress).size(), 50u);
  EXPECT_GT(progress.bytes_total.load(), 0u);
  EXPECT_EQ(progress.bytes_done.load(), progress.bytes_total.load());
  EXPECT_EQ(describe_sog_lod(folder.string()).levels.at(0).gaussians, 50u);
  struct Case {
    const char* what;
    std::function<void(nlohmann::json&)> spoil;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"range past the chunk", [](nlohmann::json& j) { j["tree"]["children"][1]["lods"]["0"]["count"] = 31; }, "which has 50"},
      {"level beyond lodLevels", [](nlohmann::json& j) { j["tree"]["children"][0]["lods"]["3"] = j["tree"]["children"][0]["lods"]["0"]; }, "lodLevels is 1"},
      {"file index beyond filenames", [](nlohmann::json& j) { j["tree"]["children"][0]["lods"]["0"]["file"] = 4; }, "file index"},
      {"escaping file name", [](nlohmann::json& j) { j["filenames"][0] = "../../etc/meta.json"; }, "inside the set's folder"},
      {"missing chunk", [](nlohmann::json& j) { j["filenames"][0] = "9_9/meta.json"; }, "cannot open"},
      {"no tree", [](nlohmann::json& j) { j.erase("tree"); }, "not a SOG lod-meta.json"},
      {"no levels", [](nlohmann::json& j) { j["lodLevels"] = 0; }, "no level"},
      {"overlapping leaves", [](nlohmann::json& j) {
         j["tree"]["children"][0]["lods"]["0"]["count"] = 24;
         j["tree"]["children"][1]["lods"]["0"] = {{"file", 0}, {"offset", 0}, {"count", 24}};
       }, "level 0 takes Gaussians 0..23 of 0_0/meta.json in two leaves"},
      {"a gap between leaves", [](nlohmann::json& j) { j["tree"]["children"][1]["lods"]["0"]["offset"] = 21; j["tree"]["children"][1]["lods"]["0"]["count"] = 29; },
       "level 0 leaves Gaussians 20..20 of 0_0/meta.json (50 Gaussians) in no leaf"},
      {"the chunk's end in no leaf", [](nlohmann::json& j) { j["tree"]["children"][1]["lods"]["0"]["count"] = 6; },
       "leaves Gaussians 26..49"},
      {"200,000 leaves taking the whole chunk each", [](nlohmann::json& j) {
         const nlohmann::json leaf = {{"lods", {{"0", {{"file", 0}, {"offset", 0}, {"count", 50}}}}}};
         j["tree"]["children"] = nlohmann::json::array();
         for (int i = 0; i < 200000; ++i) j["tree"]["children"].push_back(leaf);
       }, "in two leaves"},
  };
  for (const Case& c : cases) {
    nlohmann::json spoilt = good;
    c.spoil(spoilt);
    std::ofstream(path) << spoilt.dump();
    const std::string message = error_of([&] { read_sog_lod(path, 0); });
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
    EXPECT_NE(message.find("hostile_lod"), std::string::npos) << c.what << ": " << message;
    // The set's description (info, the level choice) checks the same.
    if (c.expected == std::string("in two leaves")) {
      EXPECT_NE(error_of([&] { describe_sog_lod(path); }).find(c.expected), std::string::npos) << c.what;
    }
  }
  std::ofstream(path) << good.dump();
  EXPECT_NE(error_of([&] { read_sog_lod(path, 1); }).find("level 1 does not exist"), std::string::npos);
}

// Writes `chunk` into `folder` as meta.json (with `meta_text` as its text) and its textures.
void write_chunk(const fs::path& folder, const test::SogChunk& chunk, const std::string& meta_text) {
  fs::create_directories(folder);
  std::ofstream(folder / "meta.json") << meta_text;
  for (const auto& [name, bytes] : chunk.files)
    std::ofstream(folder / name, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// Recognition read the first 64 KB: a valid meta.json padded with whitespace, or a
// lod-meta.json whose filenames list fills that much before "tree", was "not a scene file".
TEST(SogRecognition, KeysPastTheFirst64KBAreFound) {
  std::mt19937 rng(17);
  const fs::path folder = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "sog_long_json";
  fs::remove_all(folder);
  const test::SogChunk chunk = test::random_sog_chunk(40, 0, rng);
  const std::string padded = "{" + std::string(70 << 10, ' ') + chunk.meta.dump().substr(1);
  write_chunk(folder / "chunk", chunk, padded);
  EXPECT_EQ(load_scene_file((folder / "chunk" / "meta.json").string()).size(), 40u);

  // lod-meta.json's keys in nlohmann's order: filenames, lodLevels, tree.
  const nlohmann::json lod = {
      {"lodLevels", 1},
      {"filenames", std::vector<std::string>(5002, "chunk/meta.json")},
      {"tree", {{"lods", {{"0", {{"file", 0}, {"offset", 0}, {"count", 40}}}}}}}};
  const std::string lod_text = lod.dump();
  ASSERT_GT(lod_text.find("\"tree\""), std::size_t{64 << 10});
  const std::string lod_path = (folder / "lod-meta.json").string();
  std::ofstream(lod_path) << lod_text;
  EXPECT_TRUE(is_sog_lod_set(lod_path));
  EXPECT_EQ(load_scene_file(lod_path).size(), 40u);

  // Anything else is still looked at no further than its start.
  const std::string garbage = (folder / "garbage.json").string();
  std::ofstream(garbage) << "{" << std::string(100 << 10, 'x');
  EXPECT_NE(error_of([&] { load_scene_file(garbage); }).find("not a scene file"), std::string::npos);
}

// Texture and chunk names come from the JSON: an escape sequence in one reached the terminal
// in the "cannot open" line.
TEST(Sog, NamesFromTheJsonAreEscapedInMessages) {
  std::mt19937 rng(19);
  const fs::path folder = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "sog_control_names";
  fs::remove_all(folder);
  test::SogChunk chunk = test::random_sog_chunk(30, 0, rng);
  chunk.meta["quats"]["files"][0] = "\x1b[2Jquats.webp";
  write_chunk(folder / "chunk", chunk, chunk.meta.dump());
  const std::string texture = error_of([&] { load_scene_file((folder / "chunk" / "meta.json").string()); });
  EXPECT_EQ(texture.find('\x1b'), std::string::npos) << texture;
  EXPECT_NE(texture.find("\\x1b[2Jquats.webp: cannot open"), std::string::npos) << texture;

  const nlohmann::json lod = {
      {"lodLevels", 1},
      {"filenames", {"\x1b]0;x\x07/meta.json"}},
      {"tree", {{"lods", {{"0", {{"file", 0}, {"offset", 0}, {"count", 30}}}}}}}};
  const std::string lod_path = (folder / "lod-meta.json").string();
  std::ofstream(lod_path) << lod.dump();
  const std::string chunk_name = error_of([&] { load_scene_file(lod_path); });
  EXPECT_EQ(chunk_name.find('\x1b'), std::string::npos) << chunk_name;
  EXPECT_EQ(chunk_name.find('\x07'), std::string::npos) << chunk_name;
  EXPECT_NE(chunk_name.find("\\x1b]0;x\\x07/meta.json: cannot open"), std::string::npos) << chunk_name;
}

}  // namespace
}  // namespace flashgs
