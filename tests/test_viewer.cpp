// The viewer run headless (Xvfb + Mesa, CPU path): scripted screenshots match the CLI's render, keys move the camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "flashgs/demo_scene.h"
#include "flashgs/file_access.h"
#include "flashgs/image.h"
#include "flashgs/image_io.h"
#include "flashgs/frame_memory.h"
#include "flashgs/lod_build.h"
#include "flashgs/lod_tint.h"
#include "flashgs/generators.h"
#include "flashgs/keyframe_path.h"
#include "heatmap_legend.h"
#include "camera_controller.h"
#include "memory_budget.h"
#include "scene_lines.h"
#include "scene_state.h"
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
const std::string kExt = flashgs::image_io_writes_png() ? ".png" : ".ppm";

std::string out_dir() {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/viewer";
  std::filesystem::create_directories(dir);
  return dir;
}

// The viewer needs an X display: the one we have, or a private Xvfb through xvfb-run.
// Returns the command prefix, or empty when neither exists.
std::string display_prefix() {
  // ctest runs the tests in parallel: each process starts its search for a free display number
  // at its own place, so that two xvfb-run calls rarely race for the same one. The X authority
  // file is ours (-f), so xvfb-run has no temporary folder to remove: its cleanup of one failed
  // on a CI machine and replaced the viewer's exit status with its own 5.
  if (run("command -v xvfb-run").exit_code == 0)
    return "xvfb-run -a -n " + std::to_string(100 + (getpid() * 37) % 800) + " -f '" + out_dir() + "/xauthority-" +
           std::to_string(getpid()) + "' -s \"-screen 0 1920x1080x24\" ";
  if (std::getenv("DISPLAY")) return " ";
  return "";
}

#define REQUIRE_DISPLAY(prefix)                                                                 \
  const std::string prefix = display_prefix();                                                  \
  if (prefix.empty()) GTEST_SKIP() << "no X display and no xvfb-run (install xvfb): viewer test skipped"

#ifdef FLASHGS_X11_DROP
const char* const kDropHelper = FLASHGS_X11_DROP;
#else
const char* const kDropHelper = "";
#endif
#ifdef FLASHGS_X11_INPUT
const char* const kInputHelper = FLASHGS_X11_INPUT;
#else
const char* const kInputHelper = "";
#endif

// The --render-gate file of run `name` (run_live_viewer opens and closes it).
std::string gate_file(const std::string& name) { return out_dir() + "/" + name + ".gate"; }
std::string gate_args(const std::string& name) { return " --render-gate \"" + gate_file(name) + "\""; }
// The --load-gate file of run `name` (closed when the run starts; the script opens it).
std::string load_gate_file(const std::string& name) { return out_dir() + "/" + name + ".loadgate"; }
std::string load_gate_args(const std::string& name) { return " --load-gate \"" + load_gate_file(name) + "\""; }

// Starts the viewer (`viewer_args`, run in the test output folder, output to NAME.log there)
// in the background and runs `steps`, shell lines that drive it. They have `$drop` (x11_drop),
// `$input` (x11_input) and `$log`, and these functions, each waiting for the viewer's log (up
// to 120 s) and failing when the viewer is gone:
//   wait_for TEXT        a line of the log containing TEXT
//   wait_count TEXT N    N lines containing TEXT
//   press WHAT TOKEN     `$input down WHAT`, then two more frames logged with TOKEN held
//                        (--log-input): down across two frames, however slow they are
//   hold WHAT TOKEN      press, then `$input up WHAT`
//   close_window         a window manager's close request; waits for the viewer to exit and
//                        sets `closed` (its exit status in `exit_status`)
//   close_gate, open_gate  with gate_args(name) among `viewer_args` (--render-gate): CPU
//                        renders started while the gate is closed wait until it opens (it
//                        starts open), so a step can act while a frame is surely in flight
//   open_load_gate       with load_gate_args(name) (--load-gate): scene loads wait until
//                        then (the gate starts closed), so a step can act while one runs
// A failing step sets `status`. The script then exits with `crash_status` if the viewer is gone
// without being closed, else with `status`. Returns its result with the viewer's log appended.
// `env` (e.g. "PATH=/x:$PATH") is set for the viewer alone. The viewer keeps its settings in
// `config_home` (XDG_CONFIG_HOME; empty: a fresh folder of this test's own), never in the user's.
RunResult run_live_viewer(const std::string& prefix, const std::string& name, const std::string& viewer_args,
                          const std::string& steps, int crash_status, const std::string& env = "",
                          std::string config_home = "") {
  const std::string dir = out_dir(), script = dir + "/" + name + ".sh", log = dir + "/" + name + ".log";
  if (config_home.empty()) {
    config_home = dir + "/" + name + "_config";
    std::filesystem::remove_all(config_home);
  }
  if (FILE* f = std::fopen(script.c_str(), "w")) {
    std::fputs(("viewer=$1 drop=$2 input=$3 log=$4\n"
                "gate=\"" + gate_file(name) + "\" load_gate=\"" + load_gate_file(name) + "\"\n"
                "export XDG_CONFIG_HOME=\"" + config_home + "\"\n"
                "open_gate() { : > \"$gate\"; }\n"
                "close_gate() { rm -f \"$gate\"; }\n"
                "open_load_gate() { : > \"$load_gate\"; }\n"
                "open_gate\n"
                "rm -f \"$load_gate\"\n"
                "cd \"$(dirname \"$log\")\"\n"
                // Emptied here, not only by the viewer's redirection below: that one runs in the
                // background job, and a step could read the last run's log before it, see its
                // "UI ready" and act on a window that is not there yet.
                ": > \"$log\"\n"
                + (env.empty() ? std::string() : "env " + env + " ") + "\"$viewer\" " + viewer_args + " > \"$log\" 2>&1 &\n"
                "pid=$!\n"
                "closed=0 exit_status=\n"
                "wait_count() {\n"
                "  for _ in $(seq 1 1200); do [ \"$(grep -cF -- \"$1\" \"$log\")\" -ge \"$2\" ] && return 0; "
                "kill -0 $pid 2>/dev/null || return 1; sleep 0.1; done\n"
                "  return 1\n"
                "}\n"
                "wait_for() { wait_count \"$1\" 1; }\n"
                // Keys go to the focused window: the viewer's, as a window manager would make it
                // (x11_input focus). Without one, GLFW asks for the focus itself after waiting at
                // most 0.1 s for the window to be mapped, which a loaded machine can exceed.
                "press() {\n"
                "  n=$(grep -cF -- \"$2\" \"$log\")\n"
                "  \"$input\" focus 1 1 || return 1\n"
                "  \"$input\" down \"$1\" || return 1\n"
                "  wait_count \"$2\" $((n + 2))\n"
                "}\n"
                "hold() { press \"$1\" \"$2\"; r=$?; \"$input\" up \"$1\"; return $r; }\n"
                // Clicks a widget where the viewer last logged it (--log-input): not a fixed
                // place, which a longer scene path or another font would move.
                "move_to() {\n"
                "  wait_for \"widget \\\"$1\\\" at \" || return 1\n"
                "  at=$(grep -F -- \"widget \\\"$1\\\" at \" \"$log\" | tail -n 1 | sed 's/.* at //')\n"
                "  \"$input\" move \"${at%,*}\" \"${at#*,}\"\n"
                "}\n"
                "click() { move_to \"$1\" && hold button \" mouse0 \"; }\n"
                "close_window() {\n"
                "  \"$input\" close 20 20 || return 1\n"
                "  for _ in $(seq 1 1200); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done\n"
                "  kill -0 $pid 2>/dev/null && return 1\n"
                "  wait $pid; exit_status=$?; closed=1\n"
                "}\n"
                "status=0\n" + steps +
                "[ $closed -eq 1 ] || kill -0 $pid 2>/dev/null || status=" + std::to_string(crash_status) + "\n"
                "kill $pid 2>/dev/null\n"
                "wait $pid 2>/dev/null\n"
                "exit $status\n").c_str(),
               f);
    std::fclose(f);
  }
  RunResult r = run(prefix + "bash " + script + " " + FLASHGS_VIEWER + " \"" + kDropHelper + "\" \"" + kInputHelper +
                    "\" " + log);
  if (FILE* f = std::fopen(log.c_str(), "r")) {
    char line[1024];
    while (std::fgets(line, sizeof line, f)) r.output += line;
    std::fclose(f);
  }
  return r;
}

// The fraction of pixels brighter than near-black (a NaN pose renders the background only).
double lit_fraction(const flashgs::Image& image) {
  std::size_t lit = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float* p = image.pixel(x, y);
      lit += p[0] + p[1] + p[2] > 0.1f;
    }
  return image.width > 0 ? double(lit) / (double(image.width) * image.height) : 0.0;
}

std::string viewer() { return FLASHGS_VIEWER; }
std::string cli() { return FLASHGS_CLI; }

// The number after `key` in `output`, or -1.
long long number_after(const std::string& output, const std::string& key) {
  const auto at = output.find(key);
  return at == std::string::npos ? -1 : std::atoll(output.c_str() + at + key.size());
}

// The viewer's screenshot of `camera` vs `flashgs render` of the same camera at the same size,
// both given `options`: the same image and the same kv pairs. Returns the pairs.
long long expect_matches_cli(const std::string& prefix, const std::string& scene, int camera, const std::string& stem,
                             const std::string& options = "") {
  const std::string dir = out_dir();
  const std::string shot = dir + "/" + stem + "_viewer" + kExt, ref = dir + "/" + stem + "_cli" + kExt;
  std::filesystem::remove(shot);
  const std::string scene_arg = scene.empty() ? "" : "\"" + scene + "\" ";
  const RunResult v = run(prefix + viewer() + " " + scene_arg + options + " --backend cpu --size 640x360 --camera " +
                          std::to_string(camera) + " --frames 2 --screenshot " + shot + " --exit");
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("frame path: CPU"), std::string::npos) << v.output;
  const RunResult c = run(cli() + " render " + scene_arg + options + " --backend cpu -c " + std::to_string(camera) +
                          " -r 640x360 -o " + ref);
  EXPECT_EQ(c.exit_code, 0) << c.output;
  if (v.exit_code != 0 || c.exit_code != 0) return -1;
  const flashgs::Image a = flashgs::read_image(shot), b = flashgs::read_image(ref);
  EXPECT_EQ(a.width, 640);
  EXPECT_EQ(a.height, 360);
  const flashgs::ImageDifference d = flashgs::compare_images(a, b);
  std::printf("%s: viewer vs CLI PSNR %.2f dB, max abs %.4f\n", stem.c_str(), d.psnr_db, d.max_abs);
  if (!(d.psnr_db >= 40.0)) flashgs::test::dump_images("viewer_" + stem, b, a);
  EXPECT_GE(d.psnr_db, 40.0);
  const long long pairs = number_after(v.output, "last frame kv pairs ");
  EXPECT_EQ(pairs, number_after(c.output, "kv pairs:")) << v.output << "\n" << c.output;
  return pairs;
}

TEST(Viewer, DemoSceneScreenshotMatchesCliRender) {
  REQUIRE_DISPLAY(prefix);
  expect_matches_cli(prefix, "", 3, "demo_cam3");
}

// The --no-<switch> flags are the CLI's (one table): the same frame as `flashgs render` with
// them, and more pairs than without.
TEST(Viewer, SwitchFlagsTurnOffTheirOptimizationsAsInTheCli) {
  REQUIRE_DISPLAY(prefix);
  const long long flash = expect_matches_cli(prefix, "", 3, "demo_cam3_flash");
  const long long without = expect_matches_cli(prefix, "", 3, "demo_cam3_no_exact", "--no-exact-tile-test --no-tight-bbox");
  std::printf("kv pairs: flash %lld, without the exact test and the tight box %lld\n", flash, without);
  EXPECT_GT(flash, 0);
  EXPECT_GT(without, flash);
}

