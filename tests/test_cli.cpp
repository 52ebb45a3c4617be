// The `flashgs` binary on bad input: one line naming the option or file, a non-zero exit, no
// crash, and nothing written or rendered first.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "flashgs/backend_tuning.h"
#include "flashgs/demo_scene.h"
#include "flashgs/generators.h"
#include "flashgs/image.h"
#include "flashgs/image_io.h"
#include "flashgs/io.h"
#include "flashgs/keyframe_path.h"
#include "format_builders.h"
#include "ply_builder.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

struct CliResult {
  int exit_code = -1;  // -1 when killed by a signal
  int signal = 0;
  std::string output;  // stdout and stderr together
  std::vector<std::string> error_lines() const {
    std::vector<std::string> lines;
    std::istringstream in(output);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("error", 0) == 0) lines.push_back(line);
    return lines;
  }
};

std::string scratch_dir(const std::string& name) {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/cli/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// What run_cli holds the binary to (setrlimit and alarm in the child, as `prlimit` and
// `timeout` would); 0 leaves a limit off.
struct ChildLimits {
  std::size_t address_space_bytes = 0;
  // A write past this size fails with EFBIG ("File too large"), as a write to a full disk fails.
  std::size_t file_size_bytes = 0;
  // SIGALRM ends a run that takes longer: a hang fails the test instead of stalling it.
  unsigned seconds = 0;
};

// Seconds a run that must fail at once may take before the test calls it hung.
constexpr unsigned kHangSeconds = 60;

// Runs `flashgs <arguments>` through the shell within `limits`.
CliResult run_cli(const std::string& arguments, const ChildLimits& limits = {}) {
  // A pipe, not a log file: a file-size limit would cut the log too.
  int output[2];
  if (pipe(output) != 0) return {};
  const std::string command = std::string(FLASHGS_CLI) + " " + arguments;
  const pid_t child = fork();
  if (child == 0) {
    if (limits.address_space_bytes) {
      const rlimit limit{limits.address_space_bytes, limits.address_space_bytes};
      setrlimit(RLIMIT_AS, &limit);
    }
    if (limits.file_size_bytes) {
      signal(SIGXFSZ, SIG_IGN);  // the write returns EFBIG instead of killing the process
      const rlimit limit{limits.file_size_bytes, limits.file_size_bytes};
      setrlimit(RLIMIT_FSIZE, &limit);
    }
    if (limits.seconds) alarm(limits.seconds);  // kept across exec
    close(output[0]);
    dup2(output[1], 1);
    dup2(output[1], 2);
    close(output[1]);
    // exec, not the shell's own fork: the status is the binary's, a signal included.
    execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(output[1]);
  CliResult r;
  char chunk[4096];
  for (ssize_t n; (n = read(output[0], chunk, sizeof chunk)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    r.output.append(chunk, static_cast<std::size_t>(n));
  }
  close(output[0]);
  int status = 0;
  waitpid(child, &status, 0);
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

// The failure every bad input must give: a non-zero exit (not a signal), and exactly one
// error line, which contains `fragment` (the option or file, and the problem).
void expect_one_line_error(const CliResult& r, const std::string& fragment, const std::string& what) {
  EXPECT_EQ(r.signal, 0) << what << ": killed by signal " << r.signal << "\n" << r.output;
  EXPECT_GT(r.exit_code, 0) << what << "\n" << r.output;
  const std::vector<std::string> lines = r.error_lines();
  EXPECT_EQ(lines.size(), 1u) << what << "\n" << r.output;
  std::size_t all_lines = 0;
  for (char c : r.output) all_lines += c == '\n';
  EXPECT_EQ(all_lines, 1u) << what << ": more than the error line\n" << r.output;
  EXPECT_NE(r.output.find(fragment), std::string::npos) << what << ": no \"" << fragment << "\" in\n" << r.output;
}

TEST(CliOptions, NonFiniteValuesAreRejected) {
  const std::string out = scratch_dir("non_finite") + "/x.ppm";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--tau nan", "--tau"},
      {"--tau inf", "--tau"},
      {"--background nan,0,0", "--background"},
      {"--background 0,inf,0", "--background"},
      {"--background 0,0,2", "--background"},
      {"--fov nan", "--fov"},
      {"--eye nan,0,0 --look-at 0,0,1", "--eye"},
      {"--eye 0,0,0 --look-at 0,-inf,1", "--look-at"},
      {"--eye 0,0,0 --look-at 0,0,1 --up 0,nan,0", "--up"},
  };
  for (const auto& [arguments, option] : cases) {
    const CliResult r = run_cli("render -r 64x36 -o " + out + " " + arguments);
    expect_one_line_error(r, option, arguments);
    EXPECT_FALSE(fs::exists(out)) << arguments << ": an image was written";
  }
}

TEST(CliOptions, DegenerateLookAtIsRejected) {
  const std::string out = scratch_dir("look_at") + "/x.ppm";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--eye 1,2,3 --look-at 1,2,3", "--eye and --look-at are the same point"},
      {"--eye 0,0,0 --look-at 0,5,0", "--up is parallel to the view direction"},  // up = 0,-1,0
      {"--eye 0,0,0 --look-at 0,0,1 --up 0,0,0", "--up is the zero vector"},
  };
  for (const auto& [arguments, message] : cases) {
    const CliResult r = run_cli("render -r 64x36 -o " + out + " " + arguments);
    expect_one_line_error(r, message, arguments);
    EXPECT_EQ(r.exit_code, 2) << arguments;
    EXPECT_FALSE(fs::exists(out)) << arguments;
  }
}

TEST(CliOptions, ResolutionIsRangeChecked) {
  const std::string out = scratch_dir("resolution") + "/x.ppm";
  // 4294967312 = 2^32 + 16: sscanf's %d wrapped it to 16.
  for (const char* text : {"4294967312x9", "16x4294967305", "65537x2", "0x9", "-16x9", "16x9x", "16 x9"}) {
    const CliResult r = run_cli(std::string("render -o ") + out + " '--resolution=" + text + "'");
    expect_one_line_error(r, std::string("resolution \"") + text + "\"", text);
    EXPECT_FALSE(fs::exists(out)) << text;
  }
}

TEST(CliOptions, OutputPathIsCheckedBeforeRendering) {
  const std::string dir = scratch_dir("output_path");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {dir + "/missing/x.png", "the folder " + dir + "/missing does not exist"},
      {dir + "/x.unknown_format", "unknown image format"},
      {dir, "is a folder"},
      {"''", "--output: the output path is empty"},
  };
  for (const auto& [path, fragment] : cases) {
    // A frame that costs seconds of CPU to render: the error must come before it.
    const double cpu_before = test::children_cpu_seconds();
    const CliResult r = run_cli("render -r 4096x2304 -o " + path);
    const double seconds = test::children_cpu_seconds() - cpu_before;
    expect_one_line_error(r, fragment, path);
    EXPECT_LT(seconds, 1.5 * test::kSanitizerSlowdown) << path << ": rendered first";
  }
}

TEST(CliOptions, CameraListsAreCheckedAgainstTheFile) {
  const std::string dir = scratch_dir("camera_list");
  const std::string cameras = demo_cameras_path();
  const std::size_t count = load_cameras(cameras).size();
  const std::string missing = std::to_string(count + 63);
  const std::string quick = " --backend cpu -r 32x18 ";
  expect_one_line_error(run_cli("report --camera-list 0," + missing + quick + "--repeat 1 -o " + dir),
                        "--camera-list: camera " + missing + " does not exist (" + cameras, "report 0," + missing);
  expect_one_line_error(run_cli("report --camera-list abc" + quick + "-o " + dir), "--camera-list", "report abc");
  expect_one_line_error(run_cli("bench --camera-list 1," + missing + quick + "--json " + dir + "/b.json"),
                        "--camera-list: camera " + missing + " does not exist (" + cameras, "bench 1," + missing);
  expect_one_line_error(run_cli("render -c " + missing + quick + "-o " + dir + "/r.png"),
                        "--camera: camera " + missing + " does not exist (" + cameras, "render -c " + missing);
  EXPECT_FALSE(fs::exists(dir + "/report.csv"));
  EXPECT_FALSE(fs::exists(dir + "/r.png"));
}

// CLI11 read "" as 0 and "0x1" as 1, and dropped empty list items: each rendered or swept
// a camera the user did not name instead of saying what is wrong with the value.
TEST(CliOptions, IntegersListsAndSizesAreStrict) {
  const std::string dir = scratch_dir("strict_values");
  const std::string quick = " --backend cpu -r 32x18 ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"render -r 32x18 -o " + dir + "/r.ppm -c ''", "--camera: the value is empty"},
      {"render -r 32x18 -o " + dir + "/r.ppm -c 0x1", "--camera: \"0x1\" is not a whole number"},
      {"render -r 32x18 -o " + dir + "/r.ppm -c ' 1'", "--camera: \" 1\" is not a whole number"},
      {"render -o " + dir + "/r.ppm -r ''", "--resolution: the value is empty; expected WxH"},
      {"render -r 32x18 -o " + dir + "/r.ppm --repeat 1e1", "--repeat: \"1e1\" is not a whole number"},
      {"report --camera-list 0,,1" + quick + "-o " + dir, "--camera-list: item 2 of \"0,,1\" is empty"},
      {"report --camera-list ''" + quick + "-o " + dir, "--camera-list: the list is empty"},
      {"report --camera-list 0,1," + quick + "-o " + dir, "--camera-list: item 3 of \"0,1,\" is empty"},
      {"bench --camera-list 0,,1" + quick + "--json " + dir + "/b.json", "--camera-list: item 2 of \"0,,1\" is empty"},
      {"generate demo --count 0x10 -o " + dir, "--count: \"0x10\" is not a whole number"},
  };
  for (const auto& [arguments, fragment] : cases) expect_one_line_error(run_cli(arguments), fragment, arguments);
  EXPECT_FALSE(fs::exists(dir + "/r.ppm"));
  EXPECT_FALSE(fs::exists(dir + "/report.csv"));
  EXPECT_FALSE(fs::exists(dir + "/point_cloud.ply"));
}

