// The scene-file formats: recognition by content, the PlayCanvas compressed PLY against its
// INRIA twins, .splat written and read back and hand-checked, load progress and cancelling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "flashgs/model_constants.h"
#include "flashgs/renderer.h"
#include "flashgs/scene_formats.h"
#include "format_builders.h"
#include "ply_builder.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

std::string scratch_file(const std::string& name) {
  const fs::path dir = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "formats";
  fs::create_directories(dir);
  return (dir / name).string();
}

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The message of the flashgs::Error that `load` throws (empty when it throws none).
template <class Load>
std::string error_of(Load&& load) {
  try {
    load();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Distance in float steps (units in the last place) between two finite floats of one sign.
std::int64_t ulps(float a, float b) {
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  return std::abs(static_cast<std::int64_t>(ia) - ib);
}

Image render_cpu(const Scene& scene, const Camera& camera) {
  auto renderer = make_cpu_renderer();
  renderer->set_scene(std::make_shared<const Scene>(scene));
  Image image;
  renderer->render(camera, RenderOptions{}, image, nullptr);
  return image;
}

// The image as an 8-bit file would hold it.
std::vector<unsigned char> to_8_bit(const Image& image) {
  std::vector<unsigned char> bytes;
  for (float v : image.rgb) bytes.push_back(static_cast<unsigned char>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255)));
  return bytes;
}

// ---- recognition ----------------------------------------------------------------------

TEST(SceneFormats, UnknownContentGetsOneLineNamingTheFile) {
  const std::string path = scratch_file("picture.gif");
  write_file(path, "GIF89a\x01\x02 and more");
  LoadProgress progress;
  EXPECT_EQ(error_of([&] { load_scene_file(path, nullptr, &progress); }),
            path + ": not a scene file: it starts with \"GIF89a\\x01\\x02\"; expected a PLY, .splat, .ksplat, .spz or SOG");
  EXPECT_EQ(progress.bytes_total.load(), 0u) << "recognised from its first bytes, not read whole";
  const std::string empty = scratch_file("empty.bin");
  write_file(empty, "");
  EXPECT_EQ(error_of([&] { load_scene_file(empty); }),
            empty + ": not a scene file: it is empty; expected a PLY, .splat, .ksplat, .spz or SOG");
}

TEST(SceneFormats, ContentDecidesOverTheExtension) {
  // A compressed PLY and an INRIA PLY both named .splat: their headers say what they are.
  const std::string compressed = scratch_file("compressed_named.splat");
  write_file(compressed, test::compressed_ply_bytes(300));
  LoadReport report;
  EXPECT_EQ(load_scene_file(compressed, &report).size(), 300u);
  EXPECT_EQ(report.format, format_name(SceneFormat::compressed_ply));
  const std::string inria = scratch_file("inria_named.splat");
  write_file(inria, test::PlyBuilder::inria(1, 5).bytes());
  EXPECT_EQ(load_scene_file(inria, &report).size(), 5u);
  EXPECT_EQ(report.format, format_name(SceneFormat::inria_ply));
  EXPECT_EQ(report.quantisation, format_quantisation(SceneFormat::inria_ply));
}

// ---- PlayCanvas compressed PLY --------------------------------------------------------