// A scene whose file names the anti-aliased kernel opens in it without a flag, as the CLI renders
// it (auto), and --kernel overrides it in both alike.
TEST(Viewer, MarkedSceneOpensInItsTrainedKernelAsTheCliRendersIt) {
  REQUIRE_DISPLAY(prefix);
  namespace fs = std::filesystem;
  // The demo scene with Brush's mark for gsplat's anti-aliased kernel, and its cameras beside it.
  const fs::path dir = fs::path(out_dir()) / "marked_scene";
  fs::create_directories(dir);
  const std::vector<char> bytes = flashgs::read_regular_file(flashgs::demo_scene_path(), 1u << 30);
  std::string text(bytes.begin(), bytes.end());
  const std::size_t format_end = text.find('\n', text.find("format ")) + 1;
  text.insert(format_end, "comment SplatRenderMode: mip\n");
  const std::string scene = (dir / "point_cloud.ply").string();
  {
    std::FILE* f = std::fopen(scene.c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  fs::copy_file(fs::path(flashgs::demo_scene_path()).parent_path() / "cameras.json", dir / "cameras.json",
                fs::copy_options::overwrite_existing);
  const long long marked = expect_matches_cli(prefix, scene, 3, "demo_cam3_marked");
  const long long classic = expect_matches_cli(prefix, scene, 3, "demo_cam3_marked_classic", "--kernel classic");
  const long long mip = expect_matches_cli(prefix, "", 3, "demo_cam3_mip", "--kernel antialiased=0.1");
  std::printf("kv pairs: marked (antialiased) %lld, --kernel classic %lld, demo at antialiased=0.1 %lld\n", marked,
              classic, mip);
  // The compensated opacity shrinks the opacity-aware extents: fewer pairs than classic.
  EXPECT_GT(marked, 0);
  EXPECT_LT(marked, classic);
}

// K steps through the trainers' kernels live; each one is a new options line (and frame).
TEST(Viewer, TheKKeyStepsThroughTheKernels) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  // GLFW key code: K 75.
  const std::string steps =
      "wait_for \"UI ready\" || status=10\n"
      "[ $status -eq 0 ] && { hold k \" key75 \" && wait_for \"options: flash-antialiased\" || status=11; }\n"
      "[ $status -eq 0 ] && { hold k \" key75 \" && wait_for \"options: flash-antialiased_0.1\" || status=12; }\n"
      "[ $status -eq 0 ] && { hold k \" key75 \" && wait_count \"options: flash\" 4 || status=13; }\n"
      "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "k_key", "--backend cpu --size 1280x800 --log-input", steps, 14);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11-13 K, 14 crash, 15 close)\n"
                            << r.output;
  EXPECT_NE(r.output.find("kernel: antialiased (eps 0.1) (K)"), std::string::npos) << r.output;
#endif
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

// Made smaller, the window keeps its panels inside it: the statistics window, placed at the
// right edge of a 1280-point window, comes back inside a 1024x600 one.
TEST(Viewer, PanelsStayInsideTheWindowAfterAResize) {
  REQUIRE_DISPLAY(prefix);
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 1280x800 --frames 6 --log-input "
                          "--keys \"WAIT:0.05,RESIZE:1024:600,WAIT:0.1\" --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string name : {"Statistics corner", "panel corner"}) {
    const std::string key = "widget \"" + name + "\" at ";
    const auto at = r.output.rfind(key);
    ASSERT_NE(at, std::string::npos) << name << "\n" << r.output;
    int x = 0, y = 0;
    ASSERT_EQ(std::sscanf(r.output.c_str() + at + key.size(), "%d,%d", &x, &y), 2) << r.output;
    EXPECT_LE(x, 1024) << name;
    EXPECT_LE(y, 600) << name;
  }
}

// The first frame of a new scene is a coarse one, then the full frame follows (a large scene's
// full frame takes seconds: the window showed "no frame yet" all that time).
TEST(Viewer, TheFirstFrameOfASceneIsCoarseThenFull) {
  REQUIRE_DISPLAY(prefix);
  const std::string steps = "wait_for \"first frame shown\" || status=10\n"
                            "[ $status -eq 0 ] && { close_window || status=12; }\n";
  const RunResult r = run_live_viewer(prefix, "coarse_first", "--backend cpu --size 1280x800 --log-input", steps, 11);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code << " (10 no full frame, 11 crash, 12 close)\n" << r.output;
  const auto first = r.output.find("frame shown ");
  ASSERT_NE(first, std::string::npos) << r.output;
  const std::string line = r.output.substr(first, r.output.find('\n', first) - first);
  EXPECT_NE(line.find("(reduced)"), std::string::npos) << line;
  EXPECT_NE(r.output.find("(full)", first), std::string::npos) << r.output;
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
// viewer opens the file; a dropped file that fails to load leaves the viewer running, and it
// closes normally afterwards.
TEST(Viewer, DroppedFilesOpenAndABadOneKeepsTheViewerRunning) {
#if !defined(FLASHGS_X11_DROP) || !defined(FLASHGS_X11_INPUT)
  GTEST_SKIP() << "built without Xlib or libXtst: the drop and input helpers are absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string dir = out_dir();
  const std::string good = dir + "/dropped_scene.ply", bad = dir + "/dropped_missing.ply";
  std::filesystem::copy_file(flashgs::demo_scene_path(), good,
                             std::filesystem::copy_options::overwrite_existing);
  std::filesystem::remove(bad);
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { \"$drop\" 600 300 \"" + good + "\" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"" + good + ": 30000 Gaussians\" || status=12; }\n"
                            "[ $status -eq 0 ] && { \"$drop\" 600 300 \"" + bad + "\" || status=13; }\n"
                            "[ $status -eq 0 ] && { wait_for \"load failed, scene kept: " + bad + "\" || status=14; }\n"
                            "[ $status -eq 0 ] && { close_window || status=16; }\n"
                            "[ $status -eq 0 ] && [ \"$exit_status\" != 0 ] && status=17\n";
  const RunResult r = run_live_viewer(prefix, "drop", "--backend cpu --size 800x450", steps, 15);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11/13 drop, 12 load, 14 error, 15 crash, 16 no exit on close, "
                               "17 exit status)\n"
                            << r.output;
#endif
}

// A 3DGS training output folder dropped on the window: the highest iteration's PLY opens,
// with the cameras.json of the model root.
TEST(Viewer, ADropped3dgsOutputFolderOpensItsLastIteration) {
#if !defined(FLASHGS_X11_DROP) || !defined(FLASHGS_X11_INPUT)
  GTEST_SKIP() << "built without Xlib or libXtst: the drop and input helpers are absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  namespace fs = std::filesystem;
  const std::string model = out_dir() + "/dropped_model";
  fs::remove_all(model);
  for (const char* iteration : {"iteration_7000", "iteration_30000"}) {
    fs::create_directories(model + "/point_cloud/" + iteration);
    fs::copy_file(flashgs::demo_scene_path(), model + "/point_cloud/" + iteration + "/point_cloud.ply");
  }
  fs::copy_file(fs::path(flashgs::demo_scene_path()).parent_path() / "cameras.json", model + "/cameras.json");
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { \"$drop\" 600 300 \"" + model + "\" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"iteration_30000/point_cloud.ply: 30000 Gaussians, SH degree 1, "
                            "36 cameras\" || status=12; }\n"
                            "[ $status -eq 0 ] && { close_window || status=14; }\n";
  const RunResult r = run_live_viewer(prefix, "drop_model", "--backend cpu --size 800x450", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11 drop, 12 not loaded, 13 crash, 14 close)\n"
                            << r.output;
#endif
}

// A FIFO dropped on the window: one clear message, the scene stays, and closing the window
// does not wait for anything (opening a FIFO blocks until a writer appears).
TEST(Viewer, ADroppedFifoIsRefusedAndTheWindowClosesPromptly) {
#if !defined(FLASHGS_X11_DROP) || !defined(FLASHGS_X11_INPUT)
  GTEST_SKIP() << "built without Xlib or libXtst: the drop and input helpers are absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string fifo = out_dir() + "/dropped_fifo.ply";
  std::filesystem::remove(fifo);
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { \"$drop\" 600 300 \"" + fifo + "\" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"load failed, scene kept: " + fifo +
                            ": is a FIFO\" || status=12; }\n"
                            "[ $status -eq 0 ] && { close_window || status=14; }\n"
                            "[ $status -eq 0 ] && [ \"$exit_status\" != 0 ] && status=15\n";
  const RunResult r = run_live_viewer(prefix, "drop_fifo", "--backend cpu --size 800x450", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 drop, 12 no FIFO message, 13 crash, 14 close blocked, "
                               "15 exit status)\n"
                            << r.output;
  std::filesystem::remove(fifo);
#endif
}

// A FIFO as the scene or as --then-open in a scripted run: refused at once, not a hang.
TEST(Viewer, AFifoSceneIsRefusedInScriptedRuns) {
  REQUIRE_DISPLAY(prefix);
  const std::string fifo = out_dir() + "/scripted_fifo.ply";
  std::filesystem::remove(fifo);
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // `timeout`: before the fix the viewer blocked in open() for ever.
  const RunResult a = run(prefix + "timeout 120 " + viewer() + " " + fifo + " --backend cpu --size 320x180 --frames 1 --exit");
  EXPECT_EQ(a.exit_code, 2) << a.output;
  EXPECT_NE(a.output.find("load failed (no scene loaded yet): " + fifo + ": is a FIFO"), std::string::npos) << a.output;
  EXPECT_NE(a.output.find("no scene to run the script on"), std::string::npos) << a.output;
  const RunResult b = run(prefix + "timeout 120 " + viewer() + " --backend cpu --size 320x180 --frames 2 --then-open " +
                          fifo + " --exit");
  EXPECT_EQ(b.exit_code, 0) << b.output;
  EXPECT_NE(b.output.find("load failed, scene kept: " + fifo + ": is a FIFO"), std::string::npos) << b.output;
  std::filesystem::remove(fifo);
}

// A real mouse click (XTEST) on the panel's "Compare this view" button runs the comparison:
// ImGui's mouse position and buttons reach it through the viewer's own platform inputs. The
// click starts once the panels are on screen ("UI ready") and the button is held until the
// viewer has seen it down in two frames, so a slow frame on a loaded machine cannot lose it.
TEST(Viewer, MouseClickOnAPanelButtonWorks) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { click \"tab Compare\" && click \"Compare this view (C)\" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"compare flash vs baseline\" || status=12; }\n";
  // The default window height (800): at 720 the Compare button sits below the panels' fold.
  const RunResult r = run_live_viewer(prefix, "click", "--backend cpu --size 1280x800 --log-input", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11 click, 12 no comparison, 13 crash)\n"
                            << r.output;
#endif
}

// The pose logged with each held-button frame (--log-input): camera, forward, right, pivot.
struct LoggedPose {
  double v[12] = {};
  bool ok = false;
};

std::vector<LoggedPose> poses_while_held(const std::string& log, const std::string& token) {
  std::vector<LoggedPose> out;
  std::size_t at = 0;
  while ((at = log.find("held:", at)) != std::string::npos) {
    const std::size_t end = log.find('\n', at);
    const std::string line = log.substr(at, end - at);
    at = end;
    if (line.find(token) == std::string::npos) continue;
    const auto c = line.find("| camera ");
    if (c == std::string::npos) continue;
    LoggedPose p;
    p.ok = std::sscanf(line.c_str() + c, "| camera %lf %lf %lf forward %lf %lf %lf right %lf %lf %lf pivot %lf %lf %lf",
                       &p.v[0], &p.v[1], &p.v[2], &p.v[3], &p.v[4], &p.v[5], &p.v[6], &p.v[7], &p.v[8], &p.v[9],
                       &p.v[10], &p.v[11]) == 12;
    out.push_back(p);
  }
  return out;
}

double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double distance3(const double* a, const double* b) {
  const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return std::sqrt(dot3(d, d));
}

// Real mouse drags (XTEST) over the image: the left button orbits the object-sized demo
// scene (the default mode there) about its pivot, turning the view right when dragged right;
// the right button pans it sideways without turning.
TEST(Viewer, MouseDragsOrbitAndPanTheView) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  // Over the image: right of the main panel, below the statistics (1280x800 at UI scale 1).
  // The pointer is moved, then two frames pass (a harmless key held: Control_R, GLFW 345)
  // before the button goes down, so that the move is not taken as part of the drag.
  auto drag = [](const std::string& button, const std::string& token) {
    return "\"$input\" move 800 600 && hold Control_R \" key345 \" && press " + button + " \"" + token +
           "\" && n=$(grep -cF -- \"" + token + "\" \"$log\") && \"$input\" move 900 600 && wait_count \"" + token +
           "\" $((n + 2)); r=$?; \"$input\" up " + button + "; [ $r -eq 0 ]";
  };
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { " + drag("button", " mouse0 ") + " || status=11; }\n"
                            "[ $status -eq 0 ] && { " + drag("button3", " mouse1 ") + " || status=12; }\n"
                            "[ $status -eq 0 ] && { close_window || status=14; }\n";
  const RunResult r = run_live_viewer(prefix, "drag", "--backend cpu --size 1280x800 --log-input", steps, 13);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11 left drag, 12 right drag, 13 crash, 14 close)\n"
                            << r.output;
  EXPECT_NE(r.output.find("navigation: orbit"), std::string::npos) << r.output;
  const auto left = poses_while_held(r.output, " mouse0 "), right = poses_while_held(r.output, " mouse1 ");
  ASSERT_GE(left.size(), 3u) << r.output;
  ASSERT_GE(right.size(), 3u) << r.output;
  const LoggedPose &a = left.front(), &b = left.back();
  ASSERT_TRUE(a.ok && b.ok) << r.output;
  // Orbit: the view turned right (toward the old right axis), same distance to the same pivot.
  EXPECT_GT(dot3(b.v + 3, a.v + 6), 0.05) << r.output;
  EXPECT_NEAR(distance3(b.v, b.v + 9), distance3(a.v, a.v + 9), 1e-3 * distance3(a.v, a.v + 9));
  EXPECT_LT(distance3(a.v + 9, b.v + 9), 1e-5);
  const LoggedPose &c = right.front(), &d = right.back();
  ASSERT_TRUE(c.ok && d.ok) << r.output;
  // Pan: the same direction, the camera moved left (the scene follows the pointer right).
  EXPECT_GT(dot3(c.v + 3, d.v + 3), 0.999999) << r.output;
  const double moved[3] = {d.v[0] - c.v[0], d.v[1] - c.v[1], d.v[2] - c.v[2]};
  EXPECT_LT(dot3(moved, c.v + 6), -1e-3) << r.output;
#endif
}

// Without zenity or kdialog on PATH, Ctrl+O opens the in-app browser on the scene's folder;
// a click on a PLY there opens it.
TEST(Viewer, CtrlOWithoutADesktopDialogOpensTheInAppBrowser) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  for (const char* tool : {"/usr/bin/zenity", "/usr/bin/kdialog", "/bin/zenity", "/bin/kdialog"})
    if (std::filesystem::exists(tool)) GTEST_SKIP() << tool << " is installed: the desktop dialog would open";
  // The browser opens on the demo's folder: its point_cloud.ply is clicked.
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { \"$input\" move 700 500 && press Control_L \" key341 \" && "
                            "\"$input\" down o && \"$input\" up o; r=$?; \"$input\" up Control_L; [ $r -eq 0 ] || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"file dialog: in-app browser\" || status=12; }\n"
                            "[ $status -eq 0 ] && { click \"browser: point_cloud.ply\" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_count \"point_cloud.ply: 30000 Gaussians\" 2 || status=13; }\n"
                            "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "browser", "--backend cpu --size 1100x700 --log-input", steps, 14,
                                      "PATH=/usr/bin:/bin");
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 Ctrl+O or click, 12 no browser, 13 not loaded, 14 crash, 15 close)\n"
                            << r.output;
#endif
}

// A click (XTEST) on a training camera's frustum jumps to that camera: the test projects the
// demo scene's camera centres into the start view (camera 0's pose with a 150-degree field of
// view, so that the ring of cameras is in it) and clicks on one of them.
TEST(Viewer, ClickingAFrustumJumpsToThatCamera) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  namespace fv = flashgs::viewer;
  const fv::LoadedScene scene = fv::load_scene(flashgs::demo_scene_path());
  ASSERT_GT(scene.cameras.size(), 2u);
  fv::CameraController controller;
  controller.snap_to(scene.cameras[0]);
  const flashgs::Camera view = controller.render_camera(1280, 720, 150.0f);
  // A click on a frustum's body, well away from its centre (before, only a click within 14 px
  // of the centre picked a camera); the frustums as the viewer draws them.
  const float depth = 0.08f * scene.extent;
  const auto segments = fv::project_segments(fv::camera_frustums(scene.cameras, depth, -1), view, 1e-3f);
  ASSERT_EQ(segments.size(), scene.cameras.size() * 10) << "every frustum in front of the start view";
  int target = -1, x = 0, y = 0;
  for (std::size_t k = 1; k < scene.cameras.size() && target < 0; ++k) {
    const fv::ScreenSegment* f = &segments[k * 10];  // segments 0, 2, 4, 6: centre to each image corner
    float cx = 0, cy = 0;
    for (int j = 0; j < 4; ++j) cx += 0.25f * f[2 * j].x1, cy += 0.25f * f[2 * j].y1;
    const float px = f[0].x0 + 0.7f * (cx - f[0].x0), py = f[0].y0 + 0.7f * (cy - f[0].y0);
    bool far_from_centres = true;
    for (std::size_t i = 0; i < scene.cameras.size(); ++i)
      far_from_centres = far_from_centres && std::hypot(segments[i * 10].x0 - px, segments[i * 10].y0 - py) > 20.0f;
    if (far_from_centres && px > 60 && px < 1220 && py > 60 && py < 660 &&
        fv::pick_camera(scene.cameras, view, px, py, 8.0f, depth) == int(k)) {
      target = int(k);
      x = int(std::lround(px));
      y = int(std::lround(py));
    }
  }
  ASSERT_GE(target, 0) << "no camera in the start view";
  const std::string steps = "wait_for \"frame path\" || status=10\n"
                            "[ $status -eq 0 ] && { \"$input\" move " + std::to_string(x) + " " + std::to_string(y) +
                            " && hold Control_R \" key345 \" && hold button \" mouse0 \" || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"clicked the frustum of camera " + std::to_string(target) +
                            "\" || status=12; }\n"
                            "[ $status -eq 0 ] && { close_window || status=14; }\n";
  const RunResult r = run_live_viewer(prefix, "frustum_click",
                                      "--backend cpu --size 1280x720 --camera 0 --fov 150 --frustums --no-ui --log-input", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11 click, 12 not picked, 13 crash, 14 close)\n"
                            << r.output;
#endif
}

// Ctrl+O opens the desktop's dialog (here a stand-in zenity on PATH that answers with a
// scene), and the scene it answers with is loaded.
TEST(Viewer, CtrlOOpensTheSceneChosenInTheDesktopDialog) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string dir = out_dir(), bin = dir + "/fake_dialog_bin", scene = dir + "/dialog_scene.ply";
  std::filesystem::create_directories(bin);
  std::filesystem::copy_file(flashgs::demo_scene_path(), scene, std::filesystem::copy_options::overwrite_existing);
  if (FILE* f = std::fopen((bin + "/zenity").c_str(), "w")) {
    std::fprintf(f, "#!/bin/sh\necho '%s'\n", scene.c_str());
    std::fclose(f);
  }
  std::filesystem::permissions(bin + "/zenity", std::filesystem::perms::owner_all);
  // GLFW key code of Control_L: 341.
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { press Control_L \" key341 \" && \"$input\" down o && \"$input\" up o; "
                            "r=$?; \"$input\" up Control_L; [ $r -eq 0 ] || status=11; }\n"
                            "[ $status -eq 0 ] && { wait_for \"file dialog: zenity\" || status=12; }\n"
                            "[ $status -eq 0 ] && { wait_for \"" + scene + ": 30000 Gaussians\" || status=13; }\n"
                            "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "dialog", "--backend cpu --size 800x450 --log-input", steps, 14,
                                      "PATH=" + bin + ":$PATH");
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 Ctrl+O, 12 no dialog, 13 not loaded, 14 crash, 15 close)\n"
                            << r.output;