// The range of a coordinate option is float's: printed in full it was dozens of digits.
TEST(CliOptions, RangeTextIsShort) {
  const CliResult r = run_cli("render -r 32x18 -o " + scratch_dir("range_text") + "/r.ppm --eye 1e300,0,0 --look-at 0,0,1");
  expect_one_line_error(r, "--eye: 1e300 is outside [-3.4e+38, 3.4e+38]", "--eye 1e300");
  EXPECT_LT(r.output.size(), 120u) << r.output;
}

// What the user typed comes back in messages: an escape sequence in it must not reach the
// terminal as one.
TEST(CliOptions, ControlBytesInValuesAreEscaped) {
  const std::string dir = scratch_dir("control_bytes");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"render --backend '\x1b[31mx' -o " + dir + "/r.ppm", "--backend: \\x1b[31mx"},
      {"render --tau '\x1b[2J' -o " + dir + "/r.ppm", "\"\\x1b[2J\" is not a number"},
      {"render -c '1\x1b' -o " + dir + "/r.ppm", "\"1\\x1b\" is not a whole number"},
      {"info '" + dir + "/\x1b[2Jmissing.ply'", "/\\x1b[2Jmissing.ply: cannot open"},
  };
  for (const auto& [arguments, fragment] : cases) {
    const CliResult r = run_cli(arguments);
    expect_one_line_error(r, fragment, arguments);
    EXPECT_EQ(r.output.find('\x1b'), std::string::npos) << arguments;
  }
}

// report and generate made their output folder first and left it behind when the scene or
// the input then failed.
TEST(CliOutputs, AFailedCommandLeavesNoFolderOfItsOwn) {
  const std::string dir = scratch_dir("no_folder_left");
  expect_one_line_error(run_cli("report " + dir + "/missing.ply --backend cpu -r 32x18 -o " + dir + "/rep/sub"),
                        "missing.ply: cannot open", "report of a missing scene");
  EXPECT_FALSE(fs::exists(dir + "/rep"));
  expect_one_line_error(run_cli("generate tile -i " + dir + "/missing.ply -o " + dir + "/gen"),
                        "missing.ply: cannot open", "tile of a missing scene");
  EXPECT_FALSE(fs::exists(dir + "/gen"));
  // A folder that was there before stays, and so does one the command filled.
  fs::create_directories(dir + "/kept");
  expect_one_line_error(run_cli("generate tile -i " + dir + "/missing.ply -o " + dir + "/kept"),
                        "missing.ply: cannot open", "tile into a folder that exists");
  EXPECT_TRUE(fs::is_directory(dir + "/kept"));
}

