// The viewer run headless (Xvfb + Mesa, CPU path): scripted screenshots match the CLI's render, keys move the camera.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "flashgs/image.h"
#include "flashgs/image_io.h"
#include "test_support.h"

namespace {

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

RunResult run_once(const std::string& command) {
  RunResult r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) r.output += buffer.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Runs a command; retried when xvfb-run itself could not start its X server (a display-number
// race with another test), never when the viewer failed.
RunResult run(const std::string& command) {
  RunResult r;
  for (int attempt = 0; attempt < 3; ++attempt) {
    r = run_once(command);
    if (r.exit_code == 0 || r.output.find("xvfb-run: error") == std::string::npos) break;
  }
  return r;
}

// PNG where OpenImageIO is built in, else the built-in PPM (same 8-bit bytes).
const std::string kExt = flashgs::image_io_has_oiio() ? ".png" : ".ppm";

std::string out_dir() {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/viewer";
  std::filesystem::create_directories(dir);
  return dir;
}

// The viewer needs an X display: the one we have, or a private Xvfb through xvfb-run.
// Returns the command prefix, or empty when neither exists.
std::string display_prefix() {
  // ctest runs the tests in parallel: each process starts its search for a free display number
  // at its own place, so that two xvfb-run calls rarely race for the same one.
  if (run("command -v xvfb-run").exit_code == 0)
    return "xvfb-run -a -n " + std::to_string(100 + (getpid() * 37) % 800) + " -s \"-screen 0 1920x1080x24\" ";
  if (std::getenv("DISPLAY")) return " ";
  return "";
}

#define REQUIRE_DISPLAY(prefix)                                                                 \
  const std::string prefix = display_prefix();                                                  \
  if (prefix.empty()) GTEST_SKIP() << "no X display and no xvfb-run (install xvfb): viewer test skipped"

// Starts the viewer (`viewer_args`, output to `log`) in the background and runs `steps`, shell
// lines that drive it (`$helper` is `helper`, `wait_for TEXT` waits up to 60 s for a line of
// its log, and a failing step sets `status`); the script then exits with `crash_status` if the
// viewer is gone, else with `status`. Returns its result with the viewer's log appended.
RunResult run_live_viewer(const std::string& prefix, const std::string& script, const std::string& viewer_args,
                          const std::string& helper, const std::string& steps, int crash_status,
                          const std::string& log) {
  if (FILE* f = std::fopen(script.c_str(), "w")) {
    std::fputs(("viewer=$1 helper=$2 log=$3\n"
                "\"$viewer\" " + viewer_args + " > \"$log\" 2>&1 &\n"
                "pid=$!\n"
                "wait_for() {\n"
                "  for _ in $(seq 1 600); do grep -qF -- \"$1\" \"$log\" && return 0; kill -0 $pid 2>/dev/null || return 1; "
                "sleep 0.1; done\n"
                "  return 1\n"
                "}\n"
                "status=0\n" + steps +
                "kill -0 $pid 2>/dev/null || status=" + std::to_string(crash_status) + "\n"
                "kill $pid 2>/dev/null\n"
                "wait $pid 2>/dev/null\n"
                "exit $status\n").c_str(),
               f);
    std::fclose(f);
  }
  RunResult r = run(prefix + "bash " + script + " " + FLASHGS_VIEWER + " " + helper + " " + log);
  if (FILE* f = std::fopen(log.c_str(), "r")) {
    char line[1024];
    while (std::fgets(line, sizeof line, f)) r.output += line;
    std::fclose(f);
  }
  return r;
}

std::string viewer() { return FLASHGS_VIEWER; }
std::string cli() { return FLASHGS_CLI; }

// The viewer's screenshot of `camera` vs `flashgs render` of the same camera at the same size.
void expect_matches_cli(const std::string& prefix, const std::string& scene, int camera, const std::string& stem) {
  const std::string dir = out_dir();
  const std::string shot = dir + "/" + stem + "_viewer" + kExt, ref = dir + "/" + stem + "_cli" + kExt;
  std::filesystem::remove(shot);
  const std::string scene_arg = scene.empty() ? "" : "\"" + scene + "\" ";
  const RunResult v = run(prefix + viewer() + " " + scene_arg + "--backend cpu --size 640x360 --camera " +
                          std::to_string(camera) + " --frames 2 --screenshot " + shot + " --exit");
  ASSERT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("frame path: CPU"), std::string::npos) << v.output;
  const RunResult c = run(cli() + " render " + scene_arg + "--backend cpu -c " + std::to_string(camera) +
                          " -r 640x360 -o " + ref);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const flashgs::Image a = flashgs::read_image(shot), b = flashgs::read_image(ref);
  ASSERT_EQ(a.width, 640);
  ASSERT_EQ(a.height, 360);
  const flashgs::ImageDifference d = flashgs::compare_images(a, b);
  std::printf("%s: viewer vs CLI PSNR %.2f dB, max abs %.4f\n", stem.c_str(), d.psnr_db, d.max_abs);
  if (!(d.psnr_db >= 40.0)) flashgs::test::dump_images("viewer_" + stem, b, a);
  EXPECT_GE(d.psnr_db, 40.0);
}

TEST(Viewer, DemoSceneScreenshotMatchesCliRender) {
  REQUIRE_DISPLAY(prefix);
  expect_matches_cli(prefix, "", 3, "demo_cam3");
}

TEST(Viewer, BikerCameraZeroMatchesCliRender) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = flashgs::test::shared_scene_dir("pc_biker");
  if (dir.empty()) GTEST_SKIP() << "../shared/scenes/pc_biker is absent: skipped";
  expect_matches_cli(prefix, dir + "/point_cloud.ply", 0, "pc_biker_cam0");
}