#endif
}

// F1 opens the shortcut table, Tab hides the panels (the window then shows the help and the
// hint only), a first Esc asks and a second quits with exit status 0.
TEST(Viewer, F1ShowsHelpTabHidesThePanelsAndEscQuits) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  // GLFW key codes: F1 290, Tab 258, Escape 256.
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { hold F1 \" key290 \" && wait_for \"help shown (F1)\" || status=11; }\n"
                            // The status line stays with the panels hidden: it is drawn (its place logged) after Tab.
                            "lines=$(grep -c 'widget \"status line\" at' \"$log\")\n"
                            "[ $status -eq 0 ] && { hold Tab \" key258 \" && wait_for \"panels hidden (Tab)\" || status=12; }\n"
                            "[ $status -eq 0 ] && { wait_count 'widget \"status line\" at' $((lines + 1)) || status=18; }\n"
                            "[ $status -eq 0 ] && { hold Escape \" key256 \" && wait_for \"press Esc again to quit\" || status=16; }\n"
                            "[ $status -eq 0 ] && { kill -0 $pid 2>/dev/null || status=17; }\n"
                            "[ $status -eq 0 ] && { \"$input\" down Escape; \"$input\" up Escape; "
                            "for _ in $(seq 1 1200); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done; "
                            "if kill -0 $pid 2>/dev/null; then status=15; else wait $pid; exit_status=$?; closed=1; fi; }\n"
                            "[ $status -eq 0 ] && [ \"$exit_status\" != 0 ] && status=14\n";
  const RunResult r = run_live_viewer(prefix, "help_keys", "--backend cpu --size 800x450 --log-input", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 no help, 12 panels not hidden, 13 crash, 14 exit status, 15 the second "
                               "Esc did not quit, 16 the first Esc did not ask, 17 the first Esc quit, 18 no status line "
                               "with the panels hidden)\n"
                            << r.output;
  EXPECT_NE(r.output.find("quit (Esc / Ctrl+Q)"), std::string::npos) << r.output;
#endif
}

// V steps through the views with real key presses: colour, depth, count (each logging its
// legend once its frame is shown), then colour again.
TEST(Viewer, TheVKeyStepsThroughTheViews) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  // GLFW key code: V 86.
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { hold V \" key86 \" && wait_for \"view depth: \" || status=11; }\n"
                            "[ $status -eq 0 ] && { hold V \" key86 \" && wait_for \"view count: \" || status=12; }\n"
                            "[ $status -eq 0 ] && close_window\n";
  const RunResult r = run_live_viewer(prefix, "view_key", "--backend cpu --size 480x270 --log-input", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code << " failed (10 start, 11 no depth view, 12 no count view, 13 crash)\n"
                            << r.output;
  EXPECT_LT(r.output.find("view depth: "), r.output.find("view count: ")) << r.output;
#endif
}

// A path typed into the scene field and sent with Enter that fails to open: the typing goes
// on in the field, so a letter typed next is text, not a shortcut that the settings keep (B
// used to switch to the baseline and leave it in settings.ini).
TEST(Viewer, TypingOnAfterAFailedOpenStaysInThePathField) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string config = out_dir() + "/typing_config";
  std::filesystem::remove_all(config);
  // GLFW key code: B 66.
  const std::string steps =
      "wait_for \"UI ready\" || status=10\n"
      // Each key held across two frames (GLFW key codes: letters their capitals' ASCII, Enter 257).
      "[ $status -eq 0 ] && { click \"path field\" || status=11; }\n"
      "for c in n o p e; do [ $status -eq 0 ] && { hold $c \" key$(printf '%d' \"'${c^^}\") \" || status=11; }; done\n"
      "[ $status -eq 0 ] && { hold Return \" key257 \" || status=11; }\n"
      // (A key held across slow frames may repeat: "nopppe" is as good a wrong path.)
      "[ $status -eq 0 ] && { wait_for \"load failed, scene kept: no\" || status=12; }\n"
      "[ $status -eq 0 ] && { hold b \" key66 \" || status=13; }\n"
      "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "typing_on", "--backend cpu --size 1280x800 --log-input", steps, 14, "", config);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 typing, 12 the open did not fail, 13 B, 14 crash, 15 close)\n"
                            << r.output;
  EXPECT_EQ(r.output.find("options: baseline"), std::string::npos) << "B reached the shortcuts\n" << r.output;
  std::ifstream settings(config + "/flashgs/settings.ini");
  const std::string saved((std::istreambuf_iterator<char>(settings)), std::istreambuf_iterator<char>());
  EXPECT_NE(saved.find("algorithm"), std::string::npos) << "no settings saved\n" << saved;
  EXPECT_EQ(saved.find("baseline"), std::string::npos) << saved;
#endif
}

// Authoring a camera path with real keys: I on camera 1, N, I on camera 2, Ctrl+S saves the
// path; `flashgs render --path` of the saved file renders, at the keys' times, the cameras'
// own views (`flashgs render -c`).
TEST(Viewer, KeysAddedFromTheViewAreSavedAndRenderAsTheCameras) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string dir = out_dir() + "/keys_authored";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/path.json";
  // GLFW key codes: I 73, N 78, S 83.
  const std::string steps =
      "wait_for \"UI ready\" || status=10\n"
      "[ $status -eq 0 ] && { hold i \" key73 \" && wait_for \"key 0 added from the view\" || status=11; }\n"
      "[ $status -eq 0 ] && { hold n \" key78 \" && hold i \" key73 \" && wait_for \"key 1 added from the view\" || status=12; }\n"
      "[ $status -eq 0 ] && { \"$input\" down Control_L; hold s \" key83 \"; \"$input\" up Control_L; "
      "wait_for \"camera path saved to\" || status=13; }\n"
      "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "keys_authored",
                                      "--backend cpu --size 1280x720 --camera 1 --log-input --camera-path \"" + file + "\"",
                                      steps, 14);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 first key, 12 second key, 13 save, 14 crash, 15 close)\n"
                            << r.output;
  const std::string ext = kExt;
  const RunResult path = run(cli() + " render --backend cpu --path \"" + file + "\" -r 320x180 --fps 1 -o " + dir + "/frames");
  ASSERT_EQ(path.exit_code, 0) << path.output;
  EXPECT_NE(path.output.find("2 keyframes, 2.00 s at 1 fps: 3 frames at 320x180"), std::string::npos) << path.output;
  for (int key : {0, 1}) {
    const std::string ref = dir + "/camera" + std::to_string(key + 1) + ext;
    const RunResult c = run(cli() + " render --backend cpu -c " + std::to_string(key + 1) + " -r 320x180 -o " + ref);
    ASSERT_EQ(c.exit_code, 0) << c.output;
    const flashgs::Image a = flashgs::read_image(dir + "/frames/frame_0000" + std::to_string(2 * key) + ext);
    const flashgs::Image b = flashgs::read_image(ref);
    const double psnr = flashgs::compare_images(a, b).psnr_db;
    std::printf("key %d vs camera %d: PSNR %.2f dB\n", key, key + 1, psnr);
    EXPECT_GE(psnr, 40.0) << "key " << key;
  }
#endif
}

// A loaded keyed path renders from the viewer (--export-path) exactly as `flashgs render
// --path` renders it.
TEST(Viewer, TheViewerRendersAKeyedPathAsTheCliDoes) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir() + "/keys_render";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/path.json";
  const float up[3] = {0, 1, 0}, target[3] = {0, 0, 0}, eye0[3] = {3.2f, 2.1f, 0}, eye1[3] = {0.3f, 1.5f, 3.0f};
  flashgs::KeyframePath keys;
  keys.keys = {flashgs::Keyframe::from_camera(flashgs::look_at_camera(eye0, target, up, 192, 108, 60.0f), 0.0),
               flashgs::Keyframe::from_camera(flashgs::look_at_camera(eye1, target, up, 192, 108, 45.0f), 1.5)};
  keys.fps = 2;
  keys.width = 192;
  keys.height = 108;
  flashgs::write_camera_path(keys, file);
  const RunResult v = run(prefix + "env PATH=/usr/bin:/bin " + viewer() + " --backend cpu --size 320x180 --frames 1 --camera-path " +
                          file + " --export-path " + dir + "/viewer --exit");
  ASSERT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("camera path loaded from " + file + ": 2 keys, 1.50 s, 192x108 at 2 fps"), std::string::npos)
      << v.output;
  const RunResult c = run(cli() + " render --backend cpu --path " + file + " -o " + dir + "/cli");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  for (int i = 0; i < 4; ++i) {
    const std::string name = "/frame_0000" + std::to_string(i) + kExt;
    ASSERT_TRUE(std::filesystem::exists(dir + "/viewer" + name)) << name << "\n" << v.output;
    const flashgs::Image a = flashgs::read_image(dir + "/viewer" + name), b = flashgs::read_image(dir + "/cli" + name);
    EXPECT_EQ(a.width, 192);
    EXPECT_GE(flashgs::compare_images(a, b).psnr_db, 60.0) << name;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/viewer/frame_00004" + kExt));
}

