// Paths that are not plain files (folders, FIFOs, devices, symbolic links, empty, unreadable and
// oversized files) through the library and the flashgs binary, and how a scene path is located.
// Nothing may hang even when the code is wrong: library reads run in a child process under an
// alarm, the binary under `timeout`.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <tuple>

#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/load_progress.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "ply_builder.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

// Seconds a library read or a flashgs run may take before the test calls it hung.
constexpr int kHangSeconds = 20;

// An empty folder for one test, under the test output folder.
fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "file_kinds" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write_file(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

std::string small_ply() { return test::PlyBuilder::inria(0, 10).bytes(); }

std::string demo_cameras_json() {
  std::ifstream in(demo_cameras_path());
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// One of each odd thing a path can name, made in `dir`.
struct OddPaths {
  fs::path folder, fifo, device, loop, dangling, empty;
  explicit OddPaths(const fs::path& dir)
      : folder(dir / "folder"), fifo(dir / "fifo"), device(dir / "zero"), loop(dir / "loop"),
        dangling(dir / "dangling"), empty(dir / "empty") {
    fs::create_directories(folder);
    EXPECT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    fs::create_symlink("/dev/zero", device);
    fs::create_symlink(loop.filename(), loop);
    fs::create_symlink(dir / "nothing_here", dangling);
    write_file(empty, "");
  }
};

std::string regex_escaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (std::string("\\^$.|?*+()[]{}").find(c) != std::string::npos) out += '\\';
    out += c;
  }
  return out;
}

// The child process of expect_refused: exits 0 when `read` throws flashgs::Error.
[[noreturn]] void read_in_child(const std::function<void()>& read) {
  ::alarm(kHangSeconds);
  rlimit memory{};
  memory.rlim_cur = memory.rlim_max = 2ull << 30;
  ::setrlimit(RLIMIT_AS, &memory);
  try {
    read();
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::_Exit(0);
  }
  std::fprintf(stderr, "read without an error\n");
  std::_Exit(1);
}

// Runs `read` in a child process that the alarm ends after kHangSeconds and that may not grow
// past 2 GB (a FIFO blocks, /dev/zero never ends), and expects a flashgs::Error whose message
// starts with `path` and holds `fragment`.
void expect_refused(const std::function<void()>& read, const fs::path& path, const std::string& fragment) {
  EXPECT_EXIT(read_in_child(read), testing::ExitedWithCode(0),
              "^" + regex_escaped(path.string() + ": ") + ".*" + regex_escaped(fragment))
      << path;
}

TEST(FileKinds, TheSceneLoaderRefusesWhatIsNotAFile) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const OddPaths odd(fresh_dir("ply"));
  const std::vector<std::tuple<fs::path, std::string>> cases = {
      {odd.folder, "is a folder, not a file"},
      {odd.fifo, "is a FIFO (named pipe), not a regular file"},
      {odd.device, "is a device, not a regular file"},
      {odd.loop, "cannot open: a loop of symbolic links"},
      {odd.dangling, "cannot open: a symbolic link whose target does not exist"},
      {odd.empty, "not a PLY file (it is empty)"}};
  for (const auto& [path, fragment] : cases) expect_refused([&p = path] { load_ply(p.string()); }, path, fragment);
}

TEST(FileKinds, TheCameraLoaderRefusesWhatIsNotAFile) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const OddPaths odd(fresh_dir("cameras"));
  const std::vector<std::tuple<fs::path, std::string>> cases = {
      {odd.folder, "is a folder, not a file"},
      {odd.fifo, "is a FIFO (named pipe), not a regular file"},
      {odd.device, "is a device, not a regular file"},
      {odd.loop, "cannot open: a loop of symbolic links"},
      {odd.empty, "the file is empty"}};
  for (const auto& [path, fragment] : cases) expect_refused([&p = path] { load_cameras(p.string()); }, path, fragment);
}