// One Gaussian with every field at a hand-computed value (chunk bounds with colours, SH 1).
TEST(CompressedPly, HandMadeFileDecodesAsTheFormatSays) {
  std::string file =
      "ply\nformat binary_little_endian 1.0\nelement chunk 1\n"
      "property float min_x\nproperty float min_y\nproperty float min_z\nproperty float max_x\n"
      "property float max_y\nproperty float max_z\nproperty float min_scale_x\nproperty float min_scale_y\n"
      "property float min_scale_z\nproperty float max_scale_x\nproperty float max_scale_y\n"
      "property float max_scale_z\nproperty float min_r\nproperty float min_g\nproperty float min_b\n"
      "property float max_r\nproperty float max_g\nproperty float max_b\n"
      "element vertex 1\nproperty uint packed_position\nproperty uint packed_rotation\n"
      "property uint packed_scale\nproperty uint packed_color\nelement sh 1\n";
  for (int k = 0; k < 9; ++k) file += "property uchar f_rest_" + std::to_string(k) + "\n";
  file += "end_header\n";
  const float chunk[18] = {0, 0, 0, 2, 4, 8, -2, -2, -2, 0, 0, 0, 0, 0, 0.5f, 1, 1, 1};
  test::append_bytes(file, chunk, sizeof chunk);
  const std::uint32_t words[4] = {
      (2047u << 21) | (0u << 11) | 1023u,  // position: x = max, y = min, z = 1023/2047 of the way
      (2u << 30) | (1023u << 20) | (0u << 10) | 512u,  // rotation: rot_2 largest; a = +, b = -, c = ~0
      (0u << 21) | (1023u << 11) | 2047u,  // log-scale: -2, 0, 0
      (255u << 24) | (0u << 16) | (51u << 8) | 204u};  // colour 1, 0, 0.5 + 0.5 * 0.2; opacity 0.8
  test::append_bytes(file, words, sizeof words);
  const unsigned char sh[9] = {0, 255, 128, 1, 2, 3, 4, 5, 6};  // R of bands 1..3, then G, then B
  test::append_bytes(file, sh, sizeof sh);

  LoadReport report;
  const Scene s = parse_scene_bytes(file.data(), file.size(), "hand.compressed.ply", &report);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s.sh_degree, 1);
  EXPECT_FLOAT_EQ(s.positions[0], 2.0f);
  EXPECT_FLOAT_EQ(s.positions[1], 0.0f);
  EXPECT_FLOAT_EQ(s.positions[2], static_cast<float>(8.0 * 1023 / 2047));
  EXPECT_FLOAT_EQ(s.scales[0], std::exp(-2.0f));
  EXPECT_FLOAT_EQ(s.scales[1], 1.0f);
  EXPECT_FLOAT_EQ(s.scales[2], 1.0f);
  const double a = (1.0 - 0.5) * std::sqrt(2.0), b = -0.5 * std::sqrt(2.0), c = (512.0 / 1023 - 0.5) * std::sqrt(2.0);
  const double m = std::sqrt(std::max(0.0, 1.0 - a * a - b * b - c * c));  // 0: a and b hold it all
  const double expected_q[4] = {a, b, m, c};
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(s.rotations[k], expected_q[k], 1e-6) << k;
  EXPECT_FLOAT_EQ(s.sh_dc[0], static_cast<float>(0.5 / model::kShC0));
  EXPECT_FLOAT_EQ(s.sh_dc[1], static_cast<float>(-0.5 / model::kShC0));
  EXPECT_FLOAT_EQ(s.sh_dc[2], static_cast<float>((0.5 + 0.5 * 0.2 - 0.5) / model::kShC0));
  EXPECT_FLOAT_EQ(s.opacities[0], 0.8f);
  // sh_rest is [band][channel]: band 1 is R 0 -> -4, G 1 -> (1.5 / 256 - 0.5) * 8, B 4 -> ...
  EXPECT_FLOAT_EQ(s.sh_rest[0], -4.0f);
  EXPECT_FLOAT_EQ(s.sh_rest[1], static_cast<float>((1.5 / 256 - 0.5) * 8));
  EXPECT_FLOAT_EQ(s.sh_rest[2], static_cast<float>((4.5 / 256 - 0.5) * 8));
  EXPECT_FLOAT_EQ(s.sh_rest[3], 4.0f);  // band 2, R: 255
  EXPECT_FLOAT_EQ(s.sh_rest[6], static_cast<float>((128.5 / 256 - 0.5) * 8));  // band 3, R
}