// The demo scene at 51200x28800: 17.7 GB of image alone. Under a 2 GB address-space limit
// the frame is refused before rendering, with the estimate and what is available (it was a
// std::bad_alloc inside an OpenMP region: std::terminate, SIGABRT).
TEST(CliMemory, FrameTooLargeForTheAddressSpaceIsRefused) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const std::string out = scratch_dir("too_large") + "/x.ppm";
  const CliResult r = run_cli("render --backend cpu -r 51200x28800 -o " + out, {std::size_t{2} << 30});
  expect_one_line_error(r, "--resolution: a 51200x28800 frame needs about", "51200x28800");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("is available (the address-space limit, RLIMIT_AS)"), std::string::npos) << r.output;
}

// A frame whose image is small but whose Gaussian-tile pairs are not: 20000 Gaussians, each
// covering all 8192 tiles of a 2048x1024 frame, are 164M pairs (2 GB) that ran out of address
// space inside the emit stage's parallel region. They are counted from the projected boxes and
// refused before emit allocates them: an error naming the frame and the figures, exit 2.
TEST(CliMemory, PairsThatCannotFitAreRefusedBeforeTheyAreMade) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const std::string dir = scratch_dir("pairs_oom");
  test::PlyBuilder b = test::PlyBuilder::inria(0, 20000);
  for (std::size_t i = 0; i < b.vertices.size(); ++i) {
    b.vertices[i][b.index_of("x")] = 0;
    b.vertices[i][b.index_of("z")] = 0.001 * static_cast<double>(i);
    for (const char* s : {"scale_0", "scale_1", "scale_2"}) b.vertices[i][b.index_of(s)] = std::log(20.0);
  }
  std::ofstream(dir + "/point_cloud.ply", std::ios::binary) << b.bytes();
  const CliResult r = run_cli("render " + dir + "/point_cloud.ply --backend cpu --eye 0,0,-5 --look-at 0,0,0 " +
                                  "-r 2048x1024 -o " + dir + "/x.ppm",
                              {std::size_t{1} << 30});
  expect_one_line_error(r, "cpu renderer: a 2048x1024 frame of these 20000 visible Gaussians would make about 0.164 "
                           "billion Gaussian-tile pairs", "pairs out of memory");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("is available (the address-space limit, RLIMIT_AS)"), std::string::npos) << r.output;
}

// 50,000 needles: the baseline's square boxes give them 3DGS's pairs, far more than flash's
// ellipses touch. Under a 2 GB address-space limit the baseline frame is refused with its
// exact count before any pair is made, and flash renders the same frame.
TEST(CliMemory, BaselineNeedlesAreRefusedWhereFlashRenders) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const std::string dir = scratch_dir("needles");
  test::PlyBuilder b = test::PlyBuilder::inria(0, 50000);
  std::mt19937 rng(51);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (auto& v : b.vertices) {
    for (const char* axis : {"x", "y", "z"}) v[b.index_of(axis)] = unit(rng);
    v[b.index_of("scale_0")] = 0.5;
    v[b.index_of("scale_1")] = v[b.index_of("scale_2")] = -9.0;
    v[b.index_of("opacity")] = 3.0;
    for (const char* r : {"rot_0", "rot_1", "rot_2", "rot_3"}) v[b.index_of(r)] = unit(rng);
  }
  std::ofstream(dir + "/needles.ply", std::ios::binary) << b.bytes();
  const std::string render = "render " + dir + "/needles.ply --backend cpu --eye 0,0,-5 --look-at 0,0,0 -o " + dir;
  const CliResult baseline = run_cli(render + "/baseline.ppm -a baseline", {std::size_t{2} << 30});
  expect_one_line_error(baseline, "cpu renderer: a 1920x1080 frame of these", "baseline needles");
  EXPECT_NE(baseline.output.find("visible Gaussians would make 0."), std::string::npos) << baseline.output;
  EXPECT_FALSE(fs::exists(dir + "/baseline.ppm"));
  const CliResult flash = run_cli(render + "/flash.ppm", {std::size_t{2} << 30});
  EXPECT_EQ(flash.exit_code, 0) << flash.output;
}

// A keyframed path round trip: written, read by `render --path`, and its frames at the two
// keys' times are `render --eye/--look-at` at those poses; between them, neither.
TEST(CliRender, ACameraPathRendersItsKeysAsTheExplicitCameraDoes) {
  const std::string dir = scratch_dir("camera_path");
  const std::string ext = image_io_writes_png() ? ".png" : ".ppm";
  const float up[3] = {0, -1, 0};
  const float eye0[3] = {0.2f, -0.3f, -3.0f}, eye1[3] = {2.0f, -0.5f, -2.0f}, target[3] = {0, 0, 0};
  KeyframePath path;
  path.keys = {Keyframe::from_camera(look_at_camera(eye0, target, up, 160, 90, 70.0f), 0.0),
               Keyframe::from_camera(look_at_camera(eye1, target, up, 160, 90, 55.0f), 1.0)};
  path.fps = 4;  // frames at 0, 0.25, 0.5, 0.75 and 1 s
  path.width = 160;
  path.height = 90;
  write_camera_path(path, dir + "/path.json");
  const CliResult r = run_cli("render " + demo_scene_path() + " --backend cpu --path " + dir + "/path.json -o " + dir + "/frames");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote 5 frames to " + dir + "/frames"), std::string::npos) << r.output;
  const auto explicit_render = [&](const float* eye, float fov, const std::string& name) {
    const CliResult e = run_cli("render " + demo_scene_path() + " --backend cpu -r 160x90 --eye " + std::to_string(eye[0]) +
                                "," + std::to_string(eye[1]) + "," + std::to_string(eye[2]) + " --look-at 0,0,0 --fov " +
                                std::to_string(fov) + " -o " + dir + "/" + name + ext);
    EXPECT_EQ(e.exit_code, 0) << e.output;
    return read_image(dir + "/" + name + ext);
  };
  const Image key0 = explicit_render(eye0, 70.0f, "key0"), key1 = explicit_render(eye1, 55.0f, "key1");
  const Image first = read_image(dir + "/frames/frame_00000" + ext), last = read_image(dir + "/frames/frame_00004" + ext);
  const Image middle = read_image(dir + "/frames/frame_00002" + ext);
  ASSERT_EQ(first.width, 160);
  EXPECT_GE(compare_images(first, key0).psnr_db, 40.0);
  EXPECT_GE(compare_images(last, key1).psnr_db, 40.0);
  EXPECT_LT(compare_images(middle, key0).psnr_db, 30.0) << "the middle frame is not between the keys";
  EXPECT_LT(compare_images(middle, key1).psnr_db, 30.0) << "the middle frame is not between the keys";
  EXPECT_FALSE(fs::exists(dir + "/frames/frame_00005" + ext));
  // A bad path file: one line naming it, nothing rendered.
  std::ofstream(dir + "/bad.json") << R"({"format": "flashgs camera path", "version": 1, "fps": 30, "keyframes": []})";
  const CliResult bad = run_cli("render " + demo_scene_path() + " --backend cpu --path " + dir + "/bad.json -o " + dir + "/none");
  expect_one_line_error(bad, dir + "/bad.json: \"keyframes\" is empty", "empty path");
  EXPECT_FALSE(fs::exists(dir + "/none/frame_00000" + ext));
}