// Esc with a combo's list open closes the list, and neither quits nor asks to quit.
TEST(Viewer, EscClosesAnOpenComboFirst) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string steps =
      // The panels settle over a few frames after the load (auto-sized windows): clicks wait
      // for them to stand still, or a loaded machine clicks where the combo is not yet.
      "wait_for \"UI ready\" || status=10\n"
      "[ $status -eq 0 ] && { click \"Kernel (K)\" && wait_for \"popup open\" || status=11; }\n"
      "[ $status -eq 0 ] && { hold Escape \" key256 \" && wait_for \"popup closed (Esc)\" || status=12; }\n"
      "[ $status -eq 0 ] && { grep -q \"press Esc again\" \"$log\" && status=13; }\n"
      "[ $status -eq 0 ] && { kill -0 $pid 2>/dev/null || status=15; }\n"
      "[ $status -eq 0 ] && { close_window || status=16; }\n";
  const RunResult r = run_live_viewer(prefix, "esc_combo", "--backend cpu --size 1280x800 --log-input", steps, 14);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 click, 12 Esc did not close the list, 13 Esc asked to quit, "
                               "14 crash, 15 Esc quit, 16 close)\n"
                            << r.output;
#endif
}

// Ctrl+click on a slider turns it into a text field: what is typed there is clamped to the
// slider's range. The issue's two cases: 0 seconds per camera, then Space (the path then
// divided by zero and read a camera key at index INT_MIN), and a render scale of 40.
TEST(Viewer, TypedSliderValuesAreClampedToTheirRanges) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  if (!flashgs::image_io_writes_png()) GTEST_SKIP() << "F12 saves PNG, which this build cannot write";
  const std::string dir = out_dir();
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().rfind("flashgs_20", 0) == 0) std::filesystem::remove(e.path());
  // Ctrl+click on a slider (where the viewer logged it) types into it. GLFW key codes: Ctrl
  // 341, Enter 257, Space 32.
  auto typed = [](const std::string& slider, const std::string& text) {
    return "press Control_L \" key341 \" && move_to \"" + slider +
           "\" && hold button \" mouse0 \" && \"$input\" up Control_L && \"$input\" type " + text +
           " && hold Return \" key257 \"";
  };
  const std::string steps =
      "wait_for \"UI ready\" || status=10\n"
      "[ $status -eq 0 ] && { " + typed("s per camera", "0") + " || status=11; }\n"
      "[ $status -eq 0 ] && { hold space \" key32 \" || status=12; }\n"
      "[ $status -eq 0 ] && { \"$input\" down F12 && \"$input\" up F12 || status=12; }\n"
      "[ $status -eq 0 ] && { wait_for \"saved ./flashgs_20\" || status=13; }\n"
      "[ $status -eq 0 ] && { cp \"$(ls flashgs_20*.png | head -1)\" playing_after_typed_zero.png; hold space \" key32 \" || status=14; }\n"
      "[ $status -eq 0 ] && { " + typed("Render scale", "40") + " || status=14; }\n"
      "[ $status -eq 0 ] && { \"$input\" down F12 && \"$input\" up F12 || status=14; }\n"
      "[ $status -eq 0 ] && { wait_count \"saved ./flashgs_20\" 2 || status=15; }\n"
      "[ $status -eq 0 ] && { close_window || status=17; }\n";
  std::filesystem::remove(dir + "/playing_after_typed_zero.png");
  const RunResult r = run_live_viewer(prefix, "typed_sliders", "--backend cpu --size 640x720 --log-input --screenshot-dir .", steps, 16);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 typing 0, 12 play + screenshot, 13 no screenshot, 14 typing 40, "
                               "15 no screenshot, 16 crash, 17 close)\n"
                            << r.output;
  // The typed 0 became the range's bottom, 0.1 s; playing then shows the scene (a NaN pose
  // shows only the background).
  EXPECT_NE(r.output.find("playing the camera path: 36 cameras, 0.10 s each"), std::string::npos) << r.output;
  const double lit = lit_fraction(flashgs::read_image(dir + "/playing_after_typed_zero.png"));
  std::printf("playing after a typed 0: %.1f %% of the pixels lit\n", 100.0 * lit);
  EXPECT_GT(lit, 0.05);
  // 40 became the range's top, 4: a 2560x2880 frame.
  EXPECT_NE(r.output.find(".png (2560x2880)"), std::string::npos) << r.output;
#endif
}

// The heat-map shader draws over the frame; its legend bar is the viridis ramp from 0 to the
// maximum, with tick marks and values at round counts and a caption naming the scale.
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
  // The legend as logged: "pairs per 16x16 tile, log scale, ticks 0@0% 1@9% ... MAX@100%".
  const std::string key = "heat-map legend: pairs per 16x16 tile, log scale, ticks ";
  const auto at = a.output.find(key);
  ASSERT_NE(at, std::string::npos) << a.output;
  std::vector<std::pair<long, int>> ticks;  // value, percent along the bar
  {
    const std::string line = a.output.substr(at + key.size(), a.output.find('\n', at) - at - key.size());
    std::size_t i = 0;
    while (i < line.size()) {
      long value = 0;
      int percent = 0;
      if (std::sscanf(line.c_str() + i, "%ld@%d%%", &value, &percent) != 2) break;
      ticks.emplace_back(value, percent);
      i = line.find(' ', i);
      if (i == std::string::npos) break;
      ++i;
    }
  }
  ASSERT_GE(ticks.size(), 3u) << a.output;
  EXPECT_EQ(ticks[0], std::make_pair(0L, 0));
  EXPECT_EQ(ticks[1].first, 1);
  EXPECT_EQ(ticks.back().second, 100);
  const long max_count = ticks.back().first;
  EXPECT_GT(max_count, 10);
  for (std::size_t k = 1; k + 1 < ticks.size(); ++k) {
    EXPECT_EQ(ticks[k].first, ticks[k - 1].first == 0 ? 1 : ticks[k - 1].first * 10) << "log ticks are powers of ten";
    EXPECT_NEAR(ticks[k].second, 100.0 * std::log1p(double(ticks[k].first)) / std::log1p(double(max_count)), 0.6);
  }
  // Bar: x in [480 - 300, 480 - 20), y in [270 - 46, 270 - 32) at UI scale 1; the ramp's
  // colour at each place, and a white tick mark just below the bar at each tick.
  const float x0 = 180.0f, x1 = 460.0f;
  for (float t : {0.02f, 0.25f, 0.5f, 0.75f, 0.98f}) {
    const int x = int(x0 + t * (x1 - x0));
    const float* p = on.pixel(x, 231);
    const auto want = flashgs::viewer::heat_colour((float(x) + 0.5f - x0) / (x1 - x0));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(p[c], want[c], 3.0f / 255.0f) << "bar at t " << t << " channel " << c;
  }
  for (const auto& [value, percent] : ticks) {
    const int x = std::min(int(x1) - 1, int(std::lround(x0 + percent / 100.0 * (x1 - x0))));
    float brightest = 0.0f;
    for (int dx = -1; dx <= 1; ++dx) brightest = std::max(brightest, on.pixel(x + dx, 240)[0]);
    EXPECT_GT(brightest, 0.7f) << "no tick mark for " << value << " at x " << x;
  }
}

// The distance from `p` to the nearest colour of the heat map's ramp (sampled finely).
float distance_to_ramp(const float* p) {
  float best = 1e9f;
  for (int i = 0; i <= 512; ++i) {
    const auto c = flashgs::viewer::heat_colour(float(i) / 512.0f);
    best = std::min(best, std::max({std::abs(p[0] - c[0]), std::abs(p[1] - c[1]), std::abs(p[2] - c[2])}));
  }
  return best;
}

// The fraction of `image`'s pixels off the ramp (by more than 8-bit rounding), black ones aside.
double off_ramp_fraction(const flashgs::Image& image) {
  std::size_t off = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const float* p = image.pixel(x, y);
      if (p[0] + p[1] + p[2] == 0.0f) continue;
      off += distance_to_ramp(p) > 3.0f / 255.0f;
    }
  return double(off) / (double(image.width) * image.height);
}

// --view depth and --view count replace the colour by the debug image (every pixel on the
// ramp, or the background where depth has nothing), each logs its legend, the two differ, the
// depth view is what `flashgs render --view depth` writes, and a bad name is refused naming it.
TEST(Viewer, DepthAndCountViewsReplaceTheColour) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string common = prefix + viewer() + " --backend cpu --size 320x180 --camera 1 --frames 2 --no-ui ";
  std::map<std::string, flashgs::Image> shots;
  std::map<std::string, std::string> logs;
  for (const std::string view : {"colour", "depth", "count"}) {
    const std::string shot = dir + "/view_" + view + kExt;
    std::filesystem::remove(shot);
    const RunResult r = run(common + "--view " + view + " --screenshot " + shot + " --exit");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    shots[view] = flashgs::read_image(shot);
    logs[view] = r.output;
    ASSERT_EQ(shots[view].width, 320) << view;
  }
  EXPECT_EQ(logs["colour"].find("flashgs-viewer: view "), std::string::npos) << logs["colour"];
  EXPECT_GT(off_ramp_fraction(shots["colour"]), 0.2) << "the colour frame is not a debug image";
  EXPECT_LT(off_ramp_fraction(shots["depth"]), 1e-3);
  EXPECT_LT(off_ramp_fraction(shots["count"]), 1e-3);
  EXPECT_LT(flashgs::compare_images(shots["colour"], shots["depth"]).psnr_db, 25.0);
  EXPECT_LT(flashgs::compare_images(shots["depth"], shots["count"]).psnr_db, 25.0);
  // "view depth: blended depth, scene units, near A far B, ticks A@0% ... B@100%"
  const std::string depth_key = "view depth: blended depth, scene units, near ";
  const auto near_at = logs["depth"].find(depth_key);
  ASSERT_NE(near_at, std::string::npos) << logs["depth"];
  const auto far_at = logs["depth"].find(" far ", near_at);
  ASSERT_NE(far_at, std::string::npos) << logs["depth"];
  const double near_z = std::atof(logs["depth"].c_str() + near_at + depth_key.size());
  const double far_z = std::atof(logs["depth"].c_str() + far_at + 5);
  EXPECT_GT(near_z, 0.2) << logs["depth"];
  EXPECT_GT(far_z, near_z) << logs["depth"];
  EXPECT_NE(logs["depth"].find("@100%"), std::string::npos) << logs["depth"];
  const long long max_count = number_after(logs["count"], "Gaussians blended per pixel, log scale, max ");
  EXPECT_GT(max_count, 1) << logs["count"];
  // The nearest blended pixel is dark (the ramp's start), the farthest bright: somewhere the
  // depth image holds both ends.
  float darkest = 1e9f, brightest = 0.0f;
  for (int y = 0; y < 180; ++y)
    for (int x = 0; x < 320; ++x) {
      const float* p = shots["depth"].pixel(x, y);
      if (p[0] + p[1] + p[2] == 0.0f) continue;
      darkest = std::min(darkest, p[1]);
      brightest = std::max(brightest, p[1]);
    }
  EXPECT_LT(darkest, 0.05f);
  EXPECT_GT(brightest, 0.85f);
  // The CLI's depth view of the same frame.
  const std::string ref = dir + "/view_depth_cli" + kExt;
  const RunResult c = run(cli() + " render --backend cpu -c 1 -r 320x180 --view depth -o " + ref);
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find("view depth: blended depth from "), std::string::npos) << c.output;
  EXPECT_GE(flashgs::compare_images(shots["depth"], flashgs::read_image(ref)).psnr_db, 40.0);
  // A name that is no view: one line naming the option, from both programs.
  const RunResult bad = run(common + "--view normals --exit");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.output.find("--view"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("normals"), std::string::npos) << bad.output;
  const RunResult bad_cli = run(cli() + " render --view normals -o " + dir + "/never" + kExt);
  EXPECT_NE(bad_cli.exit_code, 0);
  EXPECT_NE(bad_cli.output.find("--view"), std::string::npos) << bad_cli.output;
}

// OpenImageIO (and the ~240 libraries it brings) is loaded only when an image is read or
// written, not at every start: neither program links it, and both still write PNG (the other
// tests' screenshots and renders).
TEST(ViewerStartup, NeitherProgramLinksOpenImageIO) {
  for (const std::string& program : {viewer(), cli()}) {
    const RunResult r = run("ldd '" + program + "'");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("libOpenImageIO"), std::string::npos) << program << "\n" << r.output;
  }
}

// G / --grid: the ground grid and the world axes are drawn over the frame (the x axis red, the
// y axis green), the frustums in orange.
TEST(Viewer, GridAxesAndFrustumsAreDrawnOverTheFrame) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string with = dir + "/guides_on" + kExt, without = dir + "/guides_off" + kExt;
  const std::string common = prefix + viewer() + " --backend cpu --size 480x270 --frames 2 --no-ui --keys S:1.5 ";
  const RunResult a = run(common + "--grid --frustums --window-screenshot " + with + " --exit");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const RunResult b = run(common + "--window-screenshot " + without + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const flashgs::Image on = flashgs::read_image(with), off = flashgs::read_image(without);
  ASSERT_EQ(on.width, off.width);
  std::size_t changed = 0, red = 0, green = 0, orange = 0;
  for (int y = 30; y < on.height; ++y)  // below the hidden-panels hint
    for (int x = 0; x < on.width; ++x) {
      const float *p = on.pixel(x, y), *q = off.pixel(x, y);
      if (std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) + std::abs(p[2] - q[2]) < 0.1f) continue;
      ++changed;
      red += p[0] > 0.8f && p[1] < 0.4f && p[2] < 0.4f;
      green += p[1] > 0.8f && p[0] < 0.5f && p[2] < 0.5f;
      orange += p[0] > 0.8f && p[1] > 0.4f && p[1] < 0.75f && p[2] < 0.3f;
    }
  std::printf("guides: %zu pixels changed, %zu red, %zu green, %zu orange\n", changed, red, green, orange);
  EXPECT_GT(changed, 2000u);
  EXPECT_GT(red, 5u) << "no x axis";
  EXPECT_GT(green, 5u) << "no y axis";
  EXPECT_GT(orange, 50u) << "no frustums";
}

