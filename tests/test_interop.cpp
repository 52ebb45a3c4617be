// Interoperability with an independent implementation, PlayCanvas's splat-transform (npm
// @playcanvas/splat-transform): it reads every file we write, and we read every format it
// writes, each file decoding to the same Gaussians in both. Skips with a message when the tool
// is absent (set FLASHGS_SPLAT_TRANSFORM to its executable, or put splat-transform on PATH).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

// The splat-transform executable: $FLASHGS_SPLAT_TRANSFORM, or splat-transform on PATH.
std::string splat_transform() {
  if (const char* given = std::getenv("FLASHGS_SPLAT_TRANSFORM"); given && *given)
    return fs::exists(given) ? given : "";
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');)
    if (!dir.empty() && fs::exists(fs::path(dir) / "splat-transform")) return (fs::path(dir) / "splat-transform").string();
  return "";
}

#define SKIP_WITHOUT_SPLAT_TRANSFORM()                                                                       \
  if (splat_transform().empty())                                                                             \
  GTEST_SKIP() << "splat-transform is absent: `npm install @playcanvas/splat-transform` and set "           \
                  "FLASHGS_SPLAT_TRANSFORM to node_modules/.bin/splat-transform (or put it on PATH) to run " \
                  "the interoperability checks"

std::string scratch(const std::string& name) {
  const fs::path path = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "interop" / name;
  fs::create_directories(path.parent_path());
  return path.string();
}

// Runs splat-transform on `arguments` (overwriting, CPU only, quiet); its output goes to a log
// that a failure shows.
void run_splat_transform(const std::string& arguments) {
  const std::string log = scratch("splat-transform.log");
  const std::string command = "'" + splat_transform() + "' -w -q -g cpu " + arguments + " > '" + log + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  const std::string output((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(status, 0) << command << "\n" << output;
}

std::string quoted(const std::string& path) { return "'" + path + "'"; }

// One file decoded by us (`ours`) and by splat-transform (`theirs`, its PLY of the file): the
// same Gaussians in the same order, to float rounding of the two decoders' arithmetic.
void expect_same_decode(const Scene& ours, const Scene& theirs, const std::string& what) {
  ASSERT_EQ(theirs.size(), ours.size()) << what;
  ASSERT_EQ(theirs.sh_degree, ours.sh_degree) << what;
  for (std::size_t v = 0; v < ours.positions.size(); ++v) {
    ASSERT_NEAR(theirs.positions[v], ours.positions[v], 1e-4 + 1e-5 * std::abs(ours.positions[v])) << what << " " << v;
    ASSERT_NEAR(std::log(theirs.scales[v]), std::log(ours.scales[v]), 1e-4) << what << " " << v;
    ASSERT_NEAR(theirs.sh_dc[v], ours.sh_dc[v], 1e-4) << what << " " << v;
  }
  for (std::size_t i = 0; i < ours.size(); ++i) {
    ASSERT_NEAR(theirs.opacities[i], ours.opacities[i], 1e-5) << what << " " << i;
    double dot = 0;
    for (int k = 0; k < 4; ++k) dot += double(ours.rotations[i * 4 + k]) * theirs.rotations[i * 4 + k];
    ASSERT_GE(std::abs(dot), 1 - 1e-7) << what << ": rotation of Gaussian " << i;
  }
  for (std::size_t v = 0; v < ours.sh_rest.size(); ++v)
    ASSERT_NEAR(theirs.sh_rest[v], ours.sh_rest[v], 1e-4) << what << " " << v;
}

// What splat-transform decodes `file` to, through its plain PLY output.
Scene their_decode(const std::string& file, const std::string& tag) {
  const std::string ply = scratch(tag + ".theirs.ply");
  run_splat_transform(quoted(file) + " " + quoted(ply));
  return load_ply(ply);
}

struct Written {
  std::string name;  // the output name, which picks the format
  SceneWriteOptions options;
};

TEST(Interop, SplatTransformReadsEveryFormatWeWrite) {
  SKIP_WITHOUT_SPLAT_TRANSFORM();
  if (test::shared_scene_dir("kacytran_try").empty()) GTEST_SKIP() << "../shared/scenes is absent";
  const Scene scene = *test::load_shared_scene("kacytran_try");  // SH degree 3
  SceneWriteOptions v4;
  v4.spz_version = 4;
  for (const Written& w : std::vector<Written>{{"ours.compressed.ply", {}}, {"ours.spz", {}}, {"ours_v4.spz", v4},
                                               {"ours.sog", {}}, {"ours_sog/meta.json", {}}, {"ours.ply", {}}}) {
    const std::string file = scratch(w.name);
    save_scene_file(scene, file, w.options);
    const Scene ours = load_scene_file(file);
    expect_same_decode(ours, their_decode(file, fs::path(w.name).stem().string() + "_read"), w.name);
  }
}

TEST(Interop, WeReadEveryFormatSplatTransformWrites) {
  SKIP_WITHOUT_SPLAT_TRANSFORM();
  if (test::shared_scene_dir("kacytran_try").empty()) GTEST_SKIP() << "../shared/scenes is absent";
  const std::string source = test::shared_scene_dir("kacytran_try") + "/point_cloud.ply";
  for (const char* written : {"theirs.compressed.ply", "theirs.spz", "theirs_v3.spz", "theirs.sog",
                              "theirs_sog/meta.json"}) {
    const std::string name = written, file = scratch(name);
    run_splat_transform((name == "theirs_v3.spz" ? "--spz-version 3 " : "") + quoted(source) + " " + quoted(file));
    expect_same_decode(load_scene_file(file), their_decode(file, fs::path(name).stem().string() + "_back"), name);
  }
}

// A real Niantic scan: both decoders put it in the same (PLY) axes, so our default axes are
// the ones the spz library and splat-transform use.
TEST(Interop, ARealNianticSpzDecodesAlike) {
  SKIP_WITHOUT_SPLAT_TRANSFORM();
  const std::string file = test::shared_format_file("biker.spz");
  if (file.empty()) GTEST_SKIP() << "../shared/scenes/formats is absent";
  expect_same_decode(load_scene_file(file), their_decode(file, "biker_spz"), "biker.spz");
}

}  // namespace
}  // namespace flashgs