TEST(Viewer, ScriptedKeysMoveTheCamera) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string still = dir + "/keys_still" + kExt, moved = dir + "/keys_moved" + kExt;
  const std::string common = prefix + viewer() + " --backend cpu --size 320x180 --camera 0 ";
  const RunResult a = run(common + "--frames 1 --screenshot " + still + " --exit");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const RunResult b = run(common + "--keys \"W:0.5,D:0.2,MOUSE:40:0\" --screenshot " + moved + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const auto position = [](const std::string& out) {
    const auto at = out.find("viewer camera: position");
    return at == std::string::npos ? std::string() : out.substr(at, out.find('\n', at) - at);
  };
  EXPECT_FALSE(position(b.output).empty()) << b.output;
  EXPECT_NE(position(a.output), position(b.output));
  const flashgs::ImageDifference d = flashgs::compare_images(flashgs::read_image(still), flashgs::read_image(moved));
  std::printf("still vs moved: PSNR %.2f dB, max abs %.3f\n", d.psnr_db, d.max_abs);
  EXPECT_LT(d.psnr_db, 30.0) << "the key sequence did not change the picture";
}

TEST(Viewer, WindowResizeRecreatesTheFrame) {
  REQUIRE_DISPLAY(prefix);
  const std::string shot = out_dir() + "/after_resize" + kExt, ref = out_dir() + "/resize_reference" + kExt;
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 320x180 --camera 4 --keys \"RESIZE:400:300,WAIT:0.05\" "
                          "--screenshot " + shot + " --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const flashgs::Image a = flashgs::read_image(shot);
  EXPECT_EQ(a.width, 400);
  EXPECT_EQ(a.height, 300);
  // At another aspect ratio the view is the free camera with the scene camera's pose and
  // horizontal field of view; the CLI's --resolution keeps fx and fy apart instead, so the
  // reference is the viewer started at that size.
  const RunResult b = run(prefix + viewer() + " --backend cpu --size 400x300 --camera 4 --frames 2 --fov 60 "
                          "--screenshot " + ref + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const flashgs::ImageDifference d = flashgs::compare_images(a, flashgs::read_image(ref));
  EXPECT_GE(d.psnr_db, 40.0);
}

TEST(Viewer, FailedLoadKeepsTheCurrentScene) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string bad = dir + "/not_a_scene.ply";
  { FILE* f = std::fopen(bad.c_str(), "wb"); ASSERT_TRUE(f); std::fputs("ply\nformat ascii 9.9\n", f); std::fclose(f); }
  const std::string shot = dir + "/after_failed_load" + kExt, ref = dir + "/before_failed_load" + kExt;
  const std::string common = prefix + viewer() + " --backend cpu --size 320x180 --camera 2 --frames 3 ";
  const RunResult a = run(common + "--then-open " + bad + " --screenshot " + shot + " --exit");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  EXPECT_NE(a.output.find("load failed, scene kept: " + bad), std::string::npos) << a.output;
  const RunResult b = run(common + "--screenshot " + ref + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const flashgs::ImageDifference d = flashgs::compare_images(flashgs::read_image(shot), flashgs::read_image(ref));
  EXPECT_TRUE(std::isinf(d.psnr_db)) << "the picture changed after a failed load (PSNR " << d.psnr_db << ")";
}

// Drag and drop end to end: an XDND drop (what a file manager sends) on the running, unscripted
// viewer opens the file; a dropped file that fails to load leaves the viewer running.
TEST(Viewer, DroppedFilesOpenAndABadOneKeepsTheViewerRunning) {
#ifndef FLASHGS_X11_DROP
  GTEST_SKIP() << "built without Xlib: the drop helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string dir = out_dir();
  const std::string good = dir + "/dropped_scene.ply", bad = dir + "/dropped_missing.ply", log = dir + "/drop_viewer.log";
  std::filesystem::copy_file(std::string(FLASHGS_ASSET_DIR) + "/demo/point_cloud.ply", good,
                             std::filesystem::copy_options::overwrite_existing);
  std::filesystem::remove(bad);
  const std::string steps = "wait_for \"frame path\" || status=10\n"
                            "[ $status -eq 0 ] && { sleep 1; \"$helper\" 600 300 \"" + good + "\" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"" + good + ": 30000 Gaussians\" || status=12; }\n"
                            "[ $status -eq 0 ] && { \"$helper\" 600 300 \"" + bad + "\" || status=13; }\n"
                            "[ $status -eq 0 ] && { wait_for \"load failed, scene kept: " + bad + "\" || status=14; }\n"
                            "sleep 0.5\n";
  const RunResult r = run_live_viewer(prefix, dir + "/drop_test.sh", "--backend cpu --size 800x450", FLASHGS_X11_DROP,
                                      steps, 15, log);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11/13 drop, 12 load, 14 error, 15 crash)\n"
                            << r.output;
#endif
}