// "in screenshots": the saved image shows the heat map and its legend as the window does
// (the panels, drawn after, are not in it); without it, the rendered image alone.
TEST(Viewer, ScreenshotsIncludeTheHeatMapWhenAsked) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string with = dir + "/shot_with_overlay" + kExt, plain = dir + "/shot_without_overlay" + kExt;
  const std::string common = prefix + viewer() + " --backend cpu --size 480x270 --camera 1 --frames 2 --heatmap ";
  const RunResult a = run(common + "--screenshot-overlay --screenshot " + with + " --exit");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const RunResult b = run(common + "--screenshot " + plain + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const flashgs::Image on = flashgs::read_image(with), off = flashgs::read_image(plain);
  ASSERT_EQ(on.width, 480);
  ASSERT_EQ(off.width, 480);
  EXPECT_LT(flashgs::compare_images(on, off).psnr_db, 30.0) << "the overlay is not in the screenshot";
  // The legend bar (x 180..460, y 224..238 at UI scale 1) in the ramp's colours.
  const auto want = flashgs::viewer::heat_colour((320.5f - 180.0f) / 280.0f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(on.pixel(320, 231)[c], want[c], 3.0f / 255.0f) << c;
  }
  // Its tick values and caption too (white text above and below the bar; the screenshot had
  // the bar alone): the ramp and the picture hold no white there.
  std::size_t white_below = 0, white_above = 0, white_plain = 0;
  for (int x = 170; x < 472; ++x) {
    for (int y = 239; y < 256; ++y) {
      white_below += on.pixel(x, y)[0] > 0.9f && on.pixel(x, y)[1] > 0.9f && on.pixel(x, y)[2] > 0.9f;
      white_plain += off.pixel(x, y)[0] > 0.9f && off.pixel(x, y)[1] > 0.9f && off.pixel(x, y)[2] > 0.9f;
    }
    for (int y = 208; y < 222; ++y)
      white_above += on.pixel(x, y)[0] > 0.9f && on.pixel(x, y)[1] > 0.9f && on.pixel(x, y)[2] > 0.9f;
  }
  std::printf("legend text in the screenshot: %zu white pixels below the bar, %zu above (%zu without the overlay)\n",
              white_below, white_above, white_plain);
  EXPECT_GT(white_below, 20u) << "no tick values";
  EXPECT_GT(white_above, 40u) << "no caption";
  EXPECT_EQ(white_plain, 0u) << "white there without the overlay: the checks above prove nothing";
}

// The split view: left of the divider the baseline's render, right of it the current
// configuration's, a white line between; the difference view shows |error| magnified, lit
// exactly where the two renders differ.
TEST(Viewer, SplitViewAndDifferenceImageShowTheTwoConfigurations) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir();
  const std::string split = dir + "/split_view" + kExt, diff = dir + "/difference_view" + kExt;
  const std::string base = dir + "/split_baseline" + kExt, flash = dir + "/split_flash" + kExt;
  const std::string common = prefix + viewer() + " --backend cpu --size 480x270 --camera 5 --frames 2 ";
  const RunResult a = run(common + "--no-ui --compare --split-at 0.4 --window-screenshot " + split + " --exit");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const RunResult b = run(common + "--no-ui --compare --compare-view difference --window-screenshot " + diff + " --exit");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const RunResult c = run(common + "--algorithm baseline --screenshot " + base + " --exit");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const RunResult d = run(common + "--screenshot " + flash + " --exit");
  ASSERT_EQ(d.exit_code, 0) << d.output;
  const auto factor_at = b.output.find("difference image x");
  ASSERT_NE(factor_at, std::string::npos) << b.output;
  const double factor = std::atof(b.output.c_str() + factor_at + std::string("difference image x").size());
  EXPECT_GE(factor, 1.0);
  const flashgs::Image s = flashgs::read_image(split), e = flashgs::read_image(diff);
  const flashgs::Image l = flashgs::read_image(base), r = flashgs::read_image(flash);
  ASSERT_EQ(s.width, 480);
  ASSERT_EQ(l.width, 480);
  // Rows clear of the labels (bottom) and the hidden-panels hint (top left).
  const int divider = int(0.4 * 480);
  std::size_t left_off = 0, right_off = 0, sides_differ = 0, dark_where_differ = 0;
  for (int y = 30; y < 200; ++y)
    for (int x = 0; x < 480; ++x) {
      if (std::abs(x - divider) <= 2) continue;
      const float* got = s.pixel(x, y);
      const float* want = x < divider ? l.pixel(x, y) : r.pixel(x, y);
      // Exact 8-bit equality: the sides differ by one step at most pixels where they differ.
      bool same = true, differ = false, differ_clearly = false;
      for (int k = 0; k < 3; ++k) {
        same = same && std::abs(got[k] - want[k]) <= 0.5f / 255.0f;
        const float between = std::abs(l.pixel(x, y)[k] - r.pixel(x, y)[k]);
        differ = differ || between > 0.5f / 255.0f;
        differ_clearly = differ_clearly || between > 1.5f / 255.0f;
      }
      (x < divider ? left_off : right_off) += !same;
      sides_differ += differ;
      // Two 8-bit steps apart, the float renders differ by more than one: magnified, it shows.
      const float* shown = e.pixel(x, y);
      dark_where_differ += differ_clearly && shown[0] + shown[1] + shown[2] < 0.5f / 255.0f;
    }
  std::printf("split view: %zu / %zu pixels off on the left / right; renders differ at %zu pixels, factor x%.0f\n",
              left_off, right_off, sides_differ, factor);
  EXPECT_EQ(left_off, 0u) << "left of the divider is not the baseline's render";
  EXPECT_EQ(right_off, 0u) << "right of the divider is not the current configuration's render";
  EXPECT_EQ(dark_where_differ, 0u) << "the difference image is black where the renders differ";
  // The divider: a white line at 40 % of the width.
  for (int y : {40, 120, 190}) EXPECT_GT(s.pixel(divider, y)[0] + s.pixel(divider, y)[1] + s.pixel(divider, y)[2], 2.9f);
  EXPECT_GT(sides_differ, 0u) << "baseline and flash render alike here: the check above proves nothing";
}

// Baseline against baseline is refused with the reason, and nothing is drawn over the frame.
TEST(Viewer, ComparingAConfigurationWithItselfIsRefused) {
  REQUIRE_DISPLAY(prefix);
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 320x180 --camera 2 --frames 2 --algorithm baseline "
                          "--compare --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("compare: both sides are baseline: nothing to compare"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("viewer compare:"), std::string::npos) << r.output;
}

// One loop of the camera path as an image sequence; without ffmpeg on PATH, the sequence only.
TEST(Viewer, ThePathExportsAsAnImageSequence) {
  REQUIRE_DISPLAY(prefix);
  const std::string folder = out_dir() + "/path_export";
  std::filesystem::remove_all(folder);
  const RunResult r = run(prefix + "env PATH=/usr/bin:/bin " + viewer() + " --backend cpu --size 160x90 --frames 1 "
                          "--export-path " + folder + " --export-frames 4 --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  if (std::filesystem::exists("/usr/bin/ffmpeg") || std::filesystem::exists("/bin/ffmpeg")) GTEST_SKIP() << "ffmpeg is in /usr/bin: the no-video case cannot be run";
  EXPECT_NE(r.output.find("path export: 4 frames in " + folder + " (no ffmpeg on PATH: image sequence only)"),
            std::string::npos) << r.output;
  std::vector<flashgs::Image> frames;
  for (int i = 0; i < 4; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%05d", i);
    ASSERT_TRUE(std::filesystem::exists(folder + name + kExt)) << name;
    frames.push_back(flashgs::read_image(folder + name + kExt));
    EXPECT_EQ(frames.back().width, 160);
  }
  EXPECT_FALSE(std::filesystem::exists(folder + "/frame_00004" + kExt));
  EXPECT_LT(flashgs::compare_images(frames[0], frames[2]).psnr_db, 30.0) << "the frames do not follow the path";
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

// Bad option values: one line naming the option, a non-zero exit, no window opened. `timeout`:
// before the fix some were accepted and the viewer ran.
TEST(Viewer, NonFiniteAndOutOfRangeOptionsAreRefusedNamingTheOption) {
  const std::pair<const char*, const char*> cases[] = {
      {"--scale nan", "--scale"},          {"--scale inf", "--scale"},     {"--scale 40", "--scale"},
      {"--fov nan", "--fov"},              {"--tau nan", "--tau"},         {"--background 0,nan,0", "--background"},
      {"--camera -1", "--camera"},         {"--render-size 0x10", "--render-size"},
      {"--render-size 99999999999x1", "--render-size"}, {"--size 12x", "--size"},
      {"--compare-left nonsense", "--compare-left"}, {"--split-at nan", "--split-at"},
      {"--split-at 2", "--split-at"},      {"--export-frames 0", "--export-frames"}};
  for (const auto& [args, option] : cases) {
    const RunResult r = run("timeout 60 " + viewer() + " " + args + " --backend cpu --frames 1 --exit");
    EXPECT_NE(r.exit_code, 0) << args << "\n" << r.output;
    EXPECT_EQ(r.output.rfind(std::string(option) + ": ", 0), 0u) << args << ": the first line must name the option\n"
                                                                 << r.output;
  }
}

TEST(Viewer, ACameraBeyondTheSceneIsAnErrorNamingTheOption) {
  REQUIRE_DISPLAY(prefix);
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 320x180 --camera 99 --frames 1 --exit");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--camera 99: the scene has 36 cameras (0..35)"), std::string::npos) << r.output;
}

// --lod opens that level of a SOG LOD set (as `flashgs render --lod` does); a level the set
// lacks, or a scene that is no LOD set, is one line naming the option.
TEST(Viewer, TheLodOptionOpensThatLevelAndABadOneIsNamed) {
  REQUIRE_DISPLAY(prefix);
  const std::string set = flashgs::test::shared_format_file("playbot_sog");
  if (set.empty()) GTEST_SKIP() << "../shared/scenes/formats/playbot_sog is absent";
  const std::string common = prefix + viewer() + " --backend cpu --size 320x180 --frames 1 --exit ";
  const RunResult coarse = run(common + "'" + set + "'" + " --lod 6");
  EXPECT_EQ(coarse.exit_code, 0) << coarse.output;
  EXPECT_NE(coarse.output.find(": LOD level 6 of 0..6, "), std::string::npos) << coarse.output;
  const RunResult beyond = run(common + "'" + set + "'" + " --lod 7");
  EXPECT_EQ(beyond.exit_code, 2) << beyond.output;
  EXPECT_NE(beyond.output.find("load failed (no scene loaded yet): --lod 7: "), std::string::npos) << beyond.output;
  EXPECT_NE(beyond.output.find("the set has levels 0..6"), std::string::npos) << beyond.output;
  const RunResult no_set = run(common + "--lod 1");  // the bundled demo PLY
  EXPECT_EQ(no_set.exit_code, 2) << no_set.output;
  EXPECT_NE(no_set.output.find("--lod 1: "), std::string::npos) << no_set.output;
  EXPECT_NE(no_set.output.find("not a SOG LOD set"), std::string::npos) << no_set.output;
  const RunResult both = run(viewer() + " --lod 1 --generate-demo 1000");  // refused before any window
  EXPECT_NE(both.exit_code, 0) << both.output;
  EXPECT_NE(both.output.find("--lod excludes --generate-demo"), std::string::npos) << both.output;
}

// --stream draws a LOD set at the detail each view needs: with a zero error bound that is every
// cell at level 0, the frame of the scene the set was built from, handed to the renderer as one
// part per leaf (set_scene_parts), once, as the scripted view settles before it; a scene that is
// no LOD set is drawn whole, with one line saying so.
TEST(Viewer, StreamingALodSetAtFullDetailShowsTheSourceScenesFrame) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir(), set = dir + "/stream_demo_set";
  std::filesystem::remove_all(set);
  flashgs::LodBuildOptions options;
  options.leaf_gaussians = 2048;
  const flashgs::LodBuildReport built = flashgs::build_lod_set(flashgs::demo_scene_path(), set, options);
  ASSERT_GT(built.leaves, 1);
  std::filesystem::copy_file(flashgs::demo_cameras_path(), set + "/cameras.json");
  const std::string common = prefix + viewer() + " --backend cpu --size 320x180 --camera 7 --frames 2 --exit ";
  const RunResult streamed = run(common + "'" + set + "' --stream --max-error-px 0 --screenshot " + dir + "/streamed.pfm");
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_NE(streamed.output.find("streaming " + set + "/lod-meta.json by view"), std::string::npos) << streamed.output;
  EXPECT_NE(streamed.output.find("stream settled: 30.0k drawn (levels 0:30.0k)"), std::string::npos) << streamed.output;
  const std::string parts = std::to_string(built.leaves) + " parts handed over (hand-over 1: " +
                            std::to_string(built.leaves) + " new)";
  EXPECT_NE(streamed.output.find(parts), std::string::npos) << "wanted \"" << parts << "\"\n" << streamed.output;
  EXPECT_EQ(streamed.output.find("goes to the renderer assembled"), std::string::npos) << streamed.output;
  const RunResult whole = run(common + "--screenshot " + dir + "/whole.pfm");
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  const flashgs::ImageDifference d =
      flashgs::compare_images(flashgs::read_image(dir + "/streamed.pfm"), flashgs::read_image(dir + "/whole.pfm"));
  std::printf("streamed at full detail vs the source scene: %.1f dB, max |difference| %.2e\n", d.psnr_db, d.max_abs);
  EXPECT_GT(d.psnr_db, 90.0);  // the chunks keep log scale and logit opacity: a float round trip
  const RunResult not_a_set = run(common + "--stream");
  EXPECT_EQ(not_a_set.exit_code, 0) << not_a_set.output;
  EXPECT_NE(not_a_set.output.find("is not a LOD set: drawn whole"), std::string::npos) << not_a_set.output;
}