TEST(FileKinds, CameraFileOverTheSizeLimit) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const fs::path path = fresh_dir("big_cameras") / "cameras.json";
  write_file(path, "");
  fs::resize_file(path, 65000000);  // sparse: no 65 MB written
  expect_refused([&] { load_cameras(path.string()); }, path, "the file is 65 MB, more than the 64 MB");
}

// A header that contradicts the file's size, or Gaussians that cannot fit in memory, are
// refused from the file's start: a sparse 10 GB PLY or 3 GB .splat is never read whole (the
// child may not grow past 2 GB, and reading either would need more).
TEST(FileKinds, SizesAreCheckedBeforeTheFileIsRead) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const fs::path dir = fresh_dir("sparse_scenes");
  const std::string ply = small_ply();
  const std::string header = ply.substr(0, ply.find("end_header\n") + 11);
  for (const std::uint64_t size : {3000000000ull, 10000000000ull}) {
    const fs::path path = dir / ("sparse_" + std::to_string(size / 1000000000) + "gb.ply");
    write_file(path, header);
    fs::resize_file(path, size);
    expect_refused([&] { load_scene_file(path.string()); }, path,
                   "bytes after the header: the vertex count does not match the file size");
  }
  const fs::path splat = dir / "zeros.splat";
  write_file(splat, "");
  fs::resize_file(splat, 3000000000ull - 3000000000ull % 32);
  expect_refused([&] { load_scene_file(splat.string()); }, splat,
                 "93750000 Gaussians in 3.0 GB need about 8.2 GB of memory to load");
  // What a file declares, without reading it.
  const SceneDeclaration declared = declare_scene_file(splat.string());
  EXPECT_EQ(declared.format, SceneFormat::splat);
  EXPECT_EQ(declared.gaussians, 93750000u);
  EXPECT_EQ(declared.file_bytes, 3000000000ull - 3000000000ull % 32);
}

TEST(FileKinds, UnreadableFile) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const fs::path path = fresh_dir("unreadable") / "point_cloud.ply";
  write_file(path, small_ply());
  fs::permissions(path, fs::perms::none);
  expect_refused(
      [&] {
        // Root reads any file: the child becomes "nobody" first.
        if (::geteuid() == 0 && ::setuid(65534) != 0) std::_Exit(2);
        load_ply(path.string());
      },
      path, "cannot open: permission denied");
}

// A file large enough for 2 MB pages (huge_pages.h) comes back byte for byte, with progress
// counting every byte.
TEST(FileKinds, ALargeFileIsReadWhole) {
  const fs::path path = fresh_dir("large_file") / "data.bin";
  std::string content(24u << 20, '\0');
  std::uint32_t x = 12345;
  for (char& c : content) c = static_cast<char>((x = x * 1664525u + 1013904223u) >> 24);
  write_file(path, content);
  LoadProgress progress;
  const std::vector<char> bytes = read_regular_file(path.string(), content.size(), &progress);
  ASSERT_EQ(bytes.size(), content.size());
  EXPECT_TRUE(std::equal(bytes.begin(), bytes.end(), content.begin()));
  EXPECT_EQ(progress.bytes_done.load(), content.size());
  EXPECT_EQ(progress.bytes_total.load(), content.size());
  // One byte more than allowed is refused before anything is read.
  try {
    read_regular_file(path.string(), content.size() - 1);
    ADD_FAILURE() << "a file over the limit was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("this kind of file may have"), std::string::npos) << e.what();
  }
}

TEST(SceneLocation, AFileIsThePlyAndItsCamerasAreBesideIt) {
  const fs::path dir = fresh_dir("file");
  write_file(dir / "scene.ply", small_ply());
  const SceneLocation location = locate_scene((dir / "scene.ply").string());
  EXPECT_EQ(location.ply, (dir / "scene.ply").string());
  EXPECT_EQ(location.cameras, (dir / "cameras.json").string());
}

TEST(SceneLocation, AFolderHoldingPointCloudPly) {
  const fs::path dir = fresh_dir("folder");
  write_file(dir / "point_cloud.ply", small_ply());
  const SceneLocation location = locate_scene(dir.string());
  EXPECT_EQ(location.ply, (dir / "point_cloud.ply").string());
  EXPECT_EQ(location.cameras, (dir / "cameras.json").string());
}

