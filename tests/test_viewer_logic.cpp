// The viewer's navigation logic without a window: exact snapping, frame-rate independence, paths, key scripts.
#include <gtest/gtest.h>

#include <cmath>

#include "camera_controller.h"
#include "camera_path.h"
#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "key_script.h"
#include "scene_state.h"
#include "stats_history.h"

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
  EXPECT_DOUBLE_EQ(s.min_ms, 1.0);
  EXPECT_DOUBLE_EQ(s.max_ms, 4.0);
  EXPECT_DOUBLE_EQ(s.fps, 400.0);
}