// `bench --tile N` renders N copies of the scene (scale runs), reports the upload and the
// first frame apart, and refuses copies that cannot fit in memory before making any.
TEST(CliBench, TiledSceneIsBenchedAndTooManyCopiesAreRefused) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  const std::string dir = scratch_dir("bench_tile");
  const std::size_t demo = load_ply(demo_scene_path()).size();
  const std::string quick = " --backend cpu -r 32x18 --camera-list 0 --configs flash --warmup 0 --repeat 1 --json ";
  const CliResult r = run_cli("bench --tile 3" + quick + dir + "/b.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(": " + std::to_string(3 * demo) + " Gaussians"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("flash                        scene upload"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("first frame"), std::string::npos) << r.output;

  const CliResult huge = run_cli("bench --tile 4096" + quick + dir + "/c.json", {std::size_t{1} << 30});
  expect_one_line_error(huge, "--tile: 4096 copies need", "4096 copies");
  EXPECT_FALSE(fs::exists(dir + "/c.json"));
}

// `bench --frames`: frames queued back to back (the default) need a backend with a queue; the
// CPU backend's frames are waited for whatever is asked, and the header and the JSON say so. An
// unknown mode is one line naming the option.
TEST(CliBench, FrameModeIsReportedAndChecked) {
  const std::string dir = scratch_dir("bench_frames");
  const std::string quick = " --backend cpu -r 32x18 --camera-list 0 --configs flash --warmup 0 --repeat 1 --json ";
  const CliResult r = run_cli("bench --frames queued" + quick + dir + "/b.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("timed frames each, each downloaded and waited for;"), std::string::npos) << r.output;
  std::ifstream json(dir + "/b.json");
  const std::string text((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"frames\": \"waited\""), std::string::npos) << text.substr(0, 400);
  expect_one_line_error(run_cli("bench --frames sometimes" + quick + dir + "/c.json"), "--frames", "--frames sometimes");
  EXPECT_FALSE(fs::exists(dir + "/c.json"));
}

// The fp16 options in the sweeps: `report` has their rows (group "precision", columns fp16_sh
// and fp16_shape set, an error against the fp64 reference) beside flash's, and `bench` theirs.
std::vector<std::vector<std::string>> read_csv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

TEST(CliReport, Fp16OptionsAreSweptWithTheirErrorAgainstTheReference) {
  const std::string dir = scratch_dir("report_fp16");
  const CliResult r = run_cli("report --backend cpu -r 64x36 --camera-list 0 --repeat 1 --ref-window 16 -o " + dir);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = read_csv(dir + "/report.csv");
  ASSERT_GT(rows.size(), 2u);
  auto column = [&](const std::string& name) {
    const auto it = std::find(rows[0].begin(), rows[0].end(), name);
    EXPECT_NE(it, rows[0].end()) << "no column " << name;
    return static_cast<std::size_t>(it - rows[0].begin());
  };
  const std::size_t config = column("config"), group = column("group"), fp16_sh = column("fp16_sh"),
                    fp16_shape = column("fp16_shape"), psnr = column("psnr_vs_fp64_db");
  std::map<std::string, std::vector<std::string>> by_name;
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (rows[i].size() == rows[0].size()) by_name[rows[i][config]] = rows[i];
  ASSERT_TRUE(by_name.count("flash"));
  EXPECT_EQ(by_name["flash"][fp16_sh], "0");
  EXPECT_EQ(by_name["flash"][fp16_shape], "0");
  // name, fp16_sh, fp16_shape
  for (const auto& [name, sh, shape] : {std::tuple<std::string, const char*, const char*>{"fp16-sh", "1", "0"},
                                        {"fp16-shape", "0", "1"},
                                        {"fp16-all", "1", "1"}}) {
    ASSERT_TRUE(by_name.count(name)) << name << "\n" << r.output;
    EXPECT_EQ(by_name[name][group], "precision") << name;
    EXPECT_EQ(by_name[name][fp16_sh], sh) << name;
    EXPECT_EQ(by_name[name][fp16_shape], shape) << name;
    const double fp16_psnr = std::strtod(by_name[name][psnr].c_str(), nullptr);
    EXPECT_GT(fp16_psnr, 40.0) << name << " " << by_name[name][psnr];
    EXPECT_NE(by_name[name][psnr], by_name["flash"][psnr]) << name << " must change the image";
  }
  // The half blend is a CUDA kernel: the CPU's report has its column, 0 on every row, and no row of it.
  const std::size_t fp16_blend = column("fp16_blend");
  for (const auto& [name, row] : by_name) EXPECT_EQ(row[fp16_blend], "0") << name;
  EXPECT_FALSE(by_name.count("fp16-blend"));

  const CliResult bench = run_cli("bench --backend cpu -r 32x18 --camera-list 0 --warmup 0 --repeat 1 --configs "
                                  "flash-fp16_sh,flash-fp16_shape,flash-fp16_sh-fp16_shape,flash-fp16_blend --json " +
                                  dir + "/b.json");
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  for (const char* label : {"flash-fp16_sh", "flash-fp16_shape", "flash-fp16_sh-fp16_shape", "flash-fp16_blend"})
    EXPECT_NE(bench.output.find(std::string("\n32x18      ") + label + " "), std::string::npos) << label << "\n"
                                                                                               << bench.output;
}

// `bench --configs all` on the CPU leaves out the rows that would repeat another: the GPU
// switches (each would be "flash") and the half blend (alone "flash", with the fp16 storage
// "flash-fp16_sh-fp16_shape").
TEST(CliBench, AllConfigsOnTheCpuRepeatNoRow) {
  const std::string dir = scratch_dir("bench_all_cpu");
  const CliResult r = run_cli("bench --backend cpu -r 32x18 --camera-list 0 --warmup 0 --repeat 1 --configs all --json " +
                              dir + "/b.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto has_row = [&](const std::string& label) {
    return r.output.find("\n32x18      " + label + " ") != std::string::npos;
  };
  for (const char* label : {"baseline", "flash", "flash-no_tight_bbox", "flash-fp16_sh", "flash-fp16_sh-fp16_shape"})
    EXPECT_TRUE(has_row(label)) << label << "\n" << r.output;
  for (const char* label : {"flash-no_warp_emit", "flash-fp16_blend", "flash-fp16_sh-fp16_shape-fp16_blend"})
    EXPECT_FALSE(has_row(label)) << label << "\n" << r.output;
}

TEST(CliGenerate, RefusesToOverwriteAScene) {
  const std::string dir = scratch_dir("overwrite");
  ASSERT_EQ(run_cli("generate demo --count 300 -o " + dir).exit_code, 0);
  const std::string ply = dir + "/point_cloud.ply";
  const auto size = fs::file_size(ply);

  expect_one_line_error(run_cli("generate demo --count 100 -o " + dir), "already holds " + ply, "demo again");
  // The source scene as the output: refused, and the source is intact.
  expect_one_line_error(run_cli("generate tile -i " + ply + " -n 4 -o " + dir), "--force", "tile onto its source");
  EXPECT_EQ(fs::file_size(ply), size);
  EXPECT_EQ(load_ply(ply).size(), 300u);

  // With --force: the source read first, the result renamed over it, nothing partial left.
  ASSERT_EQ(run_cli("generate tile -i " + ply + " -n 4 -o " + dir + " --force").exit_code, 0);
  EXPECT_EQ(load_ply(ply).size(), 4 * 300u);
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
}

// --list lists the stress cases and writes nothing (without a kind it used to write the demo).
TEST(CliGenerate, ListWritesNoScene) {
  const std::string dir = scratch_dir("list");
  const CliResult listed = run_cli("generate --list -o " + dir);
  EXPECT_EQ(listed.exit_code, 0) << listed.output;
  EXPECT_NE(listed.output.find("stiff_1e4 "), std::string::npos) << listed.output;
  EXPECT_FALSE(fs::exists(dir + "/point_cloud.ply"));
  expect_one_line_error(run_cli("generate demo --list -o " + dir), "--list: lists the stress cases", "demo --list");
  EXPECT_FALSE(fs::exists(dir + "/point_cloud.ply"));
}

TEST(CliGenerate, CountMustBePositive) {
  const std::string dir = scratch_dir("count");
  for (const char* count : {"0", "-1", "nan", "1e99"}) {
    expect_one_line_error(run_cli(std::string("generate demo --count ") + count + " -o " + dir), "--count", count);
    EXPECT_FALSE(fs::exists(dir + "/point_cloud.ply")) << count;
  }
}

TEST(CliConvert, ConvertsBetweenTheFormats) {
  const std::string dir = scratch_dir("convert");
  ASSERT_EQ(run_cli("generate demo --count 300 -o " + dir).exit_code, 0);
  const std::string ply = dir + "/point_cloud.ply", splat = dir + "/scene.splat", back = dir + "/back.ply";
  const CliResult to_splat = run_cli("convert " + ply + " " + splat);
  ASSERT_EQ(to_splat.exit_code, 0) << to_splat.output;
  EXPECT_NE(to_splat.output.find("(INRIA PLY, 300 Gaussians"), std::string::npos) << to_splat.output;
  EXPECT_EQ(fs::file_size(splat), 300u * 32);
  const CliResult to_ply = run_cli("convert " + splat + " " + back);
  ASSERT_EQ(to_ply.exit_code, 0) << to_ply.output;
  EXPECT_NE(to_ply.output.find("(.splat (antimatter15), 300 Gaussians"), std::string::npos) << to_ply.output;
  // Positions are float32 in all three files.
  EXPECT_EQ(load_ply(back).positions, load_ply(ply).positions);
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos) << entry.path();
}

