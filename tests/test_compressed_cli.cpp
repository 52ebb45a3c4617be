// `flashgs info` and `flashgs render` on the SPZ and SOG samples, --lod, and hostile files
// (one error line, a non-zero exit).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "compressed_builders.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// `shell_first`: shell commands run before flashgs (a ulimit).
CliRun flashgs(const std::string& arguments, const std::string& shell_first = "") {
  CliRun r;
  FILE* pipe = popen((shell_first + std::string(FLASHGS_CLI) + " " + arguments + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) r.output.append(buffer, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string formats() { return std::string(FLASHGS_SHARED_SCENES) + "/formats"; }
std::string scenes() { return FLASHGS_SHARED_SCENES; }

#define REQUIRE_FORMATS()                                                                   \
  do {                                                                                      \
    if (!fs::exists(formats() + "/biker.spz") || !fs::exists(scenes() + "/pc_playbot"))     \
      GTEST_SKIP() << "../shared/scenes/formats is absent: sample test skipped";            \
  } while (0)

std::string output_dir() {
  const fs::path dir = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "compressed_cli";
  fs::create_directories(dir);
  return dir.string();
}

// An SPZ that honestly declares 12M Gaussians in a few hundred KB (a gzip of zeros): loading
// them fits under a 2 GB address-space limit, a 1920x1080 frame of them on top does not. The
// render is refused from the header, before anything is inflated, naming the file and figures.
TEST(CompressedCli, DeclaredGaussiansWithoutRoomForAFrameAreRefusedBeforeLoading) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const std::string path = output_dir() + "/zeros.spz";
  test::SpzContent header;
  header.count = 12000000;  // version 3, SH degree 0: 20 bytes each
  const std::string head = test::spz_payload(header);
  gzFile out = gzopen(path.c_str(), "wb");
  ASSERT_NE(out, nullptr);
  gzwrite(out, head.data(), static_cast<unsigned>(head.size()));
  const std::string zeros(1 << 20, '\0');
  for (std::size_t left = std::size_t{20} * header.count; left > 0;) {
    const std::size_t n = std::min(left, zeros.size());
    gzwrite(out, zeros.data(), static_cast<unsigned>(n));
    left -= n;
  }
  ASSERT_EQ(gzclose(out), Z_OK);
  const CliRun r = flashgs("render " + path + " --backend cpu --eye 0,0,-5 --look-at 0,0,0 -o " + output_dir() +
                               "/zeros.png",
                           "ulimit -v 2000000; ");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("zeros.spz: 12000000 Gaussians need about 912."), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("for a 1920x1080 frame (the camera's size), but "), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(output_dir() + "/zeros.png"));
}

TEST(CompressedCli, InfoAndRenderOpenBikerSpz) {
  REQUIRE_FORMATS();
  const CliRun info = flashgs("info " + formats() + "/biker.spz");
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("152746"), std::string::npos) << info.output;
  const std::string out = output_dir() + "/biker_spz.ppm";
  fs::remove(out);
  const CliRun render = flashgs("render " + formats() + "/biker.spz --cameras " + scenes() +
                             "/pc_biker/cameras.json -r 64x48 --backend cpu -o " + out);
  EXPECT_EQ(render.exit_code, 0) << render.output;
  EXPECT_TRUE(fs::exists(out));
}

TEST(CompressedCli, InfoListsTheLodLevelsAndRenderTakesLod) {
  REQUIRE_FORMATS();
  const CliRun info = flashgs("info " + formats() + "/playbot_sog --lod 6");
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("7 levels"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("level 6: 1873 Gaussians"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("LOD set (lod-meta.json) of SOG (PlayCanvas) chunks, level 6"), std::string::npos) << info.output;
  const std::string out = output_dir() + "/playbot_lod.ppm";
  fs::remove(out);
  const CliRun render = flashgs("render " + formats() + "/playbot_sog --lod 5 --cameras " + scenes() +
                             "/pc_playbot/cameras.json -r 64x48 --backend cpu -o " + out);
  EXPECT_EQ(render.exit_code, 0) << render.output;
  EXPECT_NE(render.output.find("LOD level 5 of 0..6, 3000 Gaussians"), std::string::npos) << render.output;
  EXPECT_TRUE(fs::exists(out));
  // One chunk folder, and its meta.json, open as well.
  const CliRun chunk = flashgs("info " + formats() + "/playbot_sog/6_0");
  EXPECT_EQ(chunk.exit_code, 0) << chunk.output;
  EXPECT_NE(chunk.output.find("1873"), std::string::npos) << chunk.output;
}

TEST(CompressedCli, BadLodAndHostileFilesGiveOneErrorLine) {
  REQUIRE_FORMATS();
  const CliRun not_a_set = flashgs("info " + formats() + "/biker.spz --lod 2");
  EXPECT_NE(not_a_set.exit_code, 0);
  EXPECT_NE(not_a_set.output.find("--lod: " + formats() + "/biker.spz is not a SOG LOD set"), std::string::npos)
      << not_a_set.output;
  const CliRun too_deep = flashgs("info " + formats() + "/playbot_sog --lod 9");
  EXPECT_NE(too_deep.exit_code, 0);
  EXPECT_NE(too_deep.output.find("has levels 0..6"), std::string::npos) << too_deep.output;
  // A truncated SPZ: one line naming the file.
  std::mt19937 rng(4);
  const std::string gz = test::spz_gzip_file(test::random_spz(200, 0, 3, rng));
  const std::string path = output_dir() + "/truncated.spz";
  std::ofstream(path, std::ios::binary) << gz.substr(0, gz.size() / 2);
  const CliRun truncated = flashgs("info " + path);
  EXPECT_NE(truncated.exit_code, 0);
  EXPECT_NE(truncated.output.find(path + ": the gzip stream"), std::string::npos) << truncated.output;
  EXPECT_EQ(std::count(truncated.output.begin(), truncated.output.end(), '\n'), 1) << truncated.output;
}

}  // namespace
}  // namespace flashgs