namespace {

// The share of lit pixels whose colour points the way of one of the level palette's colours
// (over a black background a pixel is its Gaussians' colours weighted by their coverage).
double palette_share(const flashgs::Image& image, int levels) {
  std::size_t lit = 0, matching = 0;
  for (std::size_t p = 0; p + 2 < image.rgb.size(); p += 3) {
    const float* c = &image.rgb[p];
    const double norm = std::sqrt(double(c[0]) * c[0] + double(c[1]) * c[1] + double(c[2]) * c[2]);
    if (norm < 0.05) continue;
    ++lit;
    for (int level = 0; level < levels; ++level) {
      const std::array<float, 3> q = flashgs::lod_level_colour(level);
      const double qn = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2]);
      if ((c[0] * q[0] + c[1] * q[1] + c[2] * q[2]) / (norm * qn) > 0.995) {
        ++matching;
        break;
      }
    }
  }
  return lit ? double(matching) / double(lit) : 0.0;
}

}  // namespace

// --lod-overlay draws each Gaussian in its level's colour: the streamed image's colours come
// from the palette (the scene's own colours do not). The overlay's frame is drawn from parts
// (tinted copies of the cut's parts), handed over as the plain cut is.
TEST(Viewer, TheLevelOverlayColoursTheStreamedImageByLevel) {
  REQUIRE_DISPLAY(prefix);
  const std::string dir = out_dir(), set = dir + "/overlay_demo_set";
  std::filesystem::remove_all(set);
  flashgs::LodBuildOptions options;
  options.leaf_gaussians = 2048;
  const flashgs::LodBuildReport built = flashgs::build_lod_set(flashgs::demo_scene_path(), set, options);
  std::filesystem::copy_file(flashgs::demo_cameras_path(), set + "/cameras.json");
  const std::string common = prefix + viewer() + " --backend cpu --size 320x180 --camera 7 --frames 2 --exit '" + set +
                             "' --stream --max-error-px 8 ";  // four levels at 320x180
  const RunResult tinted = run(common + "--lod-overlay --screenshot " + dir + "/overlay.pfm");
  ASSERT_EQ(tinted.exit_code, 0) << tinted.output;
  EXPECT_NE(tinted.output.find("level overlay on"), std::string::npos) << tinted.output;
  const RunResult plain = run(common + "--screenshot " + dir + "/no_overlay.pfm");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  // The same cut, as many parts with the overlay as without: one per leaf drawn.
  const auto handed_parts = [](const std::string& output) {
    const std::size_t at = output.find(" parts handed over (hand-over 1: ");
    const std::size_t start = output.rfind(' ', at == std::string::npos ? 0 : at - 1);
    return at == std::string::npos || start == std::string::npos ? -1 : std::stoi(output.substr(start + 1, at - start - 1));
  };
  EXPECT_GT(handed_parts(tinted.output), 0) << tinted.output;
  EXPECT_EQ(handed_parts(tinted.output), handed_parts(plain.output)) << tinted.output << plain.output;
  const double with = palette_share(flashgs::read_image(dir + "/overlay.pfm"), built.levels);
  const double without = palette_share(flashgs::read_image(dir + "/no_overlay.pfm"), built.levels);
  std::printf("lit pixels in a palette colour: %.3f with the overlay, %.3f without\n", with, without);
  // Measured: 0.89 and 0.02 (pixels where cells of two levels overlap mix two palette colours).
  EXPECT_GT(with, 0.8);
  EXPECT_LT(without, 0.3);
}

// --stream of a scene file builds its LOD set once into a cache folder beside it (keyed by the
// file's path, size and time), streams it, and opens the cached set next time without building;
// a changed file builds anew. Where the file's folder is not writable, the user's cache serves.
TEST(Viewer, StreamingASceneFileBuildsItsLodSetOnceAndThenOpensTheCachedSet) {
  REQUIRE_DISPLAY(prefix);
  namespace fs = std::filesystem;
  const std::string dir = out_dir() + "/stream_cache";
  fs::remove_all(dir);
  fs::create_directories(dir + "/scene");
  const std::string ply = dir + "/scene/demo.ply";
  fs::copy_file(flashgs::demo_scene_path(), ply);
  fs::copy_file(flashgs::demo_cameras_path(), dir + "/scene/cameras.json");
  auto cache_folders = [&] {
    std::vector<std::string> found;
    for (const auto& e : fs::directory_iterator(dir + "/scene"))
      if (e.path().filename().string().rfind("demo.ply.lod-", 0) == 0) found.push_back(e.path().string());
    return found;
  };
  const std::string command = prefix + "env XDG_CACHE_HOME='" + dir + "/cache' " + viewer() +
                              " --backend cpu --size 320x180 --camera 7 --frames 2 --exit --stream --max-error-px 0"
                              " --lod-leaf-size 2048 --lod-file-size 8192 '" + ply + "' --screenshot ";
  const RunResult first = run(command + dir + "/first.pfm");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("building the LOD set of " + ply), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("built the LOD set of " + ply), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("stream settled: 30.0k drawn (levels 0:30.0k)"), std::string::npos) << first.output;
  ASSERT_EQ(cache_folders().size(), 1u);
  const std::string folder = cache_folders()[0];
  EXPECT_TRUE(fs::exists(folder + "/lod-meta.json"));
  EXPECT_NE(first.output.find("streaming " + folder + "/lod-meta.json by view"), std::string::npos) << first.output;

  const RunResult again = run(command + dir + "/again.pfm");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(again.output.find("building the LOD set"), std::string::npos) << again.output;
  EXPECT_NE(again.output.find("opened the cached LOD set of " + ply + ": " + folder + "/lod-meta.json"), std::string::npos)
      << again.output;
  const flashgs::ImageDifference same =
      flashgs::compare_images(flashgs::read_image(dir + "/first.pfm"), flashgs::read_image(dir + "/again.pfm"));
  EXPECT_EQ(same.max_abs, 0.0);

  // Another modification time: another key, built anew beside the old one.
  fs::last_write_time(ply, fs::last_write_time(ply) + std::chrono::seconds(5));
  const RunResult changed = run(command + dir + "/changed.pfm");
  ASSERT_EQ(changed.exit_code, 0) << changed.output;
  EXPECT_NE(changed.output.find("built the LOD set of " + ply), std::string::npos) << changed.output;
  EXPECT_EQ(cache_folders().size(), 2u);

  if (::geteuid() != 0) {  // permissions do not bind root
    fs::remove_all(dir + "/scene/" + fs::path(folder).filename().string());
    for (const std::string& f : cache_folders()) fs::remove_all(f);
    fs::permissions(dir + "/scene", fs::perms::owner_write, fs::perm_options::remove);
    const RunResult read_only = run(command + dir + "/read_only.pfm");
    fs::permissions(dir + "/scene", fs::perms::owner_write, fs::perm_options::add);
    ASSERT_EQ(read_only.exit_code, 0) << read_only.output;
    EXPECT_NE(read_only.output.find("into " + dir + "/cache/flashgs/lod/demo.ply-"), std::string::npos) << read_only.output;
    EXPECT_TRUE(cache_folders().empty());
  }
  // A file that is not a scene: one line naming it, nothing left behind.
  const std::string broken = dir + "/scene/broken.ply";
  std::ofstream(broken) << "ply\nformat binary_little_endian 1.0\nelement vertex 5\nend_header\n";
  const RunResult bad = run(prefix + "env XDG_CACHE_HOME='" + dir + "/cache' " + viewer() +
                            " --backend cpu --size 320x180 --frames 1 --exit --stream '" + broken + "'");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("load failed (no scene loaded yet): " + broken), std::string::npos) << bad.output;
  for (const auto& e : fs::directory_iterator(dir + "/scene"))
    EXPECT_EQ(e.path().filename().string().find("broken.ply.lod-"), std::string::npos) << e.path();
}

// Interactive, the build of a scene file's LOD set is the scene's load beside the window: its
// progress shows, and the set streams once it is built.
TEST(Viewer, AStreamedSceneFilesBuildShowsAsTheLoadsProgress) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string dir = out_dir() + "/stream_cache_live";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file(flashgs::demo_scene_path(), dir + "/demo.ply");
  const std::string steps = "wait_for \"load progress shown\" || status=11\n"
                            "[ $status -eq 0 ] && { open_load_gate; wait_for \"built the LOD set of\" || status=12; }\n"
                            "[ $status -eq 0 ] && { wait_for \"stream settled\" || status=14; }\n"
                            "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "stream_cache_live",
                                      "--backend cpu --size 1280x800 --stream --lod-leaf-size 2048 '" + dir + "/demo.ply'" +
                                          load_gate_args("stream_cache_live"),
                                      steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (11 progress, 12 build, 13 crash, 14 stream, 15 close)\n" << r.output;
  EXPECT_NE(r.output.find("streaming " + dir + "/demo.ply.lod-"), std::string::npos) << r.output;
#endif
}

// The Scene panel's "level colours" box turns the overlay on while the set streams (a real
// click, XTEST), and off again.
TEST(Viewer, TheLevelColoursBoxTurnsTheOverlayOnAndOffLive) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string set = out_dir() + "/live_overlay_set";
  std::filesystem::remove_all(set);
  flashgs::LodBuildOptions options;
  options.leaf_gaussians = 2048;
  flashgs::build_lod_set(flashgs::demo_scene_path(), set, options);
  const std::string steps = "wait_for \"UI ready\" || status=10\n"
                            "[ $status -eq 0 ] && { wait_for \"stream settled\" || status=11; }\n"
                            "[ $status -eq 0 ] && { click \"level colours\" && wait_for \"level overlay on\" || status=12; }\n"
                            "[ $status -eq 0 ] && { click \"level colours\" && wait_for \"level overlay off\" || status=14; }\n"
                            "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "live_overlay",
                                      "--backend cpu --size 1280x800 --log-input --stream --max-error-px 8 '" + set + "'", steps, 13);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 stream, 12 overlay on, 13 crash, 14 overlay off, 15 close)\n" << r.output;
#endif
}

// Frames and scenes too large for this machine are refused with their figures, before any
// allocation (no std::bad_alloc, no abort).
TEST(Viewer, ARenderSizeBeyondMemoryOrTextureLimitIsRefused) {
  REQUIRE_DISPLAY(prefix);
  const RunResult r = run(prefix + viewer() + " --backend cpu --size 320x180 --render-size 32768x28800 --frames 1 --exit");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--render-size 32768x28800 refused: a 32768x28800 frame"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" GB of memory"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("bad_alloc"), std::string::npos) << r.output;
}

TEST(Viewer, AGeneratedOrTiledSceneBeyondMemoryIsRefused) {
  REQUIRE_DISPLAY(prefix);
  namespace fv = flashgs::viewer;
  // 200 M demo Gaussians (SH degree 1); a machine with room for them would really build them.
  const std::uint64_t need = fv::scene_bytes(200000000, fv::scene_bytes_per_gaussian(1));
  if (double(need) <= fv::kMemoryShare * double(flashgs::system_available_memory()))
    GTEST_SKIP() << "this machine has memory for " << flashgs::format_bytes(need) << ": nothing to refuse";
  const RunResult a = run(prefix + viewer() + " --backend cpu --size 320x180 --generate-demo 200000000 --frames 1 --exit");
  EXPECT_EQ(a.exit_code, 2) << a.output;
  // The reason first, then what follows from it (the run has no scene).
  const auto reason = a.output.find("load failed (no scene loaded yet): --generate-demo 200000000: the scene would need about");
  EXPECT_NE(reason, std::string::npos) << a.output;
  EXPECT_GT(a.output.find("no scene to run the script on"), reason) << a.output;
  const RunResult b = run(prefix + viewer() + " --backend cpu --size 320x180 --generate-demo 200000 --tile 1000 --frames 1 --exit");
  EXPECT_EQ(b.exit_code, 2) << b.output;
  EXPECT_NE(b.output.find("--tile 1000 refused: the scene would need about"), std::string::npos) << b.output;
}

// A window times the render scale beyond OpenGL's texture limit: the frame falls back to a
// size that fits, with one line saying so, and the run goes on.
TEST(Viewer, ARenderSizeBeyondTheTextureLimitFallsBackToOneThatFits) {
  REQUIRE_DISPLAY(prefix);
  const RunResult probe = run(prefix + viewer() + " --backend cpu --size 64x36 --frames 1 --exit");
  ASSERT_EQ(probe.exit_code, 0) << probe.output;
  const auto at = probe.output.find("textures up to ");
  ASSERT_NE(at, std::string::npos) << probe.output;
  const int limit = std::atoi(probe.output.c_str() + at + std::string("textures up to ").size());
  ASSERT_GT(limit, 0);
  const int window = limit / 4 + 8, wanted = window * 4;  // at scale 4: just over the limit
  const std::string shot = out_dir() + "/fallback" + kExt;
  const RunResult r = run(prefix + viewer() + " --backend cpu --size " + std::to_string(window) +
                          "x8 --scale 4 --frames 2 --screenshot " + shot + " --exit");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string refused = "render size " + std::to_string(wanted) + "x32 refused: a " + std::to_string(wanted) +
                              "x32 frame is larger than OpenGL's texture limit of " + std::to_string(limit);
  EXPECT_NE(r.output.find(refused), std::string::npos) << r.output;
  const flashgs::Image image = flashgs::read_image(shot);
  EXPECT_LE(image.width, limit);
  EXPECT_EQ(image.width, wanted / 2);
}