// The name picks the writer (x.compressed.ply is no plain PLY), and the loss is printed.
TEST(CliConvert, TheNamePicksTheFormatAndTheLossIsPrinted) {
  const std::string dir = scratch_dir("convert_formats");
  ASSERT_EQ(run_cli("generate demo --count 600 -o " + dir).exit_code, 0);
  const std::string ply = dir + "/point_cloud.ply";
  const CliResult compressed = run_cli("convert " + ply + " " + dir + "/x.compressed.ply");
  ASSERT_EQ(compressed.exit_code, 0) << compressed.output;
  EXPECT_NE(compressed.output.find("wrote " + dir + "/x.compressed.ply (PlayCanvas compressed PLY)"), std::string::npos)
      << compressed.output;
  std::size_t written = 0, read_back = 1;
  const std::size_t loss_at = compressed.output.find("loss: ");
  ASSERT_NE(loss_at, std::string::npos) << compressed.output;
  ASSERT_EQ(std::sscanf(compressed.output.c_str() + loss_at, "loss: %zu Gaussians written, %zu read back", &written,
                        &read_back), 2) << compressed.output;
  EXPECT_EQ(read_back, written);
  EXPECT_GT(written, 500u);
  EXPECT_NE(compressed.output.find("loss:   position"), std::string::npos) << compressed.output;
  EXPECT_NE(compressed.output.find(" dB against the input's"), std::string::npos) << compressed.output;
  const CliResult info = run_cli("info " + dir + "/x.compressed.ply");
  EXPECT_NE(info.output.find("format:          PlayCanvas compressed PLY\n"), std::string::npos) << info.output;

  const CliResult reduced = run_cli("convert " + ply + " " + dir + "/x.spz --sh-degree 0 --spz-version 4 --no-loss");
  ASSERT_EQ(reduced.exit_code, 0) << reduced.output;
  EXPECT_EQ(reduced.output.find("loss:"), std::string::npos) << reduced.output;
  EXPECT_NE(run_cli("info " + dir + "/x.spz").output.find("sh degree:       0"), std::string::npos);
  expect_one_line_error(run_cli("convert " + ply + " " + dir + "/y.spz --spz-axes opengl"), "--spz-axes", "bad axes");
  expect_one_line_error(run_cli("convert " + ply + " " + dir + "/y.spz --spz-version 2"), "--spz-version", "bad version");
  EXPECT_FALSE(fs::exists(dir + "/y.spz"));
}

