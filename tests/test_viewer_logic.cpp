// The viewer's logic without a window: navigation, paths, key scripts, settings ranges, memory estimates, scene loads.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <limits>
#include <thread>

#include <sys/stat.h>
#include <unistd.h>

#include "camera_controller.h"
#include "camera_path.h"
#include "compare_mode.h"
#include "folder_listing.h"
#include "path_editor.h"
#include "process_clock.h"
#include "file_dialog.h"
#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "key_script.h"
#include "lod_cache.h"
#include "lod_stream_view.h"
#include "flashgs/lod_build.h"
#include "flashgs/lod_tint.h"
#include "flashgs/frame_memory.h"
#include "heatmap_legend.h"
#include "memory_budget.h"
#include "path_export.h"
#include "scene_loader.h"
#include "scene_lines.h"
#include "scene_state.h"
#include "screenshot_names.h"
#include "split_view.h"
#include "stats_history.h"
#include "test_support.h"
#include "viewer_settings.h"

namespace fv = flashgs::viewer;

namespace {

std::vector<flashgs::Camera> orbit(int count, float up_y = 1.0f) {
  const float target[3] = {0.5f, -0.2f, 1.0f};
  const float up[3] = {0.0f, up_y, 0.0f};
  return flashgs::make_orbit_cameras(target, up, 3.0f, 1.0f, count, 1920, 1080, 60.0f);
}

float max_abs_diff(const glm::mat3& a, const glm::mat3& b) {
  float m = 0;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) m = std::max(m, std::abs(a[c][r] - b[c][r]));
  return m;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();
constexpr float kInff = std::numeric_limits<float>::infinity();

void expect_rotation(const glm::mat3& r, const std::string& what) {
  EXPECT_LT(max_abs_diff(glm::transpose(r) * r, glm::mat3(1.0f)), 1e-4f) << what;
  EXPECT_NEAR(glm::determinant(r), 1.0f, 1e-4f) << what;
}

// A fresh scratch folder under the test output directory.
std::string scratch_dir(const std::string& name) {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/viewer_logic/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// The world point at view-space (x, y, z) of `view`.
glm::vec3 view_point(const flashgs::Camera& view, float x, float y, float z) {
  const float* r = view.rotation;
  return glm::vec3(view.position[0], view.position[1], view.position[2]) + glm::vec3(r[0], r[1], r[2]) * x +
         glm::vec3(r[3], r[4], r[5]) * y + glm::vec3(r[6], r[7], r[8]) * z;
}

}  // namespace

TEST(ViewerNavigation, SnappedCameraRendersExactlyLikeTheSceneCamera) {
  const auto cameras = orbit(8);
  fv::CameraController c;
  c.reset(glm::vec3(0), 2.0f, glm::vec3(0, 1, 0));
  c.snap_to(cameras[3]);
  const flashgs::Camera got = c.render_camera(640, 360, cameras[3].horizontal_fov_degrees());
  const flashgs::Camera want = cameras[3].resized(640, 360);
  EXPECT_EQ(got.fx, want.fx);
  EXPECT_EQ(got.fy, want.fy);
  EXPECT_EQ(got.cx, want.cx);
  EXPECT_EQ(got.cy, want.cy);
  for (int k = 0; k < 9; ++k) EXPECT_EQ(got.rotation[k], want.rotation[k]);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(got.position[k], want.position[k]);
  EXPECT_TRUE(c.on_scene_camera());
  // A different aspect ratio or any motion leaves the exact camera for the free one, same pose.
  fv::ViewerSettings s;
  fv::NavigationInput in;
  in.forward = true;
  c.update(in, 0.1f, s);
  EXPECT_FALSE(c.on_scene_camera());
}

TEST(ViewerNavigation, FlyMotionIsFrameRateIndependent) {
  fv::ViewerSettings s;
  fv::NavigationInput in;
  in.forward = true;
  in.right = true;
  in.up = true;
  fv::CameraController a, b;
  a.reset(glm::vec3(0), 3.0f, glm::vec3(0, -1, 0));
  b.reset(glm::vec3(0), 3.0f, glm::vec3(0, -1, 0));
  a.update(in, 0.5f, s);
  for (int i = 0; i < 50; ++i) b.update(in, 0.01f, s);
  EXPECT_LT(glm::length(a.pose().position - b.pose().position), 1e-4f);
  // 1 extent per second at speed 1: half a second moves half the extent (3.0 / 2).
  fv::CameraController c;
  c.reset(glm::vec3(0), 3.0f, glm::vec3(0, -1, 0));
  const glm::vec3 start = c.pose().position;
  fv::NavigationInput fwd;
  fwd.forward = true;
  c.update(fwd, 0.5f, s);
  EXPECT_NEAR(glm::length(c.pose().position - start), 1.5f, 1e-4f);
  fwd.fast = true;
  c.update(fwd, 0.5f, s);
  EXPECT_NEAR(glm::length(c.pose().position - start), 1.5f + 6.0f, 1e-3f);
}

TEST(ViewerNavigation, OrbitDollyIsFrameRateIndependentAndKeepsThePivot) {
  fv::ViewerSettings s;
  s.mode = fv::NavigationMode::orbit;
  fv::CameraController a, b;
  a.reset(glm::vec3(1, 2, 3), 2.0f, glm::vec3(0, 1, 0));
  b.reset(glm::vec3(1, 2, 3), 2.0f, glm::vec3(0, 1, 0));
  fv::NavigationInput in;
  in.back = true;
  in.look_dx = 0;
  a.update(in, 0.4f, s);
  for (int i = 0; i < 40; ++i) b.update(in, 0.01f, s);
  EXPECT_LT(glm::length(a.pose().position - b.pose().position), 1e-3f);
  // Rotating about the pivot keeps the distance to it.
  const float d0 = glm::length(a.pose().position - a.pivot());
  fv::NavigationInput drag;
  drag.look_dx = 200;
  drag.look_dy = 50;
  a.update(drag, 0.016f, s);
  EXPECT_NEAR(glm::length(a.pose().position - a.pivot()), d0, 1e-3f * d0);
  EXPECT_GT(glm::dot(a.pose().rotation[2], glm::normalize(a.pivot() - a.pose().position)), 0.9999f);
}

TEST(ViewerNavigation, LookNeverPassesOverThePole) {
  fv::ViewerSettings s;
  fv::CameraController c;
  c.reset(glm::vec3(0), 1.0f, glm::vec3(0, -1, 0));
  fv::NavigationInput in;
  in.look_dy = -100;  // keep looking up
  for (int i = 0; i < 200; ++i) c.update(in, 0.016f, s);
  EXPECT_LT(std::abs(glm::dot(c.pose().rotation[2], c.world_up())), 0.9999f);
  // Still a rotation (orthonormal, right-handed OpenCV frame).
  const glm::mat3 r = c.pose().rotation;
  EXPECT_LT(max_abs_diff(glm::transpose(r) * r, glm::mat3(1.0f)), 1e-5f);
  EXPECT_NEAR(glm::determinant(r), 1.0f, 1e-5f);
}

TEST(ViewerNavigation, DraggingRightTurnsRightEvenWhenUpIsFlipped) {
  fv::ViewerSettings s;
  for (bool flip : {false, true}) {
    fv::CameraController c;
    c.reset(glm::vec3(0), 1.0f, glm::vec3(0, 1, 0));
    if (flip) c.flip_up();
    const glm::vec3 right = c.pose().rotation[0];
    fv::NavigationInput in;
    in.look_dx = 50;
    c.update(in, 0.016f, s);
    EXPECT_GT(glm::dot(c.pose().rotation[2], right), 0.05f) << "flip " << flip;
  }
}

TEST(ViewerNavigation, FlipUpRollsHalfATurn) {
  fv::CameraController c;
  c.reset(glm::vec3(0), 1.0f, glm::vec3(0, 1, 0));
  const fv::Pose before = c.pose();
  c.flip_up();
  EXPECT_EQ(c.world_up(), glm::vec3(0, -1, 0));
  EXPECT_LT(glm::length(c.pose().rotation[2] - before.rotation[2]), 1e-6f);
  EXPECT_LT(glm::length(c.pose().rotation[0] + before.rotation[0]), 1e-6f);
  EXPECT_LT(glm::length(c.pose().rotation[1] + before.rotation[1]), 1e-6f);
}

TEST(ViewerCameraPath, PassesThroughEveryCameraAndIsContinuous) {
  const auto cameras = orbit(12);
  fv::CameraPath path(cameras);
  ASSERT_EQ(path.size(), 12u);
  for (std::size_t k = 0; k < cameras.size(); ++k) {
    const fv::Pose want = fv::pose_of(cameras[k]);
    const fv::Pose got = path.pose_at(double(k) / cameras.size());
    EXPECT_LT(glm::length(got.position - want.position), 1e-5f) << k;
    EXPECT_LT(max_abs_diff(got.rotation, want.rotation), 1e-5f) << k;
  }
  // No jumps: 1000 samples over the loop move by less than a few percent of the orbit each.
  float worst = 0;
  for (int i = 0; i < 1000; ++i)
    worst = std::max(worst, glm::length(path.pose_at((i + 1) / 1000.0).position - path.pose_at(i / 1000.0).position));
  EXPECT_LT(worst, 0.05f);
  EXPECT_NEAR(path.fov_at(0.37), 60.0f, 1e-3f);
}

TEST(ViewerKeyScript, ParsesHoldsAndDrags) {
  auto script = fv::KeyScript::parse("W:0.5, d+shift:0.2,MOUSE:10:-5,RESIZE:800:450,WAIT:0.1");
  ASSERT_EQ(script.size(), 5u);
  int forward_frames = 0, right_fast_frames = 0, drags = 0, frames = 0, resizes = 0;
  while (!script.done()) {
    const fv::ScriptFrame step = script.next(1.0f / 60.0f);
    const fv::NavigationInput& in = step.nav;
    resizes += step.resize_width == 800 && step.resize_height == 450;
    forward_frames += in.forward;
    right_fast_frames += in.right && in.fast;
    drags += in.look_dx == 10.0f && in.look_dy == -5.0f;
    ++frames;
    ASSERT_LT(frames, 1000);
  }
  EXPECT_NEAR(forward_frames, 30, 1);
  EXPECT_NEAR(right_fast_frames, 12, 1);
  EXPECT_EQ(drags, 1);
  EXPECT_EQ(resizes, 1);
}

TEST(ViewerKeyScript, RejectsMalformedSteps) {
  for (const char* bad : {"W", "W:abc", "X:0.5", "MOUSE:1", "W:-1", "W:0.5:1", "RESIZE:0:10", "RESIZE:5"}) {
    try {
      fv::KeyScript::parse(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const flashgs::Error& e) {
      EXPECT_NE(std::string(e.what()).find("--keys step"), std::string::npos) << e.what();
    }
  }
}

TEST(ViewerScene, GuessesUpFromTheCameras) {
  EXPECT_EQ(fv::guess_up(orbit(10, 1.0f)), glm::vec3(0, 1, 0));
  EXPECT_EQ(fv::guess_up(orbit(10, -1.0f)), glm::vec3(0, -1, 0));
  EXPECT_EQ(fv::guess_up({}), glm::vec3(0, -1, 0));
}

TEST(ViewerScene, MissingFileIsAnErrorNamingIt) {
  try {
    fv::load_scene("/nonexistent/scene.ply");
    FAIL();
  } catch (const flashgs::Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.ply"), std::string::npos);
  }
}

TEST(ViewerStats, FrameTimeSummary) {
  const fv::FrameTimeSummary s = fv::summarize_frame_times({4.0, 2.0, 3.0, 1.0});
  EXPECT_EQ(s.frames, 4u);
  EXPECT_DOUBLE_EQ(s.mean_ms, 2.5);
  EXPECT_DOUBLE_EQ(s.median_ms, 2.5);  // the mean of the middle two (flashgs::percentile)
  EXPECT_DOUBLE_EQ(s.p95_ms, 3.85);    // 3 + 0.85 (4 - 3): between the two highest ranks
  EXPECT_DOUBLE_EQ(s.min_ms, 1.0);
  EXPECT_DOUBLE_EQ(s.max_ms, 4.0);
  EXPECT_DOUBLE_EQ(s.fps, 400.0);
}

TEST(ViewerCameraPath, AnyTimeGivesAPoseOnThePath) {
  // A different field of view per camera: a key index out of range reads something else.
  auto cameras = orbit(24);
  for (std::size_t k = 0; k < cameras.size(); ++k) cameras[k].fx *= 1.0f + 0.03f * float(k);
  float lo = 1e9f, hi = 0;
  for (const auto& c : cameras) lo = std::min(lo, c.horizontal_fov_degrees()), hi = std::max(hi, c.horizontal_fov_degrees());
  fv::CameraPath path(cameras);
  for (double t : {0.0, -0.0, -1e-17, 1.0, 0.999999999999, -5.3, 7.25, 1e300, -1e300, kNaN, kInf, -kInf,
                   std::numeric_limits<double>::max(), std::numeric_limits<double>::denorm_min()}) {
    const fv::Pose pose = path.pose_at(t);
    EXPECT_TRUE(fv::is_finite(pose)) << "t = " << t;
    expect_rotation(pose.rotation, "t = " + std::to_string(t));
    const float fov = path.fov_at(t);
    EXPECT_GE(fov, lo - 1e-3f) << "t = " << t;
    EXPECT_LE(fov, hi + 1e-3f) << "t = " << t;
  }
  // NaN and the infinities mean "no position on the loop": camera 0.
  EXPECT_LT(glm::length(path.pose_at(kNaN).position - fv::pose_of(cameras[0]).position), 1e-5f);
  EXPECT_NEAR(path.fov_at(kInf), cameras[0].horizontal_fov_degrees(), 1e-4f);
}

TEST(ViewerCameraPath, AdvanceIsTotalInTimeAndDuration) {
  fv::CameraPath path(orbit(24));
  // One second at 2 s per camera over 24 cameras: 1/48 of the loop.
  EXPECT_NEAR(path.advance(0.0, 1.0, 2.0), 1.0 / 48.0, 1e-12);
  EXPECT_NEAR(path.advance(0.99, 1.0, 2.0), 0.99 + 1.0 / 48.0 - 1.0, 1e-12);  // wraps
  for (double seconds : {0.0, -0.0, -1.0, kNaN, kInf, -kInf, 1e-320, 1e300})
    for (double dt : {0.0, 1.0 / 60.0, -1.0, kNaN, kInf, 1e308}) {
      const double t = path.advance(0.25, dt, seconds);
      EXPECT_TRUE(std::isfinite(t) && t >= 0.0 && t < 1.0) << "dt " << dt << " s/camera " << seconds << " -> " << t;
      EXPECT_TRUE(fv::is_finite(path.pose_at(t)));
    }
  // A duration that is no duration leaves the path where it is.
  EXPECT_EQ(path.advance(0.25, 1.0 / 60.0, 0.0), 0.25);
  EXPECT_EQ(path.advance(0.25, 1.0 / 60.0, kNaN), 0.25);
  EXPECT_EQ(path.advance(0.25, kInf, 2.0), 0.25);
  // An empty path is total too.
  fv::CameraPath none({});
  EXPECT_TRUE(fv::is_finite(none.pose_at(kNaN)));
  EXPECT_EQ(none.advance(kNaN, 1.0, 0.0), 0.0);
}

TEST(ViewerNavigation, NonFiniteOrHugeInputNeverGivesANaNPose) {
  fv::ViewerSettings s;
  for (auto mode : {fv::NavigationMode::fly, fv::NavigationMode::orbit}) {
    s.mode = mode;
    fv::CameraController c;
    c.reset(glm::vec3(1, 2, 3), 2.0f, glm::vec3(0, 1, 0));
    const std::string m = mode == fv::NavigationMode::fly ? "fly: " : "orbit: ";
    for (float bad : {kNaNf, kInff, -kInff, 1e30f, -3e38f, std::numeric_limits<float>::max()}) {
      for (int field = 0; field < 5; ++field) {
        fv::NavigationInput in;
        in.forward = true;
        float* values[5] = {&in.look_dx, &in.look_dy, &in.pan_dx, &in.pan_dy, &in.scroll};
        *values[field] = bad;
        c.update(in, 0.016f, s);
        const std::string what = m + "field " + std::to_string(field) + " = " + std::to_string(bad);
        ASSERT_TRUE(fv::is_finite(c.pose())) << what;
        expect_rotation(c.pose().rotation, what);
        EXPECT_TRUE(std::isfinite(s.move_speed) && s.move_speed > 0) << what;
        const flashgs::Camera cam = c.render_camera(64, 36, s.fov_x_degrees);
        for (float v : cam.rotation) ASSERT_TRUE(std::isfinite(v)) << what;
        for (float v : cam.position) ASSERT_TRUE(std::isfinite(v)) << what;
      }
      fv::NavigationInput in;
      in.forward = true;
      in.back = false;
      for (float dt : {kNaNf, kInff, -1.0f, 1e30f}) {
        c.update(in, dt, s);
        ASSERT_TRUE(fv::is_finite(c.pose())) << m << "dt " << dt;
      }
    }
    // A NaN speed or field of view in the settings cannot reach the pose or the camera either.
    s.move_speed = kNaNf;
    fv::NavigationInput in;
    in.forward = true;
    c.update(in, 0.1f, s);
    EXPECT_TRUE(fv::is_finite(c.pose())) << m;
    const flashgs::Camera cam = c.render_camera(64, 36, kNaNf);
    EXPECT_TRUE(std::isfinite(cam.fx) && cam.fx > 0) << m;
    s = fv::ViewerSettings{};
  }
  // A non-finite pose handed in (a broken path) is ignored.
  fv::CameraController c;
  c.reset(glm::vec3(0), 1.0f, glm::vec3(0, 1, 0));
  const glm::vec3 before = c.pose().position;
  fv::Pose bad;
  bad.position = glm::vec3(kNaNf, 0, 0);
  c.set_pose(bad);
  EXPECT_EQ(c.pose().position, before);
}

TEST(ViewerSettings, TypedValuesStayInTheirRanges) {
  const fv::ViewerSettings before;
  fv::ViewerSettings s = before;
  s.path_seconds_per_camera = 0.0f;  // the Ctrl+click "0"
  s.render_scale = 40.0f;            // the typed render scale
  s.fov_x_degrees = kNaNf;
  s.move_speed = -kInff;
  s.heatmap_opacity = 7.0f;
  s.options.tau = kNaNf;
  s.options.background[1] = kInff;
  s.options.background[2] = -0.5f;
  s.options.sh_degree_cap = 9;
  fv::keep_settings_valid(s, before);
  EXPECT_EQ(s.path_seconds_per_camera, fv::kPathSecondsRange.min);
  EXPECT_EQ(s.render_scale, fv::kRenderScaleRange.max);
  EXPECT_EQ(s.fov_x_degrees, before.fov_x_degrees);  // NaN: the value before the edit
  EXPECT_EQ(s.move_speed, before.move_speed);
  EXPECT_EQ(s.heatmap_opacity, fv::kHeatmapOpacityRange.max);
  EXPECT_EQ(s.options.tau, before.options.tau);
  EXPECT_EQ(s.options.background[1], before.options.background[1]);
  EXPECT_EQ(s.options.background[2], 0.0f);
  EXPECT_EQ(s.options.sh_degree_cap, fv::kMaxShDegree);
  // Values in range are left exactly as they are.
  fv::ViewerSettings fine = before;
  fine.render_scale = 0.37f;
  fine.path_seconds_per_camera = 3.5f;
  fv::keep_settings_valid(fine, before);
  EXPECT_EQ(fine.render_scale, 0.37f);
  EXPECT_EQ(fine.path_seconds_per_camera, 3.5f);
}

TEST(ViewerMemory, TooLargeFramesAreRefusedWithTheirFigures) {
  // 32768 x 28800 (the issue's --render-size): 943 Mpixel at 24 bytes with one texture.
  EXPECT_NEAR(double(fv::frame_bytes(32768, 28800, 1)), 32768.0 * 28800 * 20, 32768.0 * 28800 * 0.3);
  const std::string over_limit = fv::frame_size_problem(32768, 28800, 1, 16384, 64000000000ull);
  EXPECT_NE(over_limit.find("32768x28800"), std::string::npos) << over_limit;
  EXPECT_NE(over_limit.find("texture limit of 16384"), std::string::npos) << over_limit;
  EXPECT_NE(over_limit.find(" GB"), std::string::npos) << over_limit;
  // 20000 x 20000 on a machine with 8 GB free: over 8 GB needed, refused by memory alone.
  const std::string over_memory = fv::frame_size_problem(20000, 20000, 1, 0, 8000000000ull);
  EXPECT_GT(fv::frame_bytes(20000, 20000, 1), 8000000000ull);
  EXPECT_NE(over_memory.find("needs about " + flashgs::format_bytes(fv::frame_bytes(20000, 20000, 1))), std::string::npos)
      << over_memory;
  EXPECT_NE(over_memory.find("8.0 GB is available"), std::string::npos) << over_memory;
  // Ordinary frames fit; unknown memory (0) is not held against them.
  EXPECT_EQ(fv::frame_size_problem(3840, 2160, 2, 16384, 8000000000ull), "");
  EXPECT_EQ(fv::frame_size_problem(3840, 2160, 2, 16384, 0), "");
  EXPECT_NE(fv::frame_size_problem(0, 10, 1, 16384, 0), "");
  // Scenes: 200 M demo Gaussians (SH degree 1) do not fit in 20 GB, 30 000 do.
  const std::uint64_t per = fv::scene_bytes_per_gaussian(1);
  EXPECT_EQ(per, 23u * 4u);
  EXPECT_NE(fv::scene_size_problem(fv::scene_bytes(200000000, per), 20000000000ull).find(" GB of memory"),
            std::string::npos);
  EXPECT_EQ(fv::scene_size_problem(fv::scene_bytes(30000, per), 20000000000ull), "");
  EXPECT_GT(flashgs::system_available_memory(), 0u);
}

// Loads with a time limit: a load that blocks fails the test instead of hanging it.
flashgs::Error load_error_within(const std::string& path, std::chrono::seconds limit) {
  auto result = std::make_shared<std::promise<std::string>>();
  std::future<std::string> done = result->get_future();
  std::thread([result, path] {
    try {
      fv::load_scene(path);
      result->set_value("");
    } catch (const std::exception& e) {
      result->set_value(e.what());
    }
  }).detach();
  if (done.wait_for(limit) != std::future_status::ready) return flashgs::Error(path + ": the load blocked");
  return flashgs::Error(done.get());
}

TEST(ViewerScene, AFifoOrDeviceIsRefusedWithoutOpeningIt) {
  const std::string dir = scratch_dir("fifo");
  const std::string fifo = dir + "/scene.ply";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string e = load_error_within(fifo, std::chrono::seconds(20)).what();
  EXPECT_NE(e.find(fifo + ": is a FIFO"), std::string::npos) << e;
  // A folder whose point_cloud.ply is a FIFO, and a device.
  std::filesystem::create_directories(dir + "/folder");
  ASSERT_EQ(mkfifo((dir + "/folder/point_cloud.ply").c_str(), 0600), 0);
  const std::string f = load_error_within(dir + "/folder", std::chrono::seconds(20)).what();
  EXPECT_NE(f.find("point_cloud.ply: is a FIFO"), std::string::npos) << f;
  const std::string d = load_error_within("/dev/zero", std::chrono::seconds(20)).what();
  EXPECT_NE(d.find("/dev/zero: is a device"), std::string::npos) << d;
}

TEST(ViewerScene, AFifoAsCamerasJsonIsNotedAndTheSceneLoads) {
  const std::string dir = scratch_dir("fifo_cameras");
  std::filesystem::copy_file(flashgs::demo_scene_path(), dir + "/point_cloud.ply");
  ASSERT_EQ(mkfifo((dir + "/cameras.json").c_str(), 0600), 0);
  auto result = std::async(std::launch::async, [&] { return fv::load_scene(dir + "/point_cloud.ply"); });
  ASSERT_EQ(result.wait_for(std::chrono::seconds(30)), std::future_status::ready) << "blocked on the FIFO";
  const fv::LoadedScene scene = result.get();
  EXPECT_GT(scene.scene->size(), 0u);
  EXPECT_TRUE(scene.cameras.empty());
  EXPECT_NE(scene.cameras_note.find("cameras.json: is a FIFO"), std::string::npos) << scene.cameras_note;
}

TEST(ViewerSceneLoader, LoadsInTheBackgroundAndReportsErrors) {
  fv::SceneLoader loader;
  ASSERT_TRUE(loader.start(flashgs::demo_scene_path()));
  EXPECT_FALSE(loader.start("/another.ply")) << "a second load while one runs";
  fv::LoadedScene scene;
  std::string error;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!loader.take(&scene, &error) && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  EXPECT_EQ(error, "");
  ASSERT_TRUE(scene.scene);
  EXPECT_EQ(scene.scene->size(), 30000u);
  EXPECT_FALSE(loader.busy());
  ASSERT_TRUE(loader.start("/nonexistent/x.ply"));
  while (!loader.take(&scene, &error) && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  EXPECT_NE(error.find("/nonexistent/x.ply"), std::string::npos) << error;
}

TEST(ViewerSceneLoader, ABlockedLoadIsAbandonedWithoutWaiting) {
  // A load that blocks until released, as open() on a FIFO or a hung mount does.
  auto release = std::make_shared<std::promise<void>>();
  std::shared_future<void> released = release->get_future().share();
  const int running_before = fv::SceneLoader::running();
  {
    fv::SceneLoader loader([released](const std::string& path, flashgs::LoadProgress&) -> fv::LoadedScene {
      released.wait();
      throw flashgs::Error(path + ": released");
    });
    ASSERT_TRUE(loader.start("blocked.ply"));
    EXPECT_TRUE(loader.busy());
    EXPECT_EQ(loader.path(), "blocked.ply");
    loader.abandon();  // the Cancel button
    EXPECT_FALSE(loader.busy());
    ASSERT_TRUE(loader.start("blocked-too.ply")) << "a new load can start after abandoning";
    EXPECT_EQ(fv::SceneLoader::running(), running_before + 2);
  }  // destroyed with a load still blocked: must return at once (this line is reached)
  release->set_value();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (fv::SceneLoader::running() != running_before && std::chrono::steady_clock::now() < deadline)
    std::this_thread::yield();
  EXPECT_EQ(fv::SceneLoader::running(), running_before) << "the abandoned threads did not end";
}

// Waits (up to 30 s) for `done()`, which may have effects: it is not called again once true.
template <typename DONE>
bool within_30s(DONE done) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (;;) {
    if (done()) return true;
    if (std::chrono::steady_clock::now() >= give_up) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// --load-gate: a load waits, before its load function runs, until the gate file appears.
TEST(ViewerSceneLoader, AClosedLoadGateHoldsTheLoadUntilTheFileAppears) {
  const std::string gate = scratch_dir("load_gate") + "/gate";
  auto ran = std::make_shared<std::atomic<bool>>(false);
  fv::SceneLoader loader([ran](const std::string&, flashgs::LoadProgress&) {
    *ran = true;
    return fv::LoadedScene{};
  });
  loader.set_gate(gate);
  ASSERT_TRUE(loader.start("gated.ply"));
  EXPECT_TRUE(within_30s([&] { return loader.waiting_at_gate(); })) << "the load never waited at the closed gate";
  fv::LoadedScene scene;
  std::string error;
  EXPECT_FALSE(loader.take(&scene, &error)) << "the load finished with the gate closed";
  EXPECT_FALSE(*ran);
  std::ofstream(gate).put('\n');
  EXPECT_TRUE(within_30s([&] { return loader.take(&scene, &error); })) << "the load did not finish after the gate opened";
  EXPECT_TRUE(*ran);
  EXPECT_EQ(error, "");
}

// Cancelling a load that waits at the closed gate ends its thread (the gate never opens).
TEST(ViewerSceneLoader, AnAbandonedLoadDoesNotWaitAtTheGate) {
  const std::string gate = scratch_dir("load_gate_abandoned") + "/gate";
  const int running_before = fv::SceneLoader::running();
  {
    fv::SceneLoader loader([](const std::string&, flashgs::LoadProgress&) { return fv::LoadedScene{}; });
    loader.set_gate(gate);
    ASSERT_TRUE(loader.start("gated.ply"));
    EXPECT_TRUE(within_30s([&] { return loader.waiting_at_gate(); }));
    loader.abandon();
  }
  EXPECT_TRUE(within_30s([&] { return fv::SceneLoader::running() == running_before; }))
      << "the abandoned load still waits at the gate";
}

// Navigation as SIBR, SuperSplat and viser users expect it (issue 11).
TEST(ViewerNavigation, FlyPanMovesAcrossTheViewAndKeepsTheDirection) {
  fv::ViewerSettings s;
  fv::CameraController c;
  c.reset(glm::vec3(0), 2.0f, glm::vec3(0, -1, 0));
  const fv::Pose before = c.pose();
  fv::NavigationInput in;
  in.pan_dx = 100;  // dragging right moves the scene right: the camera goes left
  in.pan_dy = 50;   // dragging down moves the scene down: the camera goes up (its -y)
  ASSERT_TRUE(c.update(in, 0.016f, s));
  const glm::vec3 moved = c.pose().position - before.position;
  EXPECT_LT(glm::dot(moved, before.rotation[0]), -1e-3f);
  EXPECT_LT(glm::dot(moved, before.rotation[1]), -1e-3f);
  EXPECT_NEAR(glm::dot(moved, before.rotation[2]), 0.0f, 1e-5f);
  EXPECT_LT(max_abs_diff(c.pose().rotation, before.rotation), 1e-6f);
}

TEST(ViewerNavigation, TheWheelDolliesInFlyModeAndCtrlWheelSetsTheSpeed) {
  fv::ViewerSettings s;
  fv::CameraController c;
  c.reset(glm::vec3(0), 2.0f, glm::vec3(0, -1, 0));
  const fv::Pose before = c.pose();
  const float distance = glm::length(before.position);  // the default view looks at the centre
  fv::NavigationInput wheel;
  wheel.scroll = 2;
  ASSERT_TRUE(c.update(wheel, 0.016f, s));
  const glm::vec3 moved = c.pose().position - before.position;
  EXPECT_GT(glm::dot(moved, before.rotation[2]), 0.0f) << "the wheel forward must move toward the view";
  EXPECT_NEAR(glm::length(glm::cross(moved, before.rotation[2])), 0.0f, 1e-4f);
  EXPECT_LT(glm::length(c.pose().position), distance);
  EXPECT_EQ(s.move_speed, 1.0f) << "the wheel alone must not change the speed";
  fv::NavigationInput faster;
  faster.speed_steps = 2;  // two + presses, or Ctrl+wheel two steps
  c.update(faster, 0.016f, s);
  EXPECT_NEAR(s.move_speed, 1.5625f, 1e-5f);
  faster.speed_steps = -1e9f;  // clamped, never zero or negative
  c.update(faster, 0.016f, s);
  EXPECT_GE(s.move_speed, fv::kMoveSpeedRange.min);
}

TEST(ViewerNavigation, FrameSceneLooksAtTheWholeScene) {
  fv::ViewerSettings s;
  fv::CameraController c;
  const glm::vec3 centre(1, 2, 3);
  c.reset(centre, 2.0f, glm::vec3(0, 1, 0));
  fv::NavigationInput away;
  away.back = true;
  away.right = true;
  c.update(away, 3.0f, s);
  c.frame_scene(60.0f, 16.0f / 9.0f);
  const fv::Pose p = c.pose();
  const glm::vec3 to_centre = centre - p.position;
  // On the view axis, the pivot at the centre, far enough for a sphere of the extent to fit
  // the narrower (vertical) field of view.
  EXPECT_GT(glm::dot(glm::normalize(to_centre), p.rotation[2]), 0.9999f);
  EXPECT_LT(glm::length(c.pivot() - centre), 1e-4f);
  const float half_vertical = std::atan(std::tan(float(M_PI) / 6.0f) * 9.0f / 16.0f);
  EXPECT_NEAR(std::asin(2.0f / glm::length(to_centre)), half_vertical, 1e-3f);  // fits, and no farther
}

TEST(ViewerNavigation, ObjectScenesOrbitAndRoomsFly) {
  // Cameras on a ring of radius 3 around an object of extent 1: an object.
  EXPECT_TRUE(fv::is_object_sized(glm::vec3(0.5f, -0.2f, 1.0f), 1.0f, orbit(12)));
  // The same cameras inside a room of extent 10: fly.
  EXPECT_FALSE(fv::is_object_sized(glm::vec3(0.5f, -0.2f, 1.0f), 10.0f, orbit(12)));
  EXPECT_TRUE(fv::is_object_sized(glm::vec3(0), 1.0f, {}));
  // Cameras within the object's extent (0.8 of it) that look at it: still an object...
  const float target[3] = {0.5f, -0.2f, 1.0f}, up[3] = {0.0f, 1.0f, 0.0f};
  const auto close = flashgs::make_orbit_cameras(target, up, 3.0f, 1.0f, 12, 1920, 1080, 60.0f);
  EXPECT_TRUE(fv::is_object_sized(glm::vec3(0.5f, -0.2f, 1.0f), 3.0f / 0.8f, close));
  // ...but the same cameras turned to look outward stand inside a space.
  std::vector<flashgs::Camera> outward = close;
  for (flashgs::Camera& c : outward)
    for (int k = 0; k < 3; ++k) c.rotation[k] = -c.rotation[k], c.rotation[6 + k] = -c.rotation[6 + k];
  EXPECT_FALSE(fv::is_object_sized(glm::vec3(0.5f, -0.2f, 1.0f), 3.0f / 0.8f, outward));
}

// Every shared scene is a scan of an object seen from around: it opens in orbit navigation.
TEST(ViewerNavigation, TheSharedObjectScansOpenInOrbit) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : flashgs::test::shared_scene_names()) {
    const fv::LoadedScene scene = fv::load_scene(flashgs::test::shared_scene_dir(name) + "/point_cloud.ply");
    EXPECT_TRUE(fv::is_object_sized(scene.centre, scene.extent, scene.cameras)) << name;
  }
}

TEST(ViewerHeatmap, LegendTicksAreRoundValuesAtTheirPlaceOnTheScale) {
  const auto ticks = fv::legend_ticks(1771, true);
  std::vector<std::uint64_t> values;
  for (const auto& t : ticks) values.push_back(t.value);
  EXPECT_EQ(values, (std::vector<std::uint64_t>{0, 1, 10, 100, 1771})) << "1000 is too close to 1771 on a log scale";
  for (const auto& t : ticks) EXPECT_NEAR(t.position, std::log1p(double(t.value)) / std::log1p(1771.0), 1e-6);
  const auto linear = fv::legend_ticks(1771, false);
  std::vector<std::uint64_t> lin;
  for (const auto& t : linear) lin.push_back(t.value);
  EXPECT_EQ(lin, (std::vector<std::uint64_t>{0, 500, 1000, 1500, 1771}));
  EXPECT_NEAR(linear[1].position, 500.0f / 1771.0f, 1e-6f);
  EXPECT_EQ(fv::legend_ticks(0, true).back().value, 1u);  // an empty frame still has a scale
  // 1000 sat 27 points left of 2087 on the 280-point bar: their labels ran together ("10002087").
  std::vector<std::string> labels;
  for (const auto& t : fv::legend_ticks(2087, true)) labels.push_back(t.label);
  EXPECT_EQ(labels, (std::vector<std::string>{"0", "1", "10", "100", "2087"}));
  EXPECT_EQ(fv::legend_ticks(123456, true).back().label, "123.5k");
  EXPECT_EQ(fv::legend_caption(16, true, false), "pairs per 16x16 tile, log scale");
  EXPECT_EQ(fv::legend_caption(16, false, true), "pairs per 16x16 tile, linear scale (max locked)");
}

// For any maximum, on either scale, neighbouring labels (centred on their ticks, in the UI's
// monospace font) keep at least a character between them, and the maximum is always the last.
TEST(ViewerHeatmap, LegendLabelsNeverRunTogether) {
  const float char_fraction = fv::kLegendCharPoints / fv::kLegendBarPoints;
  for (bool log_scale : {true, false})
    for (std::uint64_t max = 1; max < 100000000; max = max * 3 / 2 + 1) {
      const auto ticks = fv::legend_ticks(max, log_scale);
      ASSERT_FALSE(ticks.empty());
      EXPECT_EQ(ticks.back().value, max);
      EXPECT_EQ(ticks.front().value, 0u) << max;
      for (std::size_t k = 1; k < ticks.size(); ++k) {
        const float gap = (ticks[k].position - ticks[k - 1].position) / char_fraction;
        const float needed = 0.5f * float(ticks[k].label.size() + ticks[k - 1].label.size()) + 1.0f;
        EXPECT_GE(gap, needed) << (log_scale ? "log" : "linear") << " max " << max << ": " << ticks[k - 1].label
                               << " and " << ticks[k].label << " run together";
      }
    }
}

TEST(ViewerHeatmap, TheLockKeepsTheMaximumAcrossConfigurations) {
  fv::HeatScale scale;
  EXPECT_EQ(scale.update(1771, false), 1771u);
  EXPECT_EQ(scale.update(900, false), 900u);
  // Ticked while 900 is shown, the next frame (another configuration's) at 1771: the lock
  // keeps the maximum the user saw.
  EXPECT_EQ(scale.update(1771, true), 900u);
  EXPECT_EQ(scale.update(600, true), 900u);
  EXPECT_EQ(scale.update(2500, true), 900u);
  EXPECT_EQ(scale.update(600, false), 600u);   // unlocked: follows the frame again
  fv::HeatScale locked_from_start;             // locked before any frame: the first one's
  EXPECT_EQ(locked_from_start.update(1234, true), 1234u);
  EXPECT_EQ(locked_from_start.update(99, true), 1234u);
}

TEST(ViewerHeatmap, TheRampIsViridisLikeAndMonotoneInLightness) {
  // Dark purple to yellow through blue-green; luminance rises throughout (readable in grey
  // and with red-green colour-blindness).
  const auto low = fv::heat_colour(0.0f), mid = fv::heat_colour(0.5f), high = fv::heat_colour(1.0f);
  EXPECT_GT(low[2], low[1]);
  EXPECT_GT(mid[1], mid[0]);
  EXPECT_GT(high[0], 0.9f);
  EXPECT_LT(high[2], 0.2f);
  float last = -1.0f;
  for (int i = 0; i <= 64; ++i) {
    const auto c = fv::heat_colour(i / 64.0f);
    const float luma = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
    EXPECT_GT(luma, last) << "at " << i;
    last = luma;
  }
  EXPECT_EQ(fv::heat_colour(std::nanf("")), fv::heat_colour(0.0f));
}

TEST(ViewerCompare, DifferenceImageIsMagnifiedAndTheFactorReported) {
  flashgs::Image a, b;
  a.resize(4, 2);
  b.resize(4, 2);
  b.pixel(1, 1)[0] = 3.0f / 255.0f;  // one value off by 3/255
  float factor = 0;
  const flashgs::Image d = fv::difference_image(a, b, &factor);
  EXPECT_EQ(factor, 64.0f);  // 3/255 * 64 = 0.75: at least half of white
  EXPECT_NEAR(d.pixel(1, 1)[0], 3.0f / 255.0f * 64.0f, 1e-6f);
  EXPECT_EQ(d.pixel(0, 0)[0], 0.0f);
  const flashgs::Image same = fv::difference_image(a, a, &factor);
  EXPECT_EQ(factor, 1.0f);
  for (float v : same.rgb) EXPECT_EQ(v, 0.0f);
}

TEST(ViewerCompare, TheDividerIsGrabbedNearItAndFollowsTheDrag) {
  fv::SplitDivider d;
  EXPECT_FALSE(d.grabs(300, 1000));
  d.press(300, 1000);
  EXPECT_FALSE(d.dragging());
  d.press(505, 1000);
  ASSERT_TRUE(d.dragging());
  d.drag_to(250, 1000);
  EXPECT_FLOAT_EQ(d.fraction(), 0.25f);
  d.drag_to(-50, 1000);
  EXPECT_FLOAT_EQ(d.fraction(), 0.02f);
  d.release();
  d.drag_to(900, 1000);
  EXPECT_FLOAT_EQ(d.fraction(), 0.02f);
}

TEST(ViewerCompare, AnyTwoConfigurationsAndTheSameOneTwiceIsRefused) {
  flashgs::RenderOptions current;
  current.tau = 0.01f;
  current.sh_degree_cap = 1;
  ASSERT_EQ(fv::compare_choice_name(fv::kCompareBaseline), "baseline");
  ASSERT_EQ(fv::compare_choice_name(2), "flash");
  const int no_tight = fv::compare_choice_from_name("flash-no_tight_bbox");
  ASSERT_GT(no_tight, 2);
  const flashgs::RenderOptions o = fv::compare_choice_options(no_tight, current);
  EXPECT_FALSE(o.tight_bbox);
  EXPECT_TRUE(o.opacity_aware_radius);
  EXPECT_EQ(o.tau, 0.01f);  // colour inputs from the current settings
  EXPECT_EQ(o.sh_degree_cap, 1);
  EXPECT_EQ(fv::compare_choice_from_name("nonsense"), -1);
  // Baseline vs baseline (the current settings being the baseline): refused with the reason.
  const flashgs::RenderOptions base = fv::compare_choice_options(fv::kCompareBaseline, current);
  const std::string problem = fv::same_configuration_problem(base, fv::compare_choice_options(fv::kCompareCurrent, base));
  EXPECT_NE(problem.find("both sides are baseline"), std::string::npos) << problem;
  EXPECT_EQ(fv::same_configuration_problem(base, o), "");
}

// The panel lists configurations by name, not by label() token, and only those the backend
// draws differently from flash: a GPU-only switch turned off renders flash on the CPU.
TEST(ViewerCompare, ChoicesAreNamedForPeopleAndGpuOnlyOnesAreNotOfferedOnTheCpu) {
  const int no_tight = fv::compare_choice_from_name("flash-no_tight_bbox");
  const int no_warp = fv::compare_choice_from_name("flash-no_warp_emit");
  ASSERT_GT(no_warp, 2);
  EXPECT_EQ(fv::compare_choice_title(no_tight), "flash without Tight box");
  EXPECT_EQ(fv::compare_choice_title(fv::kCompareBaseline), "baseline");
  EXPECT_TRUE(fv::compare_choice_offered(no_tight, flashgs::Backend::cpu));
  EXPECT_FALSE(fv::compare_choice_offered(no_warp, flashgs::Backend::cpu));
  EXPECT_TRUE(fv::compare_choice_offered(no_warp, flashgs::Backend::cuda));
  const flashgs::RenderOptions current;
  const std::string problem = fv::compare_sides_problem(fv::kCompareBaseline, no_warp, current, flashgs::Backend::cpu);
  EXPECT_NE(problem.find("flash without Warp emit renders as flash here (the CPU backend has no warps)"),
            std::string::npos) << problem;
  EXPECT_EQ(fv::compare_sides_problem(fv::kCompareBaseline, no_warp, current, flashgs::Backend::cuda), "");
}

TEST(ViewerScreenshots, NamesAreTimestampedAndNeverReused) {
  const std::string dir = scratch_dir("viewer_shots");
  const std::time_t t = 1764612345;
  const std::string first = fv::timestamped_screenshot_path(dir, "", t);
  EXPECT_NE(first.find(dir + "/flashgs_20"), std::string::npos) << first;
  EXPECT_EQ(first.substr(first.size() - 4), ".png");
  { std::ofstream(first) << "x"; }
  const std::string second = fv::timestamped_screenshot_path(dir, "", t);  // the same second
  EXPECT_NE(second, first);
  { std::ofstream(second) << "x"; }
  const std::string third = fv::timestamped_screenshot_path(dir, "", t);
  EXPECT_NE(third, first);
  EXPECT_NE(third, second);
  EXPECT_NE(fv::timestamped_screenshot_path(dir, "window", t).find("flashgs_window_"), std::string::npos);
}

TEST(ViewerScreenshots, TheDefaultFolderIsTheXdgPicturesFolder) {
  const std::string dir = scratch_dir("viewer_pictures");
  setenv("XDG_PICTURES_DIR", dir.c_str(), 1);
  EXPECT_EQ(fv::default_screenshot_folder(), dir);
  setenv("XDG_PICTURES_DIR", (dir + "/absent").c_str(), 1);  // not a folder: the next choice
  EXPECT_NE(fv::default_screenshot_folder(), dir + "/absent");
  unsetenv("XDG_PICTURES_DIR");
}

// Without XDG_PICTURES_DIR, user-dirs.dirs names the folder; a FIFO in its place is passed
// over without blocking (it used to hang the viewer's start).
TEST(ViewerScreenshots, UserDirsNamesTheFolderAndAFifoThereIsPassedOver) {
  const std::string dir = scratch_dir("viewer_user_dirs");
  const std::string config = dir + "/config", home = dir + "/home";
  std::filesystem::create_directories(config);
  std::filesystem::create_directories(home + "/Shots");
  const char* saved_home = std::getenv("HOME");
  const std::string restore_home = saved_home ? saved_home : "";
  unsetenv("XDG_PICTURES_DIR");
  setenv("XDG_CONFIG_HOME", config.c_str(), 1);
  setenv("HOME", home.c_str(), 1);
  std::ofstream(config + "/user-dirs.dirs") << "XDG_DESKTOP_DIR=\"$HOME/Desktop\"\nXDG_PICTURES_DIR=\"$HOME/Shots\"\n";
  EXPECT_EQ(fv::default_screenshot_folder(), home + "/Shots");
  std::filesystem::remove(config + "/user-dirs.dirs");
  ASSERT_EQ(mkfifo((config + "/user-dirs.dirs").c_str(), 0600), 0);
  EXPECT_EQ(fv::default_screenshot_folder(), ".");  // no Pictures folder in this home either
  unsetenv("XDG_CONFIG_HOME");
  if (saved_home) setenv("HOME", restore_home.c_str(), 1);
}

TEST(ViewerGuides, FrustumsProjectWhereTheCamerasAreAndAClickPicksOne) {
  const auto cameras = orbit(8);
  fv::CameraController c;
  c.reset(glm::vec3(0.5f, -0.2f, 1.0f), 1.0f, glm::vec3(0, 1, 0));
  fv::NavigationInput back;
  back.back = true;
  fv::ViewerSettings s;
  c.update(back, 6.0f, s);  // far behind: every camera in view
  const flashgs::Camera view = c.render_camera(640, 360, 60.0f);
  const auto segments = fv::project_segments(fv::camera_frustums(cameras, 0.1f, 2), view, 1e-3f);
  EXPECT_EQ(segments.size(), cameras.size() * 10);
  // The first segment of camera k starts at its centre: clicking there picks k.
  for (int k : {0, 3, 5}) {
    const fv::ScreenSegment& s = segments[std::size_t(k) * 10];
    EXPECT_EQ(fv::pick_camera(cameras, view, s.x0 + 2.0f, s.y0 - 2.0f, 14.0f, 0.1f), k);
  }
  EXPECT_EQ(fv::pick_camera(cameras, view, -500.0f, -500.0f, 14.0f, 0.1f), -1);
  // Inside a frustum's body, far from its centre and its edges, picks it too.
  const fv::ScreenSegment* f = &segments[3 * 10];
  const float cx = 0.25f * (f[0].x1 + f[2].x1 + f[4].x1 + f[6].x1), cy = 0.25f * (f[0].y1 + f[2].y1 + f[4].y1 + f[6].y1);
  EXPECT_EQ(fv::pick_camera(cameras, view, cx, cy, 1.0f, 0.1f), 3);
  // Segments crossing behind the view are cut at the near plane, never mirrored.
  const fv::WorldSegment through{view_point(view, 0, 0, 1), view_point(view, 0, 0, -1), {1, 1, 1, 1}};
  const auto cut = fv::project_segments({through}, view, 0.01f);
  ASSERT_EQ(cut.size(), 1u);
  EXPECT_NEAR(cut[0].x0, view.cx, 1e-2f);
  const auto grid = fv::grid_and_axes(glm::vec3(0.5f, -0.2f, 1.0f), 1.0f, glm::vec3(0, 1, 0));
  EXPECT_EQ(grid.size(), 2u * 21u + 3u);
  for (const auto& g : grid) {
    if (g.rgba[3] < 1.0f) {
      EXPECT_NEAR(g.a.y, 0.0f, 1e-5f) << "grid lines lie in the ground plane";
    }
  }
}

// The centres view: a dot at each Gaussian's projected centre, in its base colour; those
// behind the view or outside the image are left out, and a cap thins a large scene evenly; a
// streamed cut's parts give the dots of the scene they make up.
TEST(ViewerGuides, CentresAreDotsWhereTheGaussiansProject) {
  auto shared = std::make_shared<flashgs::Scene>();
  flashgs::Scene& scene = *shared;
  const float positions[] = {0, 0, 5, 1, 0, 5, 0, 0, -5, 100, 0, 5};  // the third behind, the fourth off-image
  scene.positions.assign(std::begin(positions), std::end(positions));
  scene.sh_dc = {1.0f, 0, -1.0f, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  scene.opacities = {1, 1, 1, 1};
  const float eye[3] = {0, 0, 0}, target[3] = {0, 0, 1}, up[3] = {0, -1, 0};
  const flashgs::Camera view = flashgs::look_at_camera(eye, target, up, 200, 100, 90.0f);
  const std::vector<flashgs::ScenePart> whole = {{0, shared, 0, 4}};
  const auto dots = fv::centre_marks(whole, view, 100);
  ASSERT_EQ(dots.size(), 2u);
  EXPECT_NEAR(0.5f * (dots[0].x0 + dots[0].x1), view.cx, 1e-3f);
  EXPECT_NEAR(dots[0].y0, view.cy, 1e-3f);
  EXPECT_NEAR(dots[0].rgba[0], 0.5f + 0.2820948f, 1e-5f);
  EXPECT_NEAR(dots[0].rgba[2], 0.5f - 0.2820948f, 1e-5f);
  EXPECT_NEAR(std::abs(0.5f * (dots[1].x0 + dots[1].x1) - view.cx), 0.2f * view.fx, 1e-2f);
  EXPECT_EQ(fv::centre_marks(whole, view, 2).size(), 1u) << "every second Gaussian: the first and the third";
  // The same Gaussians as parts, out of the source's order: the second, then the fourth, third and first.
  const std::vector<flashgs::ScenePart> parts = {{7, shared, 1, 1}, {8, shared, 3, 1}, {9, shared, 2, 1}, {10, shared, 0, 1}};
  const auto part_dots = fv::centre_marks(parts, view, 100);
  ASSERT_EQ(part_dots.size(), 2u);
  EXPECT_EQ(part_dots[0].x0, dots[1].x0) << "the second Gaussian comes first";
  EXPECT_EQ(part_dots[1].x0, dots[0].x0);
  // Every second of the four drawn: the first part's and the third part's (behind the view).
  const auto thinned = fv::centre_marks(parts, view, 2);
  ASSERT_EQ(thinned.size(), 1u);
  EXPECT_EQ(thinned[0].x0, dots[1].x0);
}

// After N or a snap in a window of another shape than the camera's images (16:10 vs 16:9),
// the view is on the camera's pose and FOV: the panel says so (it said "free view").
TEST(ViewerGuides, TheViewPanelNamesTheCameraWhoseShapeDiffersFromTheWindow) {
  const auto cameras = orbit(4);
  fv::CameraController c;
  EXPECT_EQ(c.view_description(-1, 1280, 800, 60.0f), "free view");
  c.snap_to(cameras[2]);
  const float fov = cameras[2].horizontal_fov_degrees();
  EXPECT_EQ(c.view_description(2, 1280, 720, fov), "on camera 2 (exact)");
  EXPECT_EQ(c.view_description(2, 1280, 800, fov), "on camera 2: pose, window 1.60:1 vs 1.78:1");
  EXPECT_EQ(c.view_description(2, 0, 0, fov), "on camera 2");
  fv::NavigationInput forward;
  forward.forward = true;
  fv::ViewerSettings s;
  c.update(forward, 0.5f, s);
  EXPECT_EQ(c.view_description(2, 1280, 800, fov), "free view (last camera 2)");
}

// Keys from the view: added 2 s apart, replaced, retimed (kept in order, the selection
// following), deleted; saved and loaded back; the preview plays from the first key to the last.
TEST(ViewerKeyframes, KeysAreAddedReplacedRetimedDeletedAndSaved) {
  const auto cameras = orbit(4);
  fv::PathEditor e;
  e.add(cameras[0]);
  e.add(cameras[1]);
  e.add(cameras[2]);
  ASSERT_EQ(e.path().keys.size(), 3u);
  EXPECT_EQ(e.selected(), 2);
  EXPECT_DOUBLE_EQ(e.path().keys[2].time_s, 4.0);
  EXPECT_FLOAT_EQ(e.path().keys[1].position[0], cameras[1].position[0]);
  e.select(1);
  e.replace_selected(cameras[3]);
  EXPECT_FLOAT_EQ(e.path().keys[1].position[0], cameras[3].position[0]);
  EXPECT_DOUBLE_EQ(e.path().keys[1].time_s, 2.0) << "a replaced key keeps its time";
  e.set_time(1, 5.0);  // after key 2 now
  EXPECT_EQ(e.selected(), 2);
  EXPECT_FLOAT_EQ(e.path().keys[2].position[0], cameras[3].position[0]);
  EXPECT_DOUBLE_EQ(e.path().duration_s(), 5.0);
  e.set_duration(10.0);
  EXPECT_DOUBLE_EQ(e.path().keys[1].time_s, 8.0);
  e.delete_selected();
  ASSERT_EQ(e.path().keys.size(), 2u);
  EXPECT_EQ(e.selected(), 1);
  const std::string dir = scratch_dir("keyframes");
  EXPECT_EQ(e.save(dir + "/p.json"), "");
  fv::PathEditor f;
  EXPECT_EQ(f.load(dir + "/p.json"), "");
  ASSERT_EQ(f.path().keys.size(), 2u);
  EXPECT_DOUBLE_EQ(f.path().keys[1].time_s, 8.0);
  EXPECT_NE(f.load(dir + "/absent.json").find("camera path not loaded: " + dir + "/absent.json"), std::string::npos);
  EXPECT_EQ(f.path().keys.size(), 2u) << "a failed load keeps the path";
  EXPECT_NE(fv::PathEditor().save(dir + "/empty.json").find("no keyframes"), std::string::npos);
  // The preview: from key 0 to the last, then it stops on the last key.
  f.start_preview();
  ASSERT_TRUE(f.previewing());
  flashgs::Camera c = f.preview_step(0.0, 160, 90);
  EXPECT_NEAR(c.position[0], cameras[0].position[0], 1e-5f);
  for (int i = 0; i < 100 && f.previewing(); ++i) c = f.preview_step(0.1, 160, 90);
  EXPECT_FALSE(f.previewing());
  EXPECT_NEAR(c.position[0], cameras[2].position[0], 1e-5f);
}

// The load's bar covers reading and decoding: all bytes read with a tenth of the Gaussians
// decoded is not a full bar (it was: the bytes alone filled it).
TEST(ViewerLoad, TheProgressBarCoversReadingAndDecoding) {
  EXPECT_FLOAT_EQ(fv::load_fraction(574, 574, 35, 350), 0.55f);
  EXPECT_FLOAT_EQ(fv::load_fraction(287, 574, 0, 350), 0.25f);
  EXPECT_FLOAT_EQ(fv::load_fraction(574, 574, 350, 350), 1.0f);
  EXPECT_FLOAT_EQ(fv::load_fraction(100, 400, 0, 0), 0.25f);  // a reader that reports bytes only
  EXPECT_FLOAT_EQ(fv::load_fraction(0, 0, 30, 60), 0.5f);     // ...or Gaussians only
  EXPECT_FLOAT_EQ(fv::load_fraction(0, 0, 0, 0), -1.0f);
}

// Start-up is measured from exec: this test process started before the test ran, and not an
// hour ago (a wrong field of /proc/self/stat reads as years or as a negative age).
TEST(ViewerStartup, TheProcessAgeCountsFromExec) {
  const double age = fv::ms_since_process_start();
  EXPECT_GE(age, 0.0);
  EXPECT_LT(age, 3.6e6);
}

// The in-app browser lists every format the viewer reads (it listed *.ply only) and the
// folders that are a scene, with a training output's iterations; other files are left out.
TEST(ViewerFiles, TheBrowserListsEveryFormatAndSceneFoldersSorted) {
  namespace fs = std::filesystem;
  const std::string dir = scratch_dir("browser_listing");
  std::ofstream(dir + "/b.ply") << std::string(300, 'x');
  std::ofstream(dir + "/a.spz") << std::string(100, 'x');
  std::ofstream(dir + "/c.SPLAT") << std::string(200, 'x');
  std::ofstream(dir + "/notes.txt") << "x";
  std::ofstream(dir + "/.hidden.ply") << "x";
  fs::create_directories(dir + "/sog");
  std::ofstream(dir + "/sog/meta.json") << "{}";
  fs::create_directories(dir + "/plain");
  for (const char* it : {"iteration_7000", "iteration_30000", "iteration_x"}) {
    fs::create_directories(dir + "/train/point_cloud/" + it);
    std::ofstream(dir + "/train/point_cloud/" + it + "/point_cloud.ply") << "x";
  }
  std::string error;
  const auto by_name = fv::list_folder(dir, fv::FolderSort::name, &error);
  EXPECT_EQ(error, "");
  std::vector<std::string> names;
  for (const auto& e : by_name) names.push_back(e.name);
  EXPECT_EQ(names, (std::vector<std::string>{"plain", "sog", "train", "a.spz", "b.ply", "c.SPLAT"}));
  EXPECT_EQ(by_name[0].kind, fv::FolderEntry::Kind::folder);
  EXPECT_EQ(by_name[1].kind, fv::FolderEntry::Kind::scene_folder);
  ASSERT_EQ(by_name[2].iterations.size(), 2u);
  EXPECT_EQ(by_name[2].iterations[0].first, 30000);
  EXPECT_EQ(by_name[2].iterations[1].second, dir + "/train/point_cloud/iteration_7000/point_cloud.ply");
  EXPECT_EQ(by_name[4].bytes, 300u);
  const auto by_size = fv::list_folder(dir, fv::FolderSort::size, &error);
  EXPECT_EQ(by_size[3].name, "b.ply");
  EXPECT_EQ(by_size[5].name, "a.spz");
  EXPECT_TRUE(fv::is_scene_file_name("lod-meta.json"));
  EXPECT_FALSE(fv::is_scene_file_name("cameras.json"));
  EXPECT_TRUE(fv::list_folder(dir + "/absent", fv::FolderSort::name, &error).empty());
  EXPECT_NE(error.find(dir + "/absent: "), std::string::npos) << error;
}

TEST(ViewerFiles, TheDesktopDialogsAnswerIsTheChosenPath) {
  const std::string dir = scratch_dir("viewer_dialog");
  const std::string fake = dir + "/zenity";
  { std::ofstream(fake) << "#!/bin/sh\necho /some/where/scene.ply\n"; }
  chmod(fake.c_str(), 0755);
  const std::string old_path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", (dir + ":" + old_path).c_str(), 1);
  EXPECT_EQ(fv::find_on_path("zenity"), fake);
  fv::FileDialog dialog;
  ASSERT_TRUE(dialog.open_native(dir));
  EXPECT_EQ(dialog.tool(), "zenity");
  std::string chosen;
  for (int i = 0; i < 2000 && chosen.empty(); ++i) {  // its thread answers once the child exits
    chosen = dialog.take_choice();
    if (chosen.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(chosen, "/some/where/scene.ply");
  setenv("PATH", "/nonexistent", 1);
  EXPECT_EQ(fv::find_on_path("zenity"), "");
  EXPECT_FALSE(fv::FileDialog().open_native(dir)) << "no dialog on PATH: the in-app browser";
  setenv("PATH", old_path.c_str(), 1);
}

TEST(ViewerFiles, PathExportNumbersFramesAndFindsFfmpegAtRunTime) {
  const std::string dir = scratch_dir("viewer_export");
  fv::PathExport e;
  EXPECT_NE(e.start(dir + "/frames", 0), "");
  ASSERT_EQ(e.start(dir + "/frames", 3), "");
  EXPECT_TRUE(std::filesystem::is_directory(dir + "/frames"));
  std::vector<std::string> files;
  while (e.active()) {
    files.push_back(e.next_file());
    EXPECT_NEAR(e.next_t(), double(files.size() - 1) / 3.0, 1e-12);
    e.advance();
  }
  ASSERT_EQ(files.size(), 3u);
  EXPECT_NE(files[2].find("frame_00002."), std::string::npos) << files[2];
  const std::string old_path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", "/nonexistent", 1);
  EXPECT_EQ(e.video_command(30), "");
  const std::string fake = dir + "/ffmpeg";
  { std::ofstream(fake) << "#!/bin/sh\n"; }
  chmod(fake.c_str(), 0755);
  setenv("PATH", dir.c_str(), 1);
  EXPECT_NE(e.video_command(30).find("path.mp4"), std::string::npos);
  setenv("PATH", old_path.c_str(), 1);
}

// A FIFO where the video goes would keep ffmpeg waiting for a reader for ever, after every frame
// was rendered: the export is refused before its first frame.
TEST(ViewerFiles, PathExportRefusesAFifoWhereTheVideoGoes) {
  const std::string dir = scratch_dir("viewer_export_fifo");
  ASSERT_EQ(mkfifo((dir + "/path.mp4").c_str(), 0644), 0);
  fv::PathExport e;
  EXPECT_EQ(e.start(dir, 3), "path export: " + dir + "/path.mp4: is a FIFO (named pipe), not a regular file");
  EXPECT_FALSE(e.active());
}

// A SOG LOD set opens at the level asked for and lists every level (the viewer's LOD
// selector); a file that is not a LOD set refuses a level with one line naming it.
TEST(ViewerLoad, SogLodSetLoadsTheAskedLevelAndListsTheLevels) {
  const std::string set = flashgs::test::shared_format_file("playbot_sog");
  if (set.empty()) GTEST_SKIP() << "../shared/scenes/formats/playbot_sog is absent";
  const fv::LoadedScene coarse = fv::load_scene(set, "", nullptr, 6);
  ASSERT_EQ(coarse.lod_gaussians.size(), 7u);
  EXPECT_EQ(coarse.lod_level, 6);
  EXPECT_EQ(coarse.scene->size(), coarse.lod_gaussians[6]);
  EXPECT_LT(coarse.lod_gaussians[6], coarse.lod_gaussians[0]);
  try {
    fv::load_scene(set, "", nullptr, 7);
    ADD_FAILURE() << "level 7 of a 7-level set was accepted";
  } catch (const flashgs::Error& e) {
    EXPECT_NE(std::string(e.what()).find("has levels 0..6"), std::string::npos) << e.what();
  }
  const std::string ply = flashgs::demo_scene_path();
  EXPECT_TRUE(fv::load_scene(ply).lod_gaussians.empty());
  try {
    fv::load_scene(ply, "", nullptr, 1);
    ADD_FAILURE() << "a LOD level was accepted for a PLY";
  } catch (const flashgs::Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a SOG LOD set"), std::string::npos) << e.what();
  }
}

// A scene file's LOD set cache: beside the file and in the user's cache, under a key that
// changes with the file's size and time and with the build's sizes, and only with those.
TEST(ViewerLodCache, TheKeyFollowsTheFileAndTheBuildSizes) {
  namespace fs = std::filesystem;
  const std::string dir = scratch_dir("lod_cache");
  const std::string file = dir + "/big.ply";
  std::ofstream(file) << "twelve bytes";
  setenv("XDG_CACHE_HOME", (dir + "/cache").c_str(), 1);
  flashgs::LodBuildOptions options;
  const fv::LodCacheFolders a = fv::lod_cache_folders(file, options);
  unsetenv("XDG_CACHE_HOME");
  EXPECT_EQ(a.beside.rfind(file + ".lod-", 0), 0u) << a.beside;
  EXPECT_EQ(a.beside.size(), file.size() + 5 + 16) << a.beside;
  EXPECT_EQ(a.user.rfind(dir + "/cache/flashgs/lod/big.ply-", 0), 0u) << a.user;
  EXPECT_EQ(a.beside.substr(a.beside.size() - 16), a.user.substr(a.user.size() - 16));
  EXPECT_EQ(fv::lod_cache_folders(file, options).beside, a.beside) << "the same file and sizes: the same key";
  options.leaf_gaussians = 2048;
  EXPECT_NE(fv::lod_cache_folders(file, options).beside, a.beside);
  options = flashgs::LodBuildOptions{};
  options.file_gaussians = 8192;
  EXPECT_NE(fv::lod_cache_folders(file, options).beside, a.beside);
  options = flashgs::LodBuildOptions{};
  fs::last_write_time(file, fs::last_write_time(file) + std::chrono::seconds(3));
  const std::string after_touch = fv::lod_cache_folders(file, options).beside;
  EXPECT_NE(after_touch, a.beside);
  const fs::file_time_type touched = fs::last_write_time(file);
  std::ofstream(file, std::ios::app) << "!";
  fs::last_write_time(file, touched);
  EXPECT_NE(fv::lod_cache_folders(file, options).beside, after_touch) << "another size";
  EXPECT_THROW(fv::lod_cache_folders(dir + "/absent.ply", options), flashgs::Error);
}

namespace {

// A frame path that holds parts as the GPU's pool does: it refuses to draw them with the
// baseline, and records what it was given (and can refuse the next parts, as a full GPU would).
class PoolLikePath final : public fv::FramePath {
 public:
  std::string name() const override { return "pool-like"; }
  void set_scene(std::shared_ptr<const flashgs::Scene> scene) override {
    ++scenes;
    scene_size = scene->size();
  }
  void set_scene_parts(const std::vector<flashgs::ScenePart>& parts, std::uint64_t resident) override {
    if (refuse_parts) throw flashgs::Error("out of GPU memory");
    ++part_sets;
    last_parts = parts;
    resident_bytes = resident;
  }
  std::string scene_parts_refusal(const flashgs::RenderOptions& options) const override {
    return options.is_baseline() ? "not by the baseline" : "";
  }
  void attach_textures(const unsigned*, int, int) override {}
  void release_textures() override {}
  void render_to_texture(const flashgs::Camera&, const flashgs::RenderOptions&, flashgs::FrameStats*) override {}
  void render_image(const flashgs::Camera&, const flashgs::RenderOptions&, flashgs::Image&, flashgs::FrameStats*,
                    const std::atomic<bool>*) override {}
  void tile_counts(const flashgs::FrameStats&, std::vector<std::uint32_t>&) override {}

  int scenes = 0, part_sets = 0;
  std::size_t scene_size = 0;
  bool refuse_parts = false;
  std::vector<flashgs::ScenePart> last_parts;
  std::uint64_t resident_bytes = 0;
};

}  // namespace

// The viewer's streamed cut reaches a GPU-like path as parts under the GPU cap, assembled while
// the view's configuration is one the path cannot draw parts with (and for a comparison's side),
// as parts again after; a refused hand-over is tried again; the overlay hands tinted parts.
TEST(ViewerStream, TheCutGoesAsPartsOrAssembledWhereThePathCannotDrawParts) {
  const std::string set = scratch_dir("stream_parts") + "/set";
  flashgs::LodBuildOptions build;
  build.leaf_gaussians = 2048;
  flashgs::build_lod_set(flashgs::demo_scene_path(), set, build);
  fv::StreamSettings settings;
  settings.max_error_px = 8.0f;
  settings.device_bytes = 64u << 20;
  settings.parts_on_device = true;
  fv::LodStreamView stream;
  stream.start(set + "/lod-meta.json", settings);
  const flashgs::Camera camera = flashgs::load_cameras(flashgs::demo_cameras_path())[3].resized(320, 180);
  const flashgs::RenderOptions flash, baseline = flashgs::RenderOptions::baseline();
  PoolLikePath path;

  fv::StreamUpdate u = stream.update(camera, flash, true, 0.0, path);
  ASSERT_TRUE(u.handed);
  EXPECT_FALSE(u.assembled_changed);
  EXPECT_EQ(path.part_sets, 1);
  EXPECT_EQ(path.scenes, 0);
  EXPECT_GT(path.resident_bytes, 0u) << "the GPU cap did not reach the path";
  const std::uint64_t drawn = flashgs::scene_parts_size(path.last_parts);
  EXPECT_EQ(drawn, stream.stats().drawn_gaussians);
  EXPECT_FALSE(stream.update(camera, flash, false, 0.0, path).handed) << "the same cut was handed over again";

  // The host cap counts the assembled cut (the demo scene: 92 bytes a Gaussian) while the
  // path takes it so, and not once parts go to the GPU again.
  const std::uint64_t host_with_parts = stream.stats().host_bytes;
  u = stream.update(camera, baseline, false, 0.0, path);
  EXPECT_TRUE(u.handed && u.assembled_changed);
  EXPECT_EQ(stream.assembled_because(), "not by the baseline");
  EXPECT_EQ(path.scenes, 1);
  EXPECT_EQ(path.scene_size, drawn);
  EXPECT_EQ(stream.stats().host_bytes, host_with_parts + drawn * 92);
  EXPECT_FALSE(stream.update(camera, baseline, false, 0.0, path).handed);
  u = stream.update(camera, flash, false, 0.0, path);
  EXPECT_TRUE(u.handed && u.assembled_changed);
  EXPECT_EQ(path.part_sets, 2);
  EXPECT_EQ(stream.stats().host_bytes, host_with_parts);

  // A comparison of the baseline with flash: the cut assembled for it, parts at the next frame.
  EXPECT_EQ(stream.assemble_for({baseline, flash}, path), "not by the baseline");
  EXPECT_EQ(path.scenes, 2);
  EXPECT_EQ(stream.assemble_for({flash}, path), "");
  EXPECT_TRUE(stream.update(camera, flash, false, 0.0, path).handed);
  EXPECT_EQ(path.part_sets, 3);

  path.refuse_parts = true;
  stream.hand_over_again();
  u = stream.update(camera, flash, false, 0.0, path);
  EXPECT_FALSE(u.handed);
  EXPECT_EQ(u.path_error, "out of GPU memory");
  path.refuse_parts = false;
  EXPECT_TRUE(stream.update(camera, flash, false, 0.0, path).handed) << "a refused cut was not handed over again";

  stream.set_level_overlay(true);
  ASSERT_TRUE(stream.update(camera, flash, false, 0.0, path).handed);
  EXPECT_EQ(flashgs::scene_parts_size(path.last_parts), drawn);
  for (const flashgs::ScenePart& p : path.last_parts) {
    ASSERT_NE(p.key & flashgs::kTintedPartKeyBit, 0u);
    EXPECT_EQ(p.source->sh_degree, 0);
  }
  EXPECT_EQ(stream.drawn_parts().size(), path.last_parts.size());
  EXPECT_NE(stream.summary().find(std::to_string(path.last_parts.size()) + " parts handed over (hand-over 6: "),
            std::string::npos)
      << stream.summary();
}