TEST(CompressedPly, LyingHeadersGetOneLineNamingTheFile) {
  const std::string name = "lying.compressed.ply";
  const auto parse = [&](const std::string& bytes) {
    return error_of([&] { parse_scene_bytes(bytes.data(), bytes.size(), name); });
  };
  EXPECT_EQ(parse(test::compressed_ply_bytes(300, 0, true, -1, 1)),
            name + ": the header declares 1 chunks for 300 vertices; 256 vertices per chunk need 2");
  std::string truncated = test::compressed_ply_bytes(300);
  truncated.resize(truncated.size() - 5);
  EXPECT_NE(parse(truncated).find("truncated file or wrong count"), std::string::npos) << parse(truncated);
  const std::string absurd = test::compressed_ply_bytes(300, 0, true, 1ll << 40, (1ll << 40) / 256);
  EXPECT_NE(parse(absurd).find("but the file holds only"), std::string::npos) << parse(absurd);
  std::string wrong_type = test::compressed_ply_bytes(3);
  wrong_type.replace(wrong_type.find("property uint packed_scale"), 13, "property float");
  EXPECT_EQ(parse(wrong_type), name + ": property \"packed_scale\" of element \"vertex\" has type \"float\"; a "
                                      "compressed PLY stores it as uint");
}

// The twins in ../shared/scenes were converted from the compressed files by PlayCanvas's
// decompressor, which stores float32 values: the reader rounds at the same steps, so positions,
// scales, rotations and colours are equal bit for bit (tolerance 0). Opacity is kept as decoded
// (the 8-bit alpha) while the twin stores it as a float logit: the two differ by the logit's
// float rounding (measured: at most 2 float steps; allowed 4), and at alpha 0 and 1, which the
// converter clamped to 1e-6 from the ends (allowed 1.05e-6).
TEST(CompressedPly, SharedSamplesDecodeToTheirTwins) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string twin : {"pc_biker", "pc_guitar"}) {
    const std::string name = twin.substr(3);
    const std::string compressed_path = test::shared_format_file(name + ".compressed.ply");
    if (test::shared_scene_dir(twin).empty() || compressed_path.empty())
      GTEST_SKIP() << twin << " or formats/" << name << ".compressed.ply is absent";
    LoadReport report;
    const Scene decoded = load_scene_file(compressed_path, &report);
    EXPECT_EQ(report.format, format_name(SceneFormat::compressed_ply));
    const Scene& plain = *test::load_shared_scene(twin);
    ASSERT_EQ(decoded.size(), plain.size()) << name;
    ASSERT_EQ(decoded.sh_degree, plain.sh_degree) << name;
    EXPECT_EQ(decoded.positions, plain.positions) << name;
    EXPECT_EQ(decoded.scales, plain.scales) << name;
    EXPECT_EQ(decoded.rotations, plain.rotations) << name;
    EXPECT_EQ(decoded.sh_dc, plain.sh_dc) << name;
    EXPECT_EQ(decoded.sh_rest, plain.sh_rest) << name;
    std::int64_t worst_ulps = 0;
    double worst_clamped = 0;
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      const float a = decoded.opacities[i], b = plain.opacities[i];
      if (a == 0.0f || a == 1.0f) worst_clamped = std::max(worst_clamped, std::abs(double(a) - b));
      else worst_ulps = std::max(worst_ulps, ulps(a, b));
    }
    std::printf("%s: opacity differs by at most %lld float steps, %.3g where the twin clamped alpha 0 or 1\n",
                name.c_str(), static_cast<long long>(worst_ulps), worst_clamped);
    EXPECT_LE(worst_ulps, 4) << name;
    EXPECT_LE(worst_clamped, 1.05e-6) << name;

    // Those few float steps of opacity reach the float image as about 3e-7: far below one
    // step of an 8-bit image, which is identical.
    const Camera camera = test::load_shared_cameras(twin)[0].resized(192, 108);
    const Image a = render_cpu(decoded, camera), b = render_cpu(plain, camera);
    const ImageDifference d = compare_images(a, b);
    std::printf("%s: CPU render 192x108, max |difference| %.3g, PSNR %.1f dB\n", name.c_str(), d.max_abs, d.psnr_db);
    EXPECT_LE(d.max_abs, 1e-6) << name;
    EXPECT_EQ(to_8_bit(a), to_8_bit(b)) << name;
    EXPECT_GT(*std::max_element(a.rgb.begin(), a.rgb.end()), 0.2f) << name << ": the view shows nothing";
  }
}