// A .splat scale may be negative; PLY stores log scales: the conversion says how many
// Gaussians it changes, and the PLY holds them all, with finite scales of the same size.
TEST(CliConvert, NegativeScalesAreNamedAndKept) {
  const std::string dir = scratch_dir("convert_negative");
  std::string records;
  for (int i = 0; i < 16; ++i) {
    const float values[6] = {0.1f * i, 0.0f, 2.0f, i < 4 ? -0.05f : 0.05f, 0.05f, 0.05f};
    records.append(reinterpret_cast<const char*>(values), sizeof values);
    records += std::string("\xc8\x64\x32\xff\xff\x80\x80\x80", 8);
  }
  std::ofstream(dir + "/negative.splat", std::ios::binary) << records;
  const CliResult result = run_cli("convert " + dir + "/negative.splat " + dir + "/negative.ply");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("note: 4 of 16 Gaussians of " + dir + "/negative.splat have a negative scale"),
            std::string::npos) << result.output;
  LoadReport report;
  const Scene back = load_ply(dir + "/negative.ply", &report);
  EXPECT_EQ(back.size(), 16u);
  EXPECT_EQ(report.dropped_non_finite, 0u);
  EXPECT_NEAR(back.scales[0], 0.05f, 1e-7f);
}

TEST(CliConvert, BadOutputsAreRefusedBeforeReading) {
  const std::string dir = scratch_dir("convert_bad");
  ASSERT_EQ(run_cli("generate demo --count 300 -o " + dir).exit_code, 0);
  const std::string ply = dir + "/point_cloud.ply";
  const auto size = fs::file_size(ply);
  expect_one_line_error(run_cli("convert " + ply + " " + dir + "/out.obj"),
                        "OUT " + dir + "/out.obj: unknown scene format (the name picks it: .ply (INRIA PLY), "
                        ".compressed.ply, .splat, .spz, .sog", "unknown extension");
  EXPECT_FALSE(fs::exists(dir + "/out.obj"));
  expect_one_line_error(run_cli("convert " + ply + " " + ply), "is the input file itself", "same path");
  expect_one_line_error(run_cli("convert " + ply + " " + dir + "/../convert_bad/point_cloud.ply --force"),
                        "is the input file itself", "same file by another path");
  EXPECT_EQ(fs::file_size(ply), size);
  std::ofstream(dir + "/old.splat") << "keep";
  expect_one_line_error(run_cli("convert " + ply + " " + dir + "/old.splat"), "already exists (give --force",
                        "existing output");
  EXPECT_EQ(fs::file_size(dir + "/old.splat"), 4u);
}

TEST(CliInfo, ShowsTheFormatItsQuantisationAndTheDecodeTime) {
  const std::string dir = scratch_dir("info_format");
  const std::string path = dir + "/scene.compressed.ply";
  const std::string bytes = test::compressed_ply_bytes(600, 1);
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const CliResult r = run_cli("info " + path);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("format:          PlayCanvas compressed PLY\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("in 256-Gaussian chunks"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(", decoded in "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gaussians:       600\n"), std::string::npos) << r.output;
}

// The names in `dir`, sorted: what a command left there.
std::vector<std::string> names_in(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// An output that is a FIFO is refused before any work: writing opened it, which blocks until a
// reader comes, so each of these hung for ever (bench and report after all their work).
TEST(CliOutputs, AFifoAsAnOutputIsRefusedBeforeAnyWork) {
  const std::string dir = scratch_dir("fifo_outputs");
  std::vector<std::pair<std::string, std::string>> cases = {  // arguments, the error's start
      {"render -r 4096x2304 -o " + dir + "/r.png", "--output " + dir + "/r.png"},
      {"bench --backend cpu --json " + dir + "/b.json", "--json " + dir + "/b.json"},
      {"check --backend cpu --csv " + dir + "/c.csv", "--csv " + dir + "/c.csv"},
  };
  for (const char* name : {"report.csv", "report.md", "report_cpu.svg"}) {
    const std::string folder = dir + "/report_" + name;
    fs::create_directories(folder);
    cases.push_back({"report --backend cpu -o " + folder, "--output-dir " + folder + "/" + name});
  }
  for (const auto& [arguments, option_and_path] : cases) {
    const std::string fifo = option_and_path.substr(option_and_path.find(' ') + 1);
    ASSERT_EQ(mkfifo(fifo.c_str(), 0644), 0) << fifo;
    // Each command's full run costs minutes of CPU: the error must come before it.
    const double cpu_before = test::children_cpu_seconds();
    const CliResult r = run_cli(arguments, {0, 0, kHangSeconds});
    const double seconds = test::children_cpu_seconds() - cpu_before;
    expect_one_line_error(r, option_and_path + ": is a FIFO (named pipe), not a regular file", arguments);
    EXPECT_LT(seconds, 1.5 * test::kSanitizerSlowdown) << arguments << ": worked first";
    EXPECT_TRUE(fs::is_fifo(fifo)) << fifo << " was replaced";
  }
}

// `check --case NAME --csv FILE` opened the CSV before it looked the case up: with a FIFO there
// it hung instead of naming the case.
TEST(CliCheck, AnUnknownCaseIsNamedBeforeTheCsvIsOpened) {
  const std::string dir = scratch_dir("check_unknown_case");
  const std::string fifo = dir + "/c.csv";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0644), 0);
  const CliResult r = run_cli("check --case no_such_case --csv " + fifo, {0, 0, kHangSeconds});
  expect_one_line_error(r, "unknown stress case \"no_such_case\" (known: ", "check --case no_such_case");
}

// A link to a device is not a regular file either: a .png linked to /dev/full was "written"
// with exit 0. Refused before rendering, and nothing is left beside the link.
TEST(CliOutputs, ALinkToADeviceIsRefusedAndNothingIsLeft) {
  const std::string dir = scratch_dir("device_outputs");
  const std::vector<std::pair<std::string, std::string>> cases = {  // arguments, the option and the link
      {"render -r 64x36 -o " + dir + "/r.ppm", "--output " + dir + "/r.ppm"},
      {"render -r 64x36 -o " + dir + "/r.png", "--output " + dir + "/r.png"},
      {"bench --backend cpu -r 32x18 --camera-list 0 --configs flash --warmup 0 --repeat 1 --json " + dir + "/b.json",
       "--json " + dir + "/b.json"},
  };
  std::vector<std::string> links;
  for (const auto& [arguments, option_and_link] : cases) {
    const std::string link = option_and_link.substr(option_and_link.find(' ') + 1);
    fs::create_symlink("/dev/full", link);
    links.push_back(fs::path(link).filename().string());
    const CliResult r = run_cli(arguments, {0, 0, kHangSeconds});
    expect_one_line_error(r, option_and_link + ": is a device, not a regular file", arguments);
    EXPECT_EQ(fs::read_symlink(link), "/dev/full") << link;
  }
  std::sort(links.begin(), links.end());
  EXPECT_EQ(names_in(dir), links) << "a file or a temporary was left";
}