// <model>/point_cloud/iteration_<N>/point_cloud.ply, the highest N; cameras.json at the model root.
TEST(SceneLocation, ATrainingOutputFolder) {
  const fs::path model = fresh_dir("training_output");
  for (const char* iteration : {"iteration_7000", "iteration_30000", "iteration_999"}) {
    fs::create_directories(model / "point_cloud" / iteration);
    write_file(model / "point_cloud" / iteration / "point_cloud.ply", small_ply());
  }
  fs::create_directories(model / "point_cloud" / "iteration_40000");  // no PLY in it
  write_file(model / "cameras.json", demo_cameras_json());
  const fs::path latest = model / "point_cloud" / "iteration_30000";
  const SceneLocation location = locate_scene(model.string());
  EXPECT_EQ(location.ply, (latest / "point_cloud.ply").string());
  EXPECT_EQ(location.cameras, (model / "cameras.json").string());
  EXPECT_EQ(locate_scene(latest.string()).cameras, (model / "cameras.json").string());
}

// Iteration numbers past 64 bits (19 digits and more) still compare as numbers.
TEST(SceneLocation, ATrainingOutputWithIterationNumbersOfAnyLength) {
  const fs::path model = fresh_dir("training_output_long");
  for (const char* iteration : {"iteration_999999999999999999", "iteration_1000000000000000000",
                                "iteration_0000000000000000000000000000007"}) {
    fs::create_directories(model / "point_cloud" / iteration);
    write_file(model / "point_cloud" / iteration / "point_cloud.ply", small_ply());
  }
  const fs::path latest = model / "point_cloud" / "iteration_1000000000000000000";
  EXPECT_EQ(locate_scene(model.string()).ply, (latest / "point_cloud.ply").string());
  write_file(model / "cameras.json", demo_cameras_json());
  EXPECT_EQ(locate_scene(latest.string()).cameras, (model / "cameras.json").string());
}

TEST(SceneLocation, WhatIsNoScene) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const fs::path dir = fresh_dir("no_scene");
  const OddPaths odd(dir);
  fs::create_directories(dir / "fifo_inside");
  EXPECT_EQ(::mkfifo((dir / "fifo_inside" / "point_cloud.ply").c_str(), 0644), 0);
  const std::vector<std::tuple<fs::path, std::string>> cases = {
      {odd.folder, "a folder without point_cloud.ply"},
      {odd.fifo, "is a FIFO (named pipe), not a regular file"},
      {odd.device, "is a device, not a regular file"},
      {odd.loop, "cannot open: a loop of symbolic links"},
      {dir / "fifo_inside" / "point_cloud.ply", "is a FIFO (named pipe), not a regular file"},
      {dir / "missing.ply", "cannot open: no such file or folder"}};
  for (const auto& [path, fragment] : cases) {
    const std::string given = path.filename() == "point_cloud.ply" ? path.parent_path().string() : path.string();
    expect_refused([&] { locate_scene(given); }, path, fragment);
  }
  try {
    locate_scene("");
    ADD_FAILURE() << "an empty path was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "the scene path is empty: name a PLY file or a folder holding point_cloud.ply");
  }
}

// Exit status and output of `flashgs <args>`, run under `timeout` so that a hang fails the test.
struct CliRun {
  int exit_code = -1;
  std::string output;
};

CliRun run_cli(const std::string& args) {
  // One log per test, so that tests run in parallel (ctest -j) do not share one.
  const std::string test_name = testing::UnitTest::GetInstance()->current_test_info()->name();
  const std::string log = (fs::path(FLASHGS_TEST_OUTPUT_DIR) / "file_kinds" / (test_name + ".log")).string();
  const std::string command =
      "timeout " + std::to_string(kHangSeconds) + " " + FLASHGS_CLI + " " + args + " > " + log + " 2>&1";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(log);
  run.output.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return run;
}

