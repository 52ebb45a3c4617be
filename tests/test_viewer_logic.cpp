// The viewer's logic without a window: navigation, paths, key scripts, settings ranges, memory estimates, scene loads.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <limits>
#include <thread>

#include <sys/stat.h>
#include <unistd.h>

#include "camera_controller.h"
#include "camera_path.h"
#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "key_script.h"
#include "flashgs/frame_memory.h"
#include "memory_budget.h"
#include "scene_loader.h"
#include "scene_state.h"
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
    fv::SceneLoader loader([released](const std::string& path) -> fv::LoadedScene {
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