// A write that fails part way (a file-size limit here; a full disk fails the same way) is one
// line naming the file and the system's reason, exit non-zero, and leaves neither the file nor a
// temporary: a cut PNG, bench JSON, cameras.json or report SVG, and an empty report.md, came out
// with exit 0.
TEST(CliOutputs, AWriteThatFailsIsAnErrorAndLeavesNoFile) {
  const std::string dir = scratch_dir("failed_writes");
  struct Case {
    std::string arguments;
    std::size_t file_size_bytes;  // below the size of the file that fails, above the ones before it
    std::string failing;          // the file the error names
    std::vector<std::string> kept;  // what the command left in `folder` (written before the failure)
    std::string folder;
  };
  std::vector<Case> cases = {
      {"render -r 320x180 -o " + dir + "/r.ppm", 4096, dir + "/r.ppm", {}, ""},  // 173 kB
      {"bench --backend cpu -r 32x18 --camera-list 0 --configs flash --warmup 0 --repeat 1 --json " + dir + "/b.json",
       2048, dir + "/b.json", {}, ""},  // about 4 kB
      // point_cloud.ply of 10 Gaussians: under 2 kB; cameras.json: about 17 kB.
      {"generate demo --count 10 -o " + dir + "/scene", 4096, dir + "/scene/cameras.json", {"point_cloud.ply"},
       dir + "/scene"},
      // report.csv: about 3 kB; report_cpu.svg (written next): about 6 kB.
      {"report --backend cpu -r 32x18 --camera-list 0 --repeat 1 --ref-window 8 -o " + dir + "/report", 4096,
       dir + "/report/report_cpu.svg", {"report.csv"}, dir + "/report"},
  };
#ifdef FLASHGS_TEST_HAVE_OIIO
  cases.push_back({"render -r 320x180 -o " + dir + "/r.png", 4096, dir + "/r.png", {}, ""});  // about 34 kB
#endif
  for (const Case& c : cases) {
    const CliResult r = run_cli(c.arguments, {0, c.file_size_bytes, kHangSeconds});
    EXPECT_EQ(r.signal, 0) << c.arguments << ": killed by signal " << r.signal << "\n" << r.output;
    EXPECT_GT(r.exit_code, 0) << c.arguments << "\n" << r.output;
    const std::vector<std::string> lines = r.error_lines();
    ASSERT_EQ(lines.size(), 1u) << c.arguments << "\n" << r.output;
    EXPECT_EQ(lines[0], "error: " + c.failing + ": write error: File too large") << c.arguments;
    EXPECT_FALSE(fs::exists(c.failing)) << c.arguments;
    if (!c.folder.empty()) {
      EXPECT_EQ(names_in(c.folder), c.kept) << c.arguments;
    }
  }
  EXPECT_EQ(names_in(dir), (std::vector<std::string>{"report", "scene"})) << "a file or a temporary was left";
}

// The backend tuning knobs (flashgs/backend_tuning.h) on the command line: listed by
// --list-tuning, set by --set, swept by --tuning, and recorded in what a run writes.
TEST(CliTuning, ListTuningNamesEveryKnob) {
  for (const char* command : {"bench", "report"}) {
    const CliResult r = run_cli(std::string(command) + " --list-tuning");
    ASSERT_EQ(r.exit_code, 0) << command << "\n" << r.output;
    for (const TuningKnob& knob : kTuningKnobs)
      EXPECT_NE(r.output.find(std::string(knob.name) + " ("), std::string::npos) << command << " " << knob.name;
    const CliResult help = run_cli(std::string(command) + " --help");
    EXPECT_NE(help.output.find("sort_key_bits"), std::string::npos) << command << "\n" << help.output;
  }
}

