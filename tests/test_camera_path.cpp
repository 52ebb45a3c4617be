// Keyframed camera paths: interpolation through the keys, the JSON round trip, nerfstudio's camera_path.json, and one test per kind of bad path file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/keyframe_path.h"
#include "test_support.h"

namespace flashgs {
namespace {

Camera look(float ex, float ey, float ez, float tx, float ty, float tz, float fov = 60.0f) {
  const float eye[3] = {ex, ey, ez}, target[3] = {tx, ty, tz}, up[3] = {0, -1, 0};
  return look_at_camera(eye, target, up, 320, 180, fov);
}

KeyframePath three_keys() {
  KeyframePath p;
  p.keys = {Keyframe::from_camera(look(0, 0, -4, 0, 0, 0), 0.0), Keyframe::from_camera(look(4, 0, 0, 0, 0, 0, 50), 2.0),
            Keyframe::from_camera(look(0, -1, 4, 0, 0, 0), 3.0)};
  p.fps = 10;
  p.width = 320;
  p.height = 180;
  return p;
}

void expect_same_camera(const Camera& a, const Camera& b, float tolerance) {
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(a.rotation[i], b.rotation[i], tolerance) << "rotation " << i;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.position[i], b.position[i], tolerance) << "position " << i;
  EXPECT_NEAR(a.fx, b.fx, tolerance * a.fx);
  EXPECT_EQ(a.width, b.width);
}

TEST(CameraPath, ItPassesThroughEachKeyAtItsTimeAndMovesSmoothlyBetween) {
  for (PathEasing easing : {PathEasing::linear, PathEasing::ease_in_out}) {
    KeyframePath p = three_keys();
    p.easing = easing;
    EXPECT_EQ(p.frame_count(), 31);
    expect_same_camera(p.camera_at(0.0, 320, 180), look(0, 0, -4, 0, 0, 0), 1e-5f);
    expect_same_camera(p.camera_at(3.0, 320, 180), look(0, -1, 4, 0, 0, 0), 1e-5f);
    if (easing == PathEasing::linear) expect_same_camera(p.camera_at(2.0, 320, 180), look(4, 0, 0, 0, 0, 0, 50), 1e-5f);
    // Beyond the ends: the end keys.
    expect_same_camera(p.camera_at(-5.0, 320, 180), look(0, 0, -4, 0, 0, 0), 1e-5f);
    expect_same_camera(p.camera_at(99.0, 320, 180), look(0, -1, 4, 0, 0, 0), 1e-5f);
    // No jumps: successive frames 1/100 s apart are close, and every rotation is a rotation.
    Camera last = p.camera_at(0.0, 320, 180);
    for (int i = 1; i <= 300; ++i) {
      const Camera c = p.camera_at(i / 100.0, 320, 180);
      const float step = std::hypot(c.position[0] - last.position[0], c.position[1] - last.position[1],
                                    c.position[2] - last.position[2]);
      EXPECT_LT(step, 0.2f) << "t " << i / 100.0;
      for (int r = 0; r < 3; ++r)
        EXPECT_NEAR(std::hypot(c.rotation[3 * r], c.rotation[3 * r + 1], c.rotation[3 * r + 2]), 1.0f, 1e-4f);
      last = c;
    }
  }
  // Ease in/out starts at rest: the first step is far shorter than linear's.
  KeyframePath eased = three_keys(), linear = three_keys();
  linear.easing = PathEasing::linear;
  const auto first_step = [](const KeyframePath& p) {
    const Camera a = p.camera_at(0.0, 320, 180), b = p.camera_at(0.05, 320, 180);
    return std::hypot(a.position[0] - b.position[0], a.position[2] - b.position[2]);
  };
  EXPECT_LT(first_step(eased), 0.2f * first_step(linear));
}

TEST(CameraPath, WrittenAndReadBackItIsTheSamePath) {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/camera_path";
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/path.json";
  KeyframePath p = three_keys();
  p.easing = PathEasing::linear;
  write_camera_path(p, file);
  const KeyframePath q = read_camera_path(file);
  ASSERT_EQ(q.keys.size(), 3u);
  EXPECT_EQ(q.fps, 10);
  EXPECT_EQ(q.width, 320);
  EXPECT_EQ(q.height, 180);
  EXPECT_EQ(q.easing, PathEasing::linear);
  for (double t : {0.0, 0.7, 2.0, 2.5, 3.0}) expect_same_camera(q.camera_at(t, 320, 180), p.camera_at(t, 320, 180), 1e-6f);
}

// nerfstudio's frames: OpenGL axes (camera looks along -z, y up), vertical FOV.
TEST(CameraPath, NerfstudioCameraPathFramesBecomeKeys) {
  const char* json = R"({"camera_type": "perspective", "render_height": 100, "render_width": 200, "fps": 4,
    "seconds": 0.5, "camera_path": [
      {"camera_to_world": [1,0,0,1, 0,1,0,2, 0,0,1,3, 0,0,0,1], "fov": 90, "aspect": 2.0},
      {"camera_to_world": [1,0,0,1, 0,1,0,2, 0,0,1,4, 0,0,0,1], "fov": 90, "aspect": 2.0}]})";
  const KeyframePath p = parse_camera_path(json, "camera_path.json");
  ASSERT_EQ(p.keys.size(), 2u);
  EXPECT_EQ(p.width, 200);
  EXPECT_EQ(p.fps, 4);
  EXPECT_DOUBLE_EQ(p.keys[1].time_s, 0.25);
  const Camera c = p.camera_at(0.0, 200, 100);
  EXPECT_FLOAT_EQ(c.position[2], 3.0f);
  // OpenCV's forward (+z) is the file's -z: world (0,0,-1); its down (+y) the file's -y.
  EXPECT_FLOAT_EQ(c.rotation[8], -1.0f);
  EXPECT_FLOAT_EQ(c.rotation[4], -1.0f);
  // Vertical 90 degrees at aspect 2: fy = 50 = fx.
  EXPECT_NEAR(c.fx, 50.0f, 1e-3f);
}