// ---- .splat ----------------------------------------------------------------------------

TEST(Splat, HandWrittenFileDecodesToHandCheckedValues) {
  const float p0[3] = {1.5f, -2.0f, 3.25f}, s0[3] = {0.01f, 0.02f, 0.5f};
  const std::uint8_t c0[4] = {255, 0, 128, 255}, q0[4] = {255, 128, 128, 128};  // identity (w = 127/128)
  const float p1[3] = {0, 0, 0}, s1[3] = {1, 1, 1};
  const std::uint8_t c1[4] = {64, 191, 26, 51}, q1[4] = {218, 128, 218, 128};  // 90 degrees about y
  const std::string bytes = test::splat_record(p0, s0, c0, q0) + test::splat_record(p1, s1, c1, q1);
  const std::string path = scratch_file("hand.splat");
  write_file(path, bytes);
  LoadReport report;
  const Scene s = load_scene_file(path, &report);
  EXPECT_EQ(report.format, format_name(SceneFormat::splat));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s.sh_degree, 0);
  EXPECT_EQ(std::vector<float>(s.positions.begin(), s.positions.begin() + 3), std::vector<float>(p0, p0 + 3));
  EXPECT_EQ(std::vector<float>(s.scales.begin(), s.scales.begin() + 3), std::vector<float>(s0, s0 + 3));
  // Colour byte c is 0.5 + SH_C0 * dc: 255 -> dc 1.7725, 0 -> -1.7725, 128 -> 0.00696.
  EXPECT_NEAR(s.sh_dc[0], 1.7724539, 1e-6);
  EXPECT_NEAR(s.sh_dc[1], -1.7724539, 1e-6);
  EXPECT_NEAR(s.sh_dc[2], 0.0069508, 1e-6);
  EXPECT_NEAR(s.sh_dc[3], (64 / 255.0 - 0.5) / 0.28209479, 1e-6);  // -0.8827
  EXPECT_FLOAT_EQ(s.opacities[0], 1.0f);
  EXPECT_FLOAT_EQ(s.opacities[1], 0.2f);  // 51 / 255
  const float identity[4] = {1, 0, 0, 0}, about_y[4] = {0.70710678f, 0, 0.70710678f, 0};
  for (int k = 0; k < 4; ++k) {
    EXPECT_FLOAT_EQ(s.rotations[k], identity[k]) << k;
    EXPECT_FLOAT_EQ(s.rotations[4 + k], about_y[k]) << k;
  }
}

TEST(Splat, SizeNotAMultipleOf32IsNamed) {
  const std::string path = scratch_file("cut.splat");
  write_file(path, std::string(70, '\0'));
  EXPECT_EQ(error_of([&] { load_scene_file(path); }),
            path + ": a .splat file is a sequence of 32-byte records, but its 70 bytes are not a multiple of 32 "
                   "(6 bytes left over): truncated, or not a .splat file");
}

