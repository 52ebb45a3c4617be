// The readers of the variants users bring: SOG version 1 (meta.json without "version"), the
// zipped SOG bundle, uncompressed SPZ and .ksplat in its three compression modes, each
// checked value by value against what the file was built to hold, and their bad files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <zlib.h>

#include "compressed_builders.h"
#include "format_builders.h"
#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/model_constants.h"
#include "flashgs/scene_formats.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

std::string scratch(const std::string& name) {
  const fs::path path = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "format_readers" / name;
  fs::create_directories(path.parent_path());
  return path.string();
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

template <class Load>
std::string error_of(Load&& load) {
  try {
    load();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// ---- SOG version 1 ----

// The same textures as a version 2 chunk whose codebooks are linear ranges: version 1's
// per-channel ranges equal to them decode to the same Gaussians, except the opacity, which
// version 1 stores as a logit range.
TEST(SogVersion1, DecodesItsRangesLikeTheLinearCodebooksOfVersion2) {
  std::mt19937 rng(11);
  const test::SogChunk v2 = test::random_sog_chunk(300, 2, rng);
  const test::SogChunk v1 = test::sog_version_1(v2);
  const Scene a = v2.parse(), b = v1.parse();
  ASSERT_EQ(b.size(), a.size());
  ASSERT_EQ(b.sh_degree, 2) << "the band count comes from the palette's width";
  EXPECT_EQ(b.positions, a.positions);
  EXPECT_EQ(b.rotations, a.rotations);
  EXPECT_EQ(b.scales, a.scales);
  EXPECT_EQ(b.sh_dc, a.sh_dc);
  // Version 2's palette size is at most the texture's; labels inside it decode alike.
  EXPECT_EQ(b.sh_rest, a.sh_rest);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double byte = std::round(a.opacities[i] * 255.0);
    const double logit = -5 + 10 * byte / 255.0;
    ASSERT_NEAR(b.opacities[i], 1.0 / (1.0 + std::exp(-logit)), 1e-6) << i;
  }
}

TEST(SogVersion1, BadMetaJsonIsNamed) {
  std::mt19937 rng(12);
  test::SogChunk chunk = test::random_sog_chunk(20, 1, rng);
  chunk.meta.erase("version");
  EXPECT_NE(error_of([&] { chunk.parse(); }).find("means.shape"), std::string::npos);
  chunk.meta["means"]["shape"] = {20, 3};
  EXPECT_NE(error_of([&] { chunk.parse(); }).find("scales.mins"), std::string::npos) << "version 2's codebooks are not version 1's ranges";
  chunk.meta["scales"] = {{"mins", {0, 0, 0}}, {"maxs", {1, 1, 1}}, {"files", {"scales.webp"}}};
  chunk.meta["sh0"] = {{"mins", {0, 0, 0, 0}}, {"maxs", {1, 1, 1, 1}}, {"files", {"sh0.webp"}}};
  chunk.meta["shN"] = {{"mins", -1}, {"maxs", 1}, {"files", {"shN_centroids.webp", "shN_labels.webp"}}};
  chunk.files["shN_centroids.webp"] = test::lossless_webp({100, 1, std::vector<std::uint8_t>(400, 0)});
  EXPECT_NE(error_of([&] { chunk.parse(); }).find("192, 512 or 960"), std::string::npos);
}

// ---- zipped SOG ----

TEST(SogBundle, ReadsMetaJsonAndTexturesFromTheArchiveAndNamesWhatIsWrong) {
  Scene scene = *test::load_demo_scene();
  save_scene_file(scene, scratch("demo.sog"));
  const Scene back = load_scene_file(scratch("demo.sog"));
  EXPECT_EQ(back.size(), scene.size());
  LoadReport report;
  load_scene_file(scratch("demo.sog"), &report);
  EXPECT_EQ(report.format, format_name(SceneFormat::sog_bundle));

  std::ifstream in(scratch("demo.sog"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Cut short: the end record is gone.
  write_bytes(scratch("cut.sog"), bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(error_of([&] { load_scene_file(scratch("cut.sog")); }).find("no end record"), std::string::npos);
  // A byte of a texture changed: its CRC-32 no longer matches.
  std::string flipped = bytes;
  flipped[bytes.size() / 3] ^= 0x40;
  write_bytes(scratch("flipped.sog"), flipped);
  const std::string message = error_of([&] { load_scene_file(scratch("flipped.sog")); });
  EXPECT_FALSE(message.empty());
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  // A zip archive of something else.
  std::string other = bytes;
  const std::size_t meta = other.find("meta.json");
  ASSERT_NE(meta, std::string::npos);
  for (std::size_t at = 0; (at = other.find("meta.json", at)) != std::string::npos; ++at) other[at] = 'n';
  write_bytes(scratch("other.zip"), other);
  EXPECT_NE(error_of([&] { load_scene_file(scratch("other.zip")); }).find("without meta.json"), std::string::npos);
}

// ---- uncompressed SPZ ----

std::string gunzip(const std::string& gz) {
  z_stream z{};
  EXPECT_EQ(inflateInit2(&z, 15 + 16), Z_OK);
  std::string out(1 << 20, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  z.avail_in = static_cast<uInt>(gz.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(inflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  inflateEnd(&z);
  return out;
}

TEST(SpzUncompressed, ReadsTheGzipStreamsContentStoredBare) {
  std::mt19937 rng(13);
  for (std::uint32_t version : {2u, 3u}) {
    const test::SpzContent content = test::random_spz(500, 2, version, rng);
    const std::string gz = test::spz_gzip_file(content), raw = gunzip(gz);
    const Scene a = parse_spz(gz.data(), gz.size(), "a.spz"), b = parse_spz(raw.data(), raw.size(), "b.spz");
    EXPECT_EQ(b.positions, a.positions) << version;
    EXPECT_EQ(b.rotations, a.rotations) << version;
    EXPECT_EQ(b.sh_rest, a.sh_rest) << version;
    EXPECT_EQ(b.opacities, a.opacities) << version;
    EXPECT_TRUE(looks_like_spz(raw.data(), raw.size()));
    const std::string cut = raw.substr(0, raw.size() - 1);
    EXPECT_NE(error_of([&] { parse_spz(cut.data(), cut.size(), "cut.spz"); }).find("truncated file"), std::string::npos);
    const std::string longer = raw + "x";
    EXPECT_NE(error_of([&] { parse_spz(longer.data(), longer.size(), "long.spz"); }).find("extra data"), std::string::npos);
  }
}

// ---- .ksplat ----

TEST(Ksplat, DecodesEveryCompressionModeAndBucketLayout) {
  for (int mode : {0, 1, 2}) {
    std::vector<test::KsplatGaussian> gs;
    for (int i = 0; i < 11; ++i) {  // two full buckets of 4, partial buckets of 2 and 1
      test::KsplatGaussian g{};
      const std::uint32_t bucket = i < 8 ? i / 4 : 2 + (i - 8) / 2;
      for (int k = 0; k < 3; ++k) g.position[k] = (k == 0 ? bucket : k == 1 ? -float(bucket) : 0.5f * bucket) + 0.25f * (k + 1) * (i % 3 - 1);
      for (int k = 0; k < 3; ++k) g.scale[k] = 0.125f * (k + 1 + i % 2);
      const float r[4] = {0.5f, i % 2 ? -0.5f : 0.5f, 0.5f, 0.5f};
      std::copy(r, r + 4, g.rotation);
      g.rgba[0] = static_cast<std::uint8_t>(10 * i);
      g.rgba[1] = 128;
      g.rgba[2] = 255;
      g.rgba[3] = static_cast<std::uint8_t>(20 + i);
      // Distinct values per band, channel and coefficient, on mode 2's byte grid of [-2, 2].
      for (int v = 0; v < 24; ++v) g.sh.push_back(-2.0f + 4.0f * static_cast<float>((7 * v + i) % 256) / 255.0f);
      gs.push_back(g);
    }
    const std::string path = scratch("mode" + std::to_string(mode) + ".ksplat");
    write_bytes(path, test::ksplat_file(gs, mode, 2));
    LoadReport report;
    const Scene scene = load_scene_file(path, &report);
    EXPECT_EQ(report.format, format_name(SceneFormat::ksplat));
    ASSERT_EQ(scene.size(), gs.size()) << mode;
    ASSERT_EQ(scene.sh_degree, 2) << mode;
    const double position_step = mode == 0 ? 1e-6 : 2.0 / 2 / 32767;
    for (std::size_t i = 0; i < gs.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_NEAR(scene.positions[i * 3 + k], gs[i].position[k], position_step) << mode << " " << i;
        ASSERT_NEAR(scene.scales[i * 3 + k], gs[i].scale[k], 1e-6) << mode << " " << i;
        ASSERT_NEAR(scene.sh_dc[i * 3 + k], (gs[i].rgba[k] / 255.0 - 0.5) / model::kShC0, 1e-5) << mode << " " << i;
      }
      for (int k = 0; k < 4; ++k) ASSERT_NEAR(scene.rotations[i * 4 + k], gs[i].rotation[k], 1e-6) << mode << " " << i;
      ASSERT_NEAR(scene.opacities[i], gs[i].rgba[3] / 255.0, 1e-6);
      // File order band by band, channel-major; the scene's [coefficient][channel].
      const int first[2] = {0, 3}, size[2] = {3, 5};
      for (int v = 0, band = 0; band < 2; ++band)
        for (int channel = 0; channel < 3; ++channel)
          for (int c = 0; c < size[band]; ++c, ++v)
            ASSERT_NEAR(scene.sh_rest[i * 24 + (first[band] + c) * 3 + channel], gs[i].sh[v], mode == 1 ? 2e-3 : 1e-5)
                << "mode " << mode << " Gaussian " << i << " value " << v;
    }
  }
}

TEST(Ksplat, BadFilesGetOneLine) {
  std::vector<test::KsplatGaussian> gs(5);
  for (auto& g : gs) {
    g.rotation[0] = 1;
    g.scale[0] = g.scale[1] = g.scale[2] = 0.5f;
  }
  const std::string good = test::ksplat_file(gs, 1, 0);
  const std::string path = scratch("bad.ksplat");
  auto message_for = [&](const std::string& bytes) {
    write_bytes(path, bytes);
    const std::string m = error_of([&] { load_scene_file(path); });
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  };
  EXPECT_NE(message_for(good.substr(0, 100)).find("4096-byte header"), std::string::npos);
  EXPECT_NE(message_for(good.substr(0, good.size() - 1)).find("truncated file"), std::string::npos);
  std::string wrong = good;
  wrong[16] = 6;  // the header's count
  EXPECT_NE(message_for(wrong).find("the sections hold 5 Gaussians"), std::string::npos);
  wrong = good;
  wrong[20] = 3;
  EXPECT_NE(message_for(wrong).find("compression mode 3"), std::string::npos);
  wrong = good;
  wrong[4096 + 40] = 4;
  EXPECT_NE(message_for(wrong).find("SH degree 4"), std::string::npos);
}

}  // namespace
}  // namespace flashgs