std::string quoted_arg(const fs::path& path) { return "'" + path.string() + "'"; }

void expect_cli_error(const std::string& args, const std::string& message) {
  const CliRun run = run_cli(args);
  EXPECT_NE(run.exit_code, 124) << "flashgs " << args << " hung";
  EXPECT_EQ(run.exit_code, 2) << "flashgs " << args << ": " << run.output;
  EXPECT_EQ(run.output, "error: " + message + "\n") << "flashgs " << args;
}

TEST(FileKindsCli, TheSceneArgumentRefusesWhatIsNotAScene) {
  const OddPaths odd(fresh_dir("cli_scene"));
  const std::vector<std::tuple<fs::path, std::string>> cases = {
      {odd.folder, "a folder without point_cloud.ply (nor point_cloud/iteration_<N>/point_cloud.ply, as a 3DGS "
                   "training writes, nor a SOG lod-meta.json or meta.json)"},
      {odd.fifo, "is a FIFO (named pipe), not a regular file"},
      {odd.device, "is a device, not a regular file"},
      {odd.loop, "cannot open: a loop of symbolic links"},
      {odd.empty, "not a scene file: it is empty; expected a PLY, .splat, .ksplat, .spz or SOG"}};
  for (const char* command : {"info", "render"})
    for (const auto& [path, problem] : cases)
      expect_cli_error(std::string(command) + " " + quoted_arg(path), path.string() + ": " + problem);
  expect_cli_error("info ''", "the scene path is empty: name a PLY file or a scene folder, or leave it out for the "
                             "demo scene");
}

TEST(FileKindsCli, TheCamerasOptionRefusesWhatIsNotAFile) {
  const fs::path dir = fresh_dir("cli_cameras");
  const OddPaths odd(dir);
  write_file(dir / "scene.ply", small_ply());
  const std::string render = "render " + quoted_arg(dir / "scene.ply") + " -o " + quoted_arg(dir / "x.ppm") + " --cameras ";
  expect_cli_error(render + quoted_arg(odd.fifo), odd.fifo.string() + ": is a FIFO (named pipe), not a regular file");
  expect_cli_error(render + quoted_arg(odd.device), odd.device.string() + ": is a device, not a regular file");
  expect_cli_error(render + "''", "--cameras: the path is empty");
}

TEST(FileKindsCli, TheReplotOptionRefusesWhatIsNotAFile) {
  const OddPaths odd(fresh_dir("cli_replot"));
  expect_cli_error("report --replot " + quoted_arg(odd.fifo),
                   odd.fifo.string() + ": is a FIFO (named pipe), not a regular file");
  expect_cli_error("report --replot " + quoted_arg(odd.folder), odd.folder.string() + ": is a folder, not a file");
  expect_cli_error("report --replot " + quoted_arg(odd.device), odd.device.string() + ": is a device, not a regular file");
}

TEST(FileKindsCli, SceneFolderAndTrainingOutputRender) {
  const fs::path folder = fresh_dir("cli_folder");
  write_file(folder / "point_cloud.ply", small_ply());
  write_file(folder / "cameras.json", demo_cameras_json());
  const fs::path model = fresh_dir("cli_training_output");
  fs::create_directories(model / "point_cloud" / "iteration_30000");
  write_file(model / "point_cloud" / "iteration_30000" / "point_cloud.ply", small_ply());
  write_file(model / "cameras.json", demo_cameras_json());
  for (const fs::path& scene : {folder, model}) {
    const fs::path image = scene / "render.ppm";
    const CliRun run = run_cli("render " + quoted_arg(scene) + " --backend cpu -r 32x18 -o " + quoted_arg(image));
    EXPECT_EQ(run.exit_code, 0) << run.output;
    EXPECT_TRUE(fs::exists(image)) << run.output;
  }
  const CliRun info = run_cli("info " + quoted_arg(model));
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("iteration_30000/point_cloud.ply"), std::string::npos) << info.output;
}

}  // namespace
}  // namespace flashgs