TEST(CliTuning, BenchSweepsAKnobAndRecordsTheValuesUsed) {
  const std::string dir = scratch_dir("bench_tuning");
  // The scene after --set stays the scene: each --set takes one value.
  const CliResult r = run_cli("bench --backend cpu -r 32x18 --camera-list 0 --configs flash --warmup 0 --repeat 1 "
                              "--set sort_key_bits=24 " + demo_scene_path() + " --tuning blend_stop_bound=0,1 --json " +
                              dir + "/b.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("tuning (changed from the defaults): sort_key_bits=24\n"), std::string::npos) << r.output;
  for (const char* row : {"baseline blend_stop_bound=0", "baseline blend_stop_bound=1", "flash blend_stop_bound=0",
                          "flash blend_stop_bound=1"})
    EXPECT_NE(r.output.find(std::string("\n32x18      ") + row + " "), std::string::npos) << row << "\n" << r.output;
  std::ifstream in(dir + "/b.json");
  std::stringstream json;
  json << in.rdbuf();
  const std::string text = json.str();
  // The run's values (before the sweep) and each row's.
  auto count = [&](const std::string& fragment) {
    std::size_t n = 0;
    for (std::size_t at = text.find(fragment); at != std::string::npos; at = text.find(fragment, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("\"sort_key_bits\": \"24\""), 5u) << text;
  EXPECT_EQ(count("\"blend_stop_bound\": \"0\""), 2u) << text;
  EXPECT_EQ(count("\"blend_stop_bound\": \"1\""), 3u) << text;
  EXPECT_EQ(count("\"bin_sort\": \"auto\""), 5u) << text;
}

TEST(CliTuning, BadSettingsAreOneLineBeforeAnyWork) {
  const std::string dir = scratch_dir("bench_tuning_bad");
  const std::string quick = " --backend cpu -r 32x18 --camera-list 0 --configs flash --warmup 0 --repeat 1 ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--set sort_key_bits=40", "--set: sort_key_bits=\"40\": expected 16-32"},
      {"--set nothing=1", "--set \"nothing=1\": expected NAME=VALUE"},
      {"--set bin_sort", "--set \"bin_sort\": expected NAME=VALUE"},
      {"--tuning bin_sort=0,,1", "--tuning: bin_sort=\"\": expected auto, 0 or 1"},
      {"--tuning blend_region_width=8,12", "--tuning: blend_region_width=\"12\": expected 8 or 16"},
      {"--tuning nothing=1,2", "--tuning \"nothing=1,2\": expected NAME=V1,V2,..."},
  };
  for (const auto& [options, fragment] : cases) {
    expect_one_line_error(run_cli("bench" + quick + options + " --json " + dir + "/b.json"), fragment, "bench " + options);
    expect_one_line_error(run_cli("report" + quick.substr(0, quick.find(" --configs")) + " --repeat 1 " + options +
                                  " -o " + dir + "/report"),
                          fragment, "report " + options);
  }
  EXPECT_FALSE(fs::exists(dir + "/b.json"));
  EXPECT_FALSE(fs::exists(dir + "/report"));
}

TEST(CliTuning, ReportSweepsAKnobAndRecordsTheValuesUsed) {
  const std::string dir = scratch_dir("report_tuning");
  const CliResult r = run_cli("report --backend cpu -r 32x18 --camera-list 0 --repeat 1 --ref-window 8 --ref-cameras 1 "
                              "--set chunk_cull=0 --tuning sort_key_bits=20,28 -o " + dir);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::set<std::string> configs;
  for (const auto& row : read_csv(dir + "/report.csv"))
    if (row.size() > 1) configs.insert(row[1]);
  for (const char* config : {"baseline sort_key_bits=20", "baseline sort_key_bits=28", "flash sort_key_bits=20",
                             "flash sort_key_bits=28"})
    EXPECT_TRUE(configs.count(config)) << config << "\n" << r.output;
  EXPECT_FALSE(configs.count("flash")) << "a row without the swept knob";
  std::ifstream in(dir + "/report.md");
  std::stringstream md;
  md << in.rdbuf();
  EXPECT_NE(md.str().find("- tuning (docs/TUNING.md): bin_sort=auto "), std::string::npos) << md.str();
  EXPECT_NE(md.str().find(" chunk_cull=0 "), std::string::npos) << md.str();
  EXPECT_NE(md.str().find("settings of --tuning"), std::string::npos) << md.str();
}

// `lod city` on a built set: the city streams on the CPU along its own path; bad options, an
// instanced base and a folder in use are one line each, with nothing written.
TEST(CliLodCity, ACityOfASetFliesOnTheCpuAndBadOptionsAreOneLine) {
  const std::string dir = scratch_dir("lod_city");
  const CliResult build = run_cli("lod build " + demo_scene_path() + " " + dir + "/base --leaf-size 4096 --file-size 16384");
  ASSERT_EQ(build.exit_code, 0) << build.output;
  const CliResult info = run_cli("info " + dir + "/base --lod 1");  // PLY chunks, named as such
  EXPECT_NE(info.output.find("LOD set (lod-meta.json) of INRIA PLY chunks, level 1"), std::string::npos) << info.output;
  const CliResult city = run_cli("lod city " + dir + "/base " + dir + "/city --blocks 3 --up +y --cameras 4");
  ASSERT_EQ(city.exit_code, 0) << city.output;
  EXPECT_NE(city.output.find("city " + dir + "/city: 3 blocks"), std::string::npos) << city.output;
  EXPECT_NE(city.output.find("level 0: 90000 Gaussians"), std::string::npos) << city.output;  // 3 x the demo's 30,000
  const CliResult fly = run_cli("lod fly " + dir + "/city --backend cpu -r 160x90 --steps 1 --fps 1000 --psnr-every 2 "
                                "--frames-csv " + dir + "/frames.csv");
  ASSERT_EQ(fly.exit_code, 0) << fly.output;
  EXPECT_NE(fly.output.find("(3 instances), 5 levels, level 0 90000 Gaussians; path of 4 frames"), std::string::npos)
      << fly.output;
  EXPECT_NE(fly.output.find("failed 0"), std::string::npos) << fly.output;
  EXPECT_NE(fly.output.find("PSNR against the full-detail scene (2 frames"), std::string::npos) << fly.output;
  // One row per frame; the compared frames (every second) have both PSNRs, the settled cut's
  // no worse than the frame as shown.
  const auto rows = read_csv(dir + "/frames.csv");
  ASSERT_EQ(rows.size(), 5u) << fly.output;
  EXPECT_EQ(rows[0][6], "psnr_shown_db");
  for (std::size_t frame = 0; frame < 4; ++frame) {
    const auto& row = rows[frame + 1];
    ASSERT_GE(row.size(), 6u) << "frame " << frame;
    EXPECT_EQ(row[0], std::to_string(frame));
    EXPECT_GT(std::stod(row[2]), 0.0) << "frame " << frame << " drew nothing";
    if (frame % 2 != 0) {  // empty PSNR cells (the reader drops a row's empty last cells)
      EXPECT_TRUE(row.size() < 7 || row[6].empty()) << "frame " << frame;
      continue;
    }
    ASSERT_EQ(row.size(), 8u) << "frame " << frame;
    EXPECT_GE(std::stod(row[7]), std::stod(row[6]) - 1e-3) << "frame " << frame;
    EXPECT_GT(std::stod(row[7]), 30.0) << "frame " << frame;
  }

  const std::string base = " " + dir + "/base " + dir + "/refused";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"lod city" + base + " --blocks 0", "--blocks"},
      {"lod city" + base + " --blocks two", "--blocks"},
      {"lod city" + base, "--blocks is required"},
      {"lod city" + base + " --blocks 2 --up +w", "--up"},
      {"lod city" + base + " --blocks 2 --spacing nan", "--spacing"},
      {"lod city" + base + " --blocks 2 --spacing -1", "--spacing"},
      {"lod city" + base + " --blocks 2 --cameras 1", "--cameras"},
      {"lod city" + base + " --blocks 2 --chunk-format sog", "--chunk-format requires --materialize"},
      {"lod city" + base + " --blocks 2 --materialize --chunk-format webp", "--chunk-format"},
      {"lod city " + dir + "/city " + dir + "/refused --blocks 2", "already an instanced set"},
      {"lod city " + dir + "/nothing " + dir + "/refused --blocks 2", dir + "/nothing"},
      {"lod city " + dir + "/base " + dir + "/city --blocks 2", "is not empty"},
      {"lod fly " + dir + "/city --backend cpu --frames-csv " + dir + "/missing/frames.csv", "--frames-csv"},
  };
  for (const auto& [arguments, fragment] : cases) expect_one_line_error(run_cli(arguments), fragment, arguments);
  EXPECT_FALSE(fs::exists(dir + "/refused"));
}

}  // namespace
}  // namespace flashgs