// An allocation failure inside a frame (here forced by a 3 GB address-space limit) is one line
// and exit 2 from a scripted run, not "std::bad_alloc" from the top level.
TEST(Viewer, AFrameThatRunsOutOfMemoryIsReportedNotFatal) {
  SKIP_IF_ADDRESS_SPACE_CAP_MEETS_SANITIZER();
  REQUIRE_DISPLAY(prefix);
  // 2 GB of address space: the viewer's own (Mesa, the threads' stacks) and the frame's 1.7 GB
  // of float RGB do not fit, so the render runs out before any texture is asked for.
  const RunResult r = run(prefix + "sh -c 'ulimit -v 2000000; exec " + viewer() +
                          " --backend cpu --size 320x180 --render-size 12000x12000 --frames 2 --exit'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("a 12000x12000 frame failed: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("out of memory"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("flashgs-viewer: error:"), std::string::npos) << r.output;
}

// The viewer's "NAME: N ms" figure from a log line containing `key`, or -1.
double logged_ms(const std::string& log, const std::string& key) {
  const auto at = log.find(key);
  if (at == std::string::npos) return -1;
  return std::atof(log.c_str() + at + key.size());
}

// The worst UI frame from the viewer's exit summary, and how many it counted (-1: no summary).
double worst_ui_frame_ms(const std::string& log, double* frames) {
  *frames = logged_ms(log, "UI frames while a frame rendered in the background: ");
  const auto at = log.find(", worst ", log.find("UI frames while a frame rendered"));
  return at == std::string::npos ? -1 : std::atof(log.c_str() + at + 8);
}

// The shortest full-size render the viewer logged (--log-input), or -1 if none. A UI frame
// that waited for a render would take at least this long, on a loaded machine as on an idle
// one, so it bounds the worst UI frame without a fixed figure (a fixed 100 ms failed on CI,
// where llvmpipe's swap alone took 87 ms beside the other tests).
double shortest_full_render_ms(const std::string& log) {
  const std::string key = "(full) rendered in ";
  double shortest = -1;
  for (auto at = log.find(key); at != std::string::npos; at = log.find(key, at + 1)) {
    const double ms = std::atof(log.c_str() + at + key.size());
    if (shortest < 0 || ms < shortest) shortest = ms;
  }
  return shortest;
}

#ifdef FLASHGS_X11_INPUT
// The live tests on pc_playbot: a private display (their XTEST input must not reach another
// session's) and the scene, its folder made canonical.
#define REQUIRE_LIVE_PLAYBOT(prefix, dir)                                                    \
  REQUIRE_DISPLAY(prefix);                                                                   \
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";                   \
  const std::string dir = playbot_dir();                                                     \
  if (dir.empty()) GTEST_SKIP() << "../shared/scenes/pc_playbot is absent: skipped"

std::string playbot_dir() {
  const std::string found = flashgs::test::shared_scene_dir("pc_playbot");
  return found.empty() ? found : std::filesystem::canonical(found).string();
}

// The viewer on pc_playbot in a `window`-sized window, its frames rendered at 2048x1200 on one
// thread (a core stays free for the test's script) behind the render gate of run `name`.
std::string gated_playbot_viewer_args(const std::string& dir, const std::string& window, const std::string& name) {
  return "\"" + dir + "/point_cloud.ply\" --backend cpu --threads 1 --size " + window +
         " --render-size 2048x1200 --log-input" + gate_args(name);
}
#endif

// While the CPU renders a frame of pc_playbot on the worker thread, a real click (XTEST) on a
// checkbox is answered: the frames that see the button held are logged while the frame is in
// flight (held there by the render gate, however fast the machine), the option changes, and
// no UI frame while a frame rendered took as long as a render (the viewer measures each from
// input to swap; before the worker, each took as long as a render). The frame times are
// printed; the 100 ms goal is a figure, not an assertion, since a loaded machine's swap varies.
TEST(Viewer, TheUiAnswersAClickWhileACpuRenderIsInFlight) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_LIVE_PLAYBOT(prefix, dir);
  // H turns the heat map on (a new full frame starts and waits at the closed gate), then the
  // "Tight box" checkbox is clicked; the gate opens and the frame of the new options is shown.
  // 1024x600: the sections are open from 600 points up, and the swap (llvmpipe drawing the
  // window, Xvfb copying it) is most of a UI frame's time here.
  const std::string steps =
      "wait_for \"first frame shown\" || status=10\n"
      "close_gate\n"
      "[ $status -eq 0 ] && { hold H \" key72 \" || status=11; }\n"
      "[ $status -eq 0 ] && { click \"Tight box\" || status=12; }\n"
      "[ $status -eq 0 ] && { wait_for \"options: flash-no_tight_bbox\" || status=13; }\n"
      "open_gate\n"
      "[ $status -eq 0 ] && { wait_count \"(full) rendered in\" 2 || status=16; }\n"
      "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "ui_while_rendering",
                                      gated_playbot_viewer_args(dir, "1024x600", "ui_while_rendering"),
                                      steps, 14);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 first frame, 11 H, 12 click, 13 option not changed, 14 crash, 15 close, "
                               "16 no frame after the gate opened)\n"
                            << r.output;
  bool seen_while_rendering = false;  // a held-button line of a frame that began with a render in flight
  for (std::size_t at = r.output.find("held: mouse0 at "); at != std::string::npos;
       at = r.output.find("held: mouse0 at ", at + 1)) {
    const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
    seen_while_rendering |= line.find("(a frame is rendering)") != std::string::npos;
  }
  EXPECT_TRUE(seen_while_rendering) << "the click was not seen while a frame rendered\n" << r.output;
  // A click on a checkbox is the panel's: the view does not turn (the cursor jumped there).
  const auto held = r.output.find("held: mouse0 at ");
  ASSERT_NE(held, std::string::npos) << r.output;
  const auto last_held = r.output.rfind("held: mouse0 at ");
  auto forward = [&](std::size_t at) {
    const auto f = r.output.find(" forward ", at);
    return r.output.substr(f, r.output.find(" right ", f) - f);
  };
  EXPECT_EQ(forward(held), forward(last_held)) << "clicking a checkbox turned the view\n" << r.output;
  double frames = 0;
  const double worst_ms = worst_ui_frame_ms(r.output, &frames);
  ASSERT_GE(worst_ms, 0.0) << r.output;
  const double render_ms = shortest_full_render_ms(r.output);
  std::printf("UI frames while rendering: %.0f, worst %.1f ms; shortest full render %.0f ms\n", frames, worst_ms,
              render_ms);
  EXPECT_GE(frames, 2.0);
  EXPECT_LT(worst_ms, render_ms) << r.output;
#endif
}

#ifdef FLASHGS_X11_INPUT
// A continuous change on the CPU path (a drag, a slider) goes on showing frames: a newer request
// does not cancel the frame in flight; that frame is shown, and the newest request renders after
// it. Before, each UI frame's change cancelled the frame in flight, so changes coming faster than
// a frame rendered showed nothing until they ended (pc_biker at 1280x800 on two cores: no frame
// in the first 570 UI frames of a drag, 3 frames in a 3-second drag of the FOV slider).
// `to_start` sets the shell's x and y and moves the pointer there; the button goes down and the
// pointer moves 10 px right three times. The render gate holds the first frame of the change
// while the other two come (each move logged twice, so that the second line is of a UI frame
// after the one that asked for its frame); the render size is pinned, so that no change asks for
// fewer pixels. Returns the viewer's log.
std::string expect_continuous_change_keeps_frame(const std::string& prefix, const std::string& name,
                                                 const std::string& viewer_args, const std::string& to_start) {
  const std::string steps =
      "wait_for \"first frame shown\" || status=10\n"
      "shown=$(grep -c \"frame shown\" \"$log\")\n"
      "close_gate\n" + to_start +
      "[ $status -eq 0 ] && { press button \" mouse0 \" || status=11; }\n"
      "\"$input\" move $((x + 10)) $y\n"
      "[ $status -eq 0 ] && { wait_for \"render gate: a 320x180 frame waits\" || status=12; }\n"
      "for k in 2 3; do\n"
      "  \"$input\" move $((x + 10 * k)) $y\n"
      "  [ $status -eq 0 ] && { wait_count \"held: mouse0 at $((x + 10 * k)),$y \" 2 || status=13; }\n"
      "done\n"
      "open_gate\n"
      "[ $status -eq 0 ] && { wait_count \"frame shown\" $((shown + 1)) || status=14; }\n"
      "\"$input\" up button\n"
      "[ $status -eq 0 ] && { close_window || status=16; }\n";
  const RunResult r = run_live_viewer(prefix, name,
                                      viewer_args + " --backend cpu --render-size 320x180 --log-input" + gate_args(name),
                                      steps, 15);
  EXPECT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 first frame, 11 press, 12 no frame at the gate, 13 moves not taken, "
                               "14 no frame shown, 15 crash, 16 close, 17 start not found)\n"
                            << r.output;
  EXPECT_EQ(r.output.find("render gate: the waiting frame was cancelled"), std::string::npos)
      << "a newer request cancelled the frame in flight\n" << r.output;
  std::size_t waited = 0;
  for (auto at = r.output.find("render gate: a "); at != std::string::npos; at = r.output.find("render gate: a ", at + 1))
    ++waited;
  EXPECT_EQ(waited, 1u) << "one frame waits at the gate while the changes come\n" << r.output;
  return r.output;
}

// The text between `from` and `to` in the first line at or after `at` holding `from`.
std::string field_after(const std::string& log, std::size_t at, const std::string& from, const std::string& to) {
  const auto f = log.find(from, at);
  if (f == std::string::npos) return "";
  return log.substr(f, log.find(to, f) - f);
}
#endif

TEST(Viewer, ADragDoesNotCancelTheFrameInFlight) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string log = expect_continuous_change_keeps_frame(
      prefix, "drag_keeps_frame", "--size 640x360 --camera 1 --no-ui", "x=300 y=200\n\"$input\" move $x $y\n");
  // The drag turned the view at each move (not taken as a click on the panels).
  const std::string second = field_after(log, log.find("held: mouse0 at 320,200 "), " forward ", " right ");
  const std::string third = field_after(log, log.find("held: mouse0 at 330,200 "), " forward ", " right ");
  EXPECT_NE(field_after(log, log.find("held: mouse0 at "), " forward ", " right "), second) << log;
  EXPECT_NE(second, third) << log;
#endif
}

TEST(Viewer, DraggingASliderDoesNotCancelTheFrameInFlight) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  // The FOV slider's centre, as the viewer logs it (--log-input); 1024x600: its section is open.
  const std::string to_start =
      "wait_for \"widget \\\"FOV (deg)\\\" at \" || status=17\n"
      "at=$(grep -F \"widget \\\"FOV (deg)\\\" at \" \"$log\" | tail -n 1 | sed 's/.* at //')\n"
      "x=${at%,*} y=${at#*,}\n"
      "\"$input\" move $x $y\n";
  const std::string log =
      expect_continuous_change_keeps_frame(prefix, "slider_keeps_frame", "--size 1024x600 --camera 1", to_start);
  // Each move changed the field of view: the FOV of the first held-input line at each point.
  const auto first = log.find("held: mouse0 at ");
  ASSERT_NE(first, std::string::npos) << log;
  const int x = std::atoi(log.c_str() + first + std::string("held: mouse0 at ").size());
  double fov[4];
  for (int k = 1; k <= 3; ++k) {
    const auto line = log.find("held: mouse0 at " + std::to_string(x + 10 * k) + ",");
    ASSERT_NE(line, std::string::npos) << "no held-input line at the move " << k << "\n" << log;
    const auto at = log.find(" fov ", line);
    ASSERT_NE(at, std::string::npos) << log;
    fov[k] = std::atof(log.c_str() + at + 5);
  }
  EXPECT_NE(fov[1], fov[2]) << log;
  EXPECT_NE(fov[2], fov[3]) << log;
#endif
}

// "Compare this view" on the CPU path renders two frames of pc_playbot beside the frame loop.
// While they are in flight (held by the render gate), a second C is refused with a notice and
// a click changes an option (frames logged as "(comparing)"); then the gate opens and the
// comparison arrives, stale (the options changed meanwhile), and no UI frame while it ran took
// as long as a render. Before, the window froze for the whole comparison and the second C
// started another.
TEST(Viewer, TheUiAnswersWhileAComparisonRendersOnTheCpu) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_LIVE_PLAYBOT(prefix, dir);
  // GLFW key code of C: 67.
  const std::string steps =
      "wait_for \"first frame shown\" || status=10\n"
      "close_gate\n"
      "[ $status -eq 0 ] && { hold c \" key67 \" || status=11; }\n"
      "[ $status -eq 0 ] && { wait_for \"comparing flash vs baseline at 2048x1200 in the background\" || status=12; }\n"
      "[ $status -eq 0 ] && { hold c \" key67 \" && wait_for \"this request is ignored\" || status=13; }\n"
      "[ $status -eq 0 ] && { click \"tab Rendering\" && click \"Tight box\" && wait_for \"options: flash-no_tight_bbox\" || status=14; }\n"
      "open_gate\n"
      "[ $status -eq 0 ] && { wait_for \"compare flash vs baseline\" || status=15; }\n"
      "[ $status -eq 0 ] && { close_window || status=17; }\n";
  const RunResult r = run_live_viewer(prefix, "ui_while_comparing",
                                      gated_playbot_viewer_args(dir, "1024x600", "ui_while_comparing"),
                                      steps, 16);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 first frame, 11 C, 12 not started in the background, 13 second C not "
                               "refused, 14 click, 15 no comparison, 16 crash, 17 close)\n"
                            << r.output;
  const std::string& log = r.output;
  const auto result = log.find("compare flash vs baseline");
  // Each answer came while the comparison ran: before its result, from frames that said so.
  for (const char* answer : {"still comparing flash vs baseline", "options: flash-no_tight_bbox"})
    EXPECT_LT(log.find(answer), result) << answer << " came after the comparison\n" << log;
  const auto clicked = log.find("held: mouse0 ");
  ASSERT_NE(clicked, std::string::npos) << log;
  EXPECT_NE(log.substr(clicked, log.find('\n', clicked) - clicked).find("(comparing)"), std::string::npos)
      << "the click was not seen while comparing\n" << log;
  EXPECT_NE(log.find("the comparison is stale", result), std::string::npos) << "an option changed meanwhile\n" << log;
  double frames = 0;
  const double worst_ms = worst_ui_frame_ms(log, &frames);
  const double render_ms = shortest_full_render_ms(log);
  std::printf("UI frames while comparing: %.0f, worst %.1f ms; shortest full render %.0f ms\n", frames, worst_ms,
              render_ms);
  EXPECT_GE(frames, 5.0) << log;
  ASSERT_GE(worst_ms, 0.0) << log;
  EXPECT_LT(worst_ms, render_ms) << log;