void expect_error(const std::string& json, const std::string& fragment) {
  try {
    parse_camera_path(json, "path.json");
    ADD_FAILURE() << "expected an error containing \"" << fragment << "\"";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("path.json", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(CameraPath, BadFilesGetOneLineNamingTheFileAndTheProblem) {
  const std::string key = R"({"time": 0, "position": [0,0,0], "rotation": [[1,0,0],[0,1,0],[0,0,1]], "fov_x_degrees": 60})";
  const std::string head = R"({"format": "flashgs camera path", "version": 1, "fps": 30, "keyframes": [)";
  expect_error("{", "not valid JSON");
  expect_error("[1, 2]", "not a camera path");
  expect_error(R"({"cameras": []})", "not a camera path");
  expect_error(head + "]}", "\"keyframes\" is empty");
  expect_error(R"({"format": "flashgs camera path", "version": 1, "fps": 0, "keyframes": [)" + key + "]}",
               "\"fps\" is 0, outside 1..240");
  expect_error(R"({"format": "flashgs camera path", "version": 7, "fps": 30, "keyframes": [)" + key + "]}",
               "version 7 is newer");
  std::string bad = key;
  bad.replace(bad.find("[0,0,0]"), 7, "[0,null,0]");
  expect_error(head + bad + "]}", "keyframe 0: \"position\" holds something that is not a finite number");
  bad = key;
  bad.replace(bad.find("[[1,0,0]"), 8, "[[2,0,0]");
  expect_error(head + bad + "]}", "is not a rotation");
  bad = key;
  bad.replace(bad.find("60"), 2, "400");
  expect_error(head + bad + "]}", "\"fov_x_degrees\" is 400, outside 1..179");
  std::string later = key;
  later.replace(later.find("\"time\": 0"), 9, "\"time\": 5");
  expect_error(head + later + "," + key + "]}", "keyframe 1: its time comes before keyframe 0's");
  expect_error(R"({"fps": 24, "camera_path": [{"camera_to_world": [1,0,0], "fov": 50}]})",
               "\"camera_to_world\" has 3 numbers, not 16");
}

}  // namespace
}  // namespace flashgs