// A real mouse click (XTEST) on the panel's "Compare this view" button runs the comparison:
// ImGui's mouse position and buttons reach it through the viewer's own platform inputs.
TEST(Viewer, MouseClickOnAPanelButtonWorks) {
#ifndef FLASHGS_X11_CLICK
  GTEST_SKIP() << "built without libXtst: the click helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string dir = out_dir();
  const std::string log = dir + "/click_viewer.log";
  // The button's place in a 1280x720 window at UI scale 1 (the panel layout is fixed).
  const std::string steps = "wait_for \"Gaussians, SH degree\" || status=10\n"
                            "[ $status -eq 0 ] && { sleep 1; \"$helper\" 95 650 || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"compare flash vs baseline\" || status=12; }\n";
  const RunResult r = run_live_viewer(prefix, dir + "/click_test.sh", "--backend cpu --size 1280x720",
                                      FLASHGS_X11_CLICK, steps, 13, log);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11 click, 12 no comparison, 13 crash)\n"
                            << r.output;
#endif
}

// The heat-map shader draws over the frame, and its legend runs from blue (0) to red (max).
TEST(Viewer, HeatmapOverlayAndLegendAreDrawn) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string with = dir + "/overlay_on" + kExt, without = dir + "/overlay_off" + kExt;
  const std::string common = prefix + viewer() + " --backend cpu --size 480x270 --camera 1 --frames 2 --no-ui ";
  const RunResult a = run(common + "--heatmap --window-screenshot " + with + " --exit");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const RunResult b = run(common + "--window-screenshot " + without + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const flashgs::Image on = flashgs::read_image(with), off = flashgs::read_image(without);
  ASSERT_EQ(on.width, 480);
  EXPECT_LT(flashgs::compare_images(on, off).psnr_db, 30.0) << "the overlay changed nothing";
  // Legend bar: x in [480 - 300, 480 - 20), y in [270 - 30, 270 - 16) at UI scale 1.
  const float* low = on.pixel(185, 247);
  const float* high = on.pixel(455, 247);
  EXPECT_GT(low[2], 0.25f);
  EXPECT_LT(low[0], 0.2f);
  EXPECT_GT(high[0], 0.7f);
  EXPECT_LT(high[2], 0.2f);
}

TEST(Viewer, CameraPathReportsFrameTimes) {
  REQUIRE_DISPLAY(prefix);
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 320x180 --path --frames 4 --warmup 1 --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("viewer frames: 4 at 320x180"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("FPS"), std::string::npos) << r.output;
}

TEST(Viewer, HeatmapAndCompareRun) {
  REQUIRE_DISPLAY(prefix);
  const std::string shot = out_dir() + "/heatmap_window" + kExt;
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 480x270 --camera 1 --frames 2 --heatmap --compare --check-frame "
                          "--window-screenshot " + shot + " --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // flash vs baseline at tau = 1/255 on the demo scene: equal within rounding.
  const auto at = r.output.find("viewer compare: flash vs baseline PSNR ");
  ASSERT_NE(at, std::string::npos) << r.output;
  const double psnr = std::atof(r.output.c_str() + at + std::string("viewer compare: flash vs baseline PSNR ").size());
  EXPECT_GE(psnr, 50.0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(shot));
  // The texture on screen holds exactly the backend's image of the view.
  EXPECT_NE(r.output.find("viewer frame check: displayed 480x270"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("-> ok"), std::string::npos) << r.output;
}

}  // namespace