#endif
}

// Closing the window while a comparison renders on the CPU (held in flight by the render
// gate) cancels it: the viewer exits cleanly (status 0, the cancel logged) instead of
// finishing the comparison first.
TEST(Viewer, ClosingTheWindowCancelsAComparisonInFlight) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_LIVE_PLAYBOT(prefix, dir);
  const std::string steps =
      "wait_for \"first frame shown\" || status=10\n"
      "close_gate\n"
      "[ $status -eq 0 ] && { hold c \" key67 \" || status=11; }\n"
      "[ $status -eq 0 ] && { wait_for \"comparing flash vs baseline\" || status=12; }\n"
      "t0=$(date +%s%N)\n"
      "[ $status -eq 0 ] && { close_window || status=14; }\n"
      "echo \"closed after $(( ($(date +%s%N) - t0) / 1000000 )) ms\"\n"
      "[ $status -eq 0 ] && [ \"$exit_status\" != 0 ] && status=15\n";
  const RunResult r = run_live_viewer(prefix, "close_while_comparing",
                                      gated_playbot_viewer_args(dir, "800x450", "close_while_comparing"),
                                      steps, 13);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 first frame, 11 C, 12 not started, 13 crash, 14 close, 15 exit status)\n"
                            << r.output;
  EXPECT_NE(r.output.find("comparison of flash vs baseline at 2048x1200 cancelled after"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("compare flash vs baseline"), std::string::npos) << "it finished instead\n" << r.output;
  const auto closed = r.output.find("closed after ");
  if (closed != std::string::npos) std::printf("%s\n", r.output.substr(closed, r.output.find('\n', closed) - closed).c_str());
#endif
}

// A path export on the CPU renders its frames beside the frame loop: while one is in flight
// (held by the render gate), a click on a checkbox is answered (in a frame that says so), no
// UI frame takes a second, and the frames are all written once the gate opens. The folder is
// typed into the panel's box, as a user would.
TEST(Viewer, TheUiAnswersWhileThePathExportsOnTheCpu) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_LIVE_PLAYBOT(prefix, dir);
  // The viewer runs in out_dir(): the typed name (letters: the input helper types no "/") is
  // a folder there.
  const std::string folder = out_dir() + "/exportwhilelive";
  std::filesystem::remove_all(folder);
  // 1024x1000: the export row is on screen below the open sections.
  const std::string steps =
      "wait_for \"UI ready\" || status=10\n"
      "[ $status -eq 0 ] && { click \"tab Overlay & output\" && click \"export folder\" && \"$input\" type exportwhilelive || status=11; }\n"
      "close_gate\n"
      "[ $status -eq 0 ] && { click \"Export path\" && wait_for \"path export: 3 frames into\" || status=12; }\n"
      "[ $status -eq 0 ] && { click \"tab Rendering\" && click \"Tight box\" && wait_for \"options: flash-no_tight_bbox\" || status=13; }\n"
      "open_gate\n"
      "[ $status -eq 0 ] && { wait_for \"path export: 3 frames in \" || status=14; }\n"
      "[ $status -eq 0 ] && { close_window || status=16; }\n";
  const RunResult r = run_live_viewer(prefix, "ui_while_exporting",
                                      gated_playbot_viewer_args(dir, "1024x1000", "ui_while_exporting") +
                                          " --export-frames 3",
                                      steps, 15, "PATH=/usr/bin:/bin");
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 first frame, 11 typing the folder, 12 export not started, 13 click, "
                               "14 export not finished, 15 crash, 16 close)\n"
                            << r.output;
  const std::string& log = r.output;
  const auto finished = log.find("path export: 3 frames in ");
  EXPECT_LT(log.find("options: flash-no_tight_bbox"), finished) << "the click was answered after the export\n" << log;
  bool seen_exporting = false;  // a held-button line of a frame that began with an export frame in flight
  for (auto at = log.find("held: mouse0 "); at != std::string::npos; at = log.find("held: mouse0 ", at + 1))
    seen_exporting |= log.substr(at, log.find('\n', at) - at).find("(exporting)") != std::string::npos;
  EXPECT_TRUE(seen_exporting) << "no click was seen while an export frame rendered\n" << log;
  for (int i = 0; i < 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%05d", i);
    EXPECT_TRUE(std::filesystem::exists(folder + name + kExt)) << name;
  }
  // Every UI frame of the run (--log-input logs each that takes 50 ms or more): the 1-megapixel
  // window's swap alone takes up to ~160 ms on a loaded 2-core machine under llvmpipe, while
  // an export frame rendered on the UI thread, as before, held its UI frame for the whole
  // render (seconds here).
  double slowest_ms = 0;
  const std::string slow = "slow UI frame ";
  for (auto at = log.find(slow); at != std::string::npos; at = log.find(slow, at + 1))
    slowest_ms = std::max(slowest_ms, std::atof(log.c_str() + log.find(": ", at) + 2));
  std::printf("slowest UI frame while exporting: %.1f ms\n", slowest_ms);
  EXPECT_LT(slowest_ms, 1000.0) << log;
#endif
}

// The first scene loads beside the window: its progress is on screen within the first second
// of the load (logged, and in a window screenshot taken through Shift+F12 while it loads), and
// the picture follows. The load gate holds the load until the screenshot is saved, however
// fast the machine reads the file.
TEST(Viewer, LoadProgressIsOnScreenInTheFirstSecond) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  if (!flashgs::image_io_writes_png()) GTEST_SKIP() << "Shift+F12 saves PNG, which this build cannot write";
  const std::string dir = flashgs::test::shared_scene_dir("pc_playbot");
  if (dir.empty()) GTEST_SKIP() << "../shared/scenes/pc_playbot is absent: skipped";
  const std::string out = out_dir();
  const std::string shots = out + "/load_progress_shots";
  std::filesystem::remove_all(shots);
  std::filesystem::create_directories(shots);
  // GLFW key codes: left Shift 340, F12 301. Shift+F12 saves the window, a fresh name in `shots`.
  const std::string steps =
      "wait_for \"load progress shown\" || status=10\n"
      "[ $status -eq 0 ] && { press Shift_L \" key340 \" && hold F12 \" key301 \"; \"$input\" up Shift_L; }\n"
      "[ $status -eq 0 ] && { wait_for \"saved window \" || status=11; }\n"
      "[ $status -eq 0 ] && { cp \"$(ls " + shots + "/*.png | head -1)\" loading_window.png; "
      "grep -q \"load of\" \"$log\" && status=12; }\n"
      "open_load_gate\n"
      "[ $status -eq 0 ] && { wait_for \"first frame shown\" || status=13; }\n"
      "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "load_progress",
                                      "\"" + dir + "/point_cloud.ply\" --backend cpu --size 800x450 --log-input --screenshot-dir " +
                                          shots + load_gate_args("load_progress"),
                                      steps, 14);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 no progress, 11 no screenshot, 12 loaded before the screenshot, 13 no "
                               "frame, 14 crash, 15 close)\n"
                            << r.output;
  const double shown_ms = logged_ms(r.output, "load progress shown ");
  std::printf("load progress shown %.0f ms after the load started\n", shown_ms);
  EXPECT_GE(shown_ms, 0.0);
  EXPECT_LT(shown_ms, 1000.0) << r.output;
  // The progress window at the bottom centre, right of the main panel: its bar (ImGui's blue
  // frame, filled or swept in orange) is drawn where the window is otherwise dark.
  const flashgs::Image shot = flashgs::read_image(out + "/loading_window.png");
  ASSERT_EQ(shot.width, 800);
  int bar = 0;
  for (int y = shot.height - 100; y < shot.height - 45; ++y)
    for (int x = 400; x < 620; ++x) {
      const float* p = shot.pixel(x, y);
      const bool orange = p[0] > 0.7f && p[1] > 0.5f && p[2] < 0.2f;
      const bool frame_blue = p[2] > 0.25f && p[2] > p[0] + 0.1f;
      bar += orange || frame_blue;
    }
  std::printf("progress bar pixels: %d\n", bar);
  EXPECT_GT(bar, 1500) << "no progress bar in the window while loading";
#endif
}

// B (baseline) and then the Flash radio button: one rule, so flash comes back with every
// optimisation on (before, B had switched them all off and the radio left them so).
TEST(Viewer, TheBKeyAndTheAlgorithmRadioAgree) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  // GLFW key code: B 66.
  const std::string steps =
      "wait_for \"UI ready\" || status=10\n"
      "[ $status -eq 0 ] && { hold b \" key66 \" && wait_for \"options: baseline\" || status=11; }\n"
      "[ $status -eq 0 ] && { click Flash || status=12; }\n"
      "[ $status -eq 0 ] && { wait_count \"options: \" 3 || status=13; }\n"
      "[ $status -eq 0 ] && { close_window || status=15; }\n";
  const RunResult r = run_live_viewer(prefix, "b_and_radio", "--backend cpu --size 1280x800 --log-input", steps, 14);
  ASSERT_EQ(r.exit_code, 0) << "step " << r.exit_code
                            << " failed (10 start, 11 B, 12 click, 13 radio did nothing, 14 crash, 15 close)\n"
                            << r.output;
  // The option lines in order: flash at start, baseline after B, flash (every switch on) after the radio.
  std::vector<std::string> lines;
  for (std::size_t at = r.output.find("options: "); at != std::string::npos; at = r.output.find("options: ", at + 1))
    lines.push_back(r.output.substr(at, r.output.find('\n', at) - at));
  ASSERT_GE(lines.size(), 3u) << r.output;
  EXPECT_EQ(lines[0], "options: flash");
  EXPECT_EQ(lines[1], "options: baseline");
  EXPECT_EQ(lines[2], "options: flash") << r.output;
#endif
}

// Settings and recent files survive a restart (a private XDG_CONFIG_HOME); a corrupt file is
// one line and the defaults, never a refusal to start.
TEST(Viewer, SettingsAndRecentFilesSurviveARestart) {
#ifndef FLASHGS_X11_INPUT
  GTEST_SKIP() << "built without libXtst: the input helper is absent";
#else
  REQUIRE_DISPLAY(prefix);
  if (prefix == " ") GTEST_SKIP() << "needs xvfb-run (a private display)";
  const std::string config = out_dir() + "/restart_config";
  std::filesystem::remove_all(config);
  const std::string scene = flashgs::demo_scene_path();
  // Run 1: the demo scene by name (a recent file), B (baseline), Tab (orbit); closing saves.
  const std::string first =
      "wait_for \"first frame shown\" || status=10\n"
      "[ $status -eq 0 ] && { hold b \" key66 \" && wait_for \"options: baseline\" || status=11; }\n"
      "[ $status -eq 0 ] && { hold Tab \" key258 \" || status=11; }\n"
      "[ $status -eq 0 ] && { close_window || status=13; }\n";
  const RunResult a = run_live_viewer(prefix, "restart_1", "\"" + scene + "\" --backend cpu --size 800x450 --log-input",
                                      first, 12, "", config);
  ASSERT_EQ(a.exit_code, 0) << "run 1: step " << a.exit_code << "\n" << a.output;
  EXPECT_TRUE(std::filesystem::exists(config + "/flashgs/settings.ini")) << a.output;
  EXPECT_TRUE(std::filesystem::exists(config + "/flashgs/imgui.ini")) << "the panel layout is kept too";
  // Run 2, no scene named: the settings and the recent file come back.
  const std::string second = "wait_for \"UI ready\" || status=10\n"
                             "[ $status -eq 0 ] && { close_window || status=13; }\n";
  const RunResult b = run_live_viewer(prefix, "restart_2", "--size 800x450", second, 12, "", config);
  ASSERT_EQ(b.exit_code, 0) << "run 2: step " << b.exit_code << "\n" << b.output;
  EXPECT_NE(b.output.find("settings from " + config + "/flashgs/settings.ini (1 recent files)"), std::string::npos)
      << b.output;
  EXPECT_NE(b.output.find("options: baseline"), std::string::npos) << b.output;
  EXPECT_NE(b.output.find("frame path: CPU renderer + texture upload (--backend cpu)"), std::string::npos)
      << "the backend choice is kept\n" << b.output;
  // Run 3: a corrupt file: one line naming it, the defaults, the viewer runs.
  if (FILE* f = std::fopen((config + "/flashgs/settings.ini").c_str(), "w")) {
    std::fputs("render_scale = banana\n", f);
    std::fclose(f);
  }
  const RunResult c = run_live_viewer(prefix, "restart_3", "--backend cpu --size 800x450", second, 12, "", config);
  ASSERT_EQ(c.exit_code, 0) << "run 3: step " << c.exit_code << "\n" << c.output;
  EXPECT_NE(c.output.find(config + "/flashgs/settings.ini line 1: \"render_scale = banana\" is not a valid setting: "
                          "ignored, using the defaults"),
            std::string::npos)
      << c.output;
  EXPECT_NE(c.output.find("options: flash"), std::string::npos) << c.output;
#endif
}

}  // namespace