// Written and read back: positions and scales are float32 in the file (exact); colour,
// opacity and rotation are bytes rounded to the nearest, so colour (within [0, 1]) is off by
// at most 0.5/255 (dc by 0.5/255/SH_C0), opacity by 0.5/255, and each quaternion component
// by 1/256 before renormalising (1/128 where a component of 1 clamps to 255): at most 0.016
// after it.
TEST(Splat, WrittenSceneReadsBackWithinItsQuantisation) {
  const Scene original = make_demo_scene(5000);
  const std::string path = scratch_file("demo.splat");
  save_splat(original, path);
  EXPECT_EQ(fs::file_size(path), 32 * original.size());
  const Scene back = load_scene_file(path);
  ASSERT_EQ(back.size(), original.size());
  EXPECT_EQ(back.positions, original.positions);
  EXPECT_EQ(back.scales, original.scales);
  double worst_dc = 0, worst_opacity = 0, worst_rotation = 0;
  for (std::size_t i = 0; i < original.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double colour = 0.5 + model::kShC0 * original.sh_dc[i * 3 + k];
      const double clamped_dc = (std::min(std::max(colour, 0.0), 1.0) - 0.5) / model::kShC0;
      worst_dc = std::max(worst_dc, std::abs(back.sh_dc[i * 3 + k] - clamped_dc));
    }
    worst_opacity = std::max(worst_opacity, std::abs(double(back.opacities[i]) - original.opacities[i]));
    for (int k = 0; k < 4; ++k)
      worst_rotation = std::max(worst_rotation, std::abs(double(back.rotations[i * 4 + k]) - original.rotations[i * 4 + k]));
  }
  std::printf("splat round trip: dc %.3g, opacity %.3g, rotation component %.3g\n", worst_dc, worst_opacity,
              worst_rotation);
  EXPECT_LE(worst_dc, 0.5 / 255 / model::kShC0 + 1e-6);
  EXPECT_LE(worst_opacity, 0.5 / 255 + 1e-7);
  EXPECT_LE(worst_rotation, 0.016);
  EXPECT_GT(worst_rotation, 0.0) << "the rotation bytes must quantise";
}

// ---- progress and cancelling ----------------------------------------------------------

// Every format's reader: the totals are reached; a cancel request stops the read at the first
// chunk and the decoding at its first check.
TEST(LoadProgress, ReachesTheTotalsAndStopsOnCancel) {
  const Scene scene = make_demo_scene(120000);  // a PLY of ~7 MB: more than one read chunk
  const std::string ply = scratch_file("progress.ply"), splat = scratch_file("progress.splat");
  save_ply(scene, ply);
  save_splat(scene, splat);
  const std::string compressed = scratch_file("progress.compressed.ply");
  write_file(compressed, test::compressed_ply_bytes(70000, 2));
  for (const std::string& path : {ply, splat, compressed}) {
    LoadProgress progress;
    const Scene loaded = load_scene_file(path, nullptr, &progress);
    EXPECT_EQ(progress.bytes_total.load(), fs::file_size(path)) << path;
    EXPECT_EQ(progress.bytes_done.load(), progress.bytes_total.load()) << path;
    EXPECT_EQ(progress.gaussians_total.load(), loaded.size()) << path;
    EXPECT_EQ(progress.gaussians_done.load(), loaded.size()) << path;

    LoadProgress cancelled;
    cancelled.cancel_requested = true;
    EXPECT_THROW(load_scene_file(path, nullptr, &cancelled), LoadCancelled) << path;
    EXPECT_EQ(cancelled.bytes_done.load(), 0u) << path;
    EXPECT_EQ(cancelled.bytes_total.load(), fs::file_size(path)) << path;

    // The decoding checks too (the bytes already in memory).
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    LoadProgress decoding;
    decoding.cancel_requested = true;
    EXPECT_EQ(error_of([&] { parse_scene_bytes(bytes.data(), bytes.size(), path, nullptr, &decoding); }),
              path + ": loading cancelled");
    EXPECT_EQ(decoding.gaussians_done.load(), 0u) << path;
    EXPECT_EQ(decoding.gaussians_total.load(), loaded.size()) << path;
  }
}

}  // namespace
}  // namespace flashgs
