// cameras.json loading: the 3DGS format, and one test per kind of bad camera file.
#include <gtest/gtest.h>

#include <cmath>

#include "flashgs/error.h"
#include "flashgs/io.h"
#include "test_support.h"

namespace flashgs {
namespace {

const char* kGood = R"([{"id": 0, "img_name": "a", "width": 64, "height": 32,
  "position": [1, 2, 3], "rotation": [[1, 0, 0], [0, 0, -1], [0, 1, 0]], "fx": 50, "fy": 50}])";

void expect_error(const std::string& json, const std::string& fragment) {
  try {
    parse_cameras(json, "cams.json");
    ADD_FAILURE() << "expected an error containing \"" << fragment << "\"";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cams.json", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

TEST(Cameras, ReadsPoseIntrinsicsAndName) {
  const auto cams = parse_cameras(kGood, "cams.json");
  ASSERT_EQ(cams.size(), 1u);
  const Camera& c = cams[0];
  EXPECT_EQ(c.width, 64);
  EXPECT_EQ(c.name, "a");
  EXPECT_FLOAT_EQ(c.cx, 31.5f);
  // world-to-camera is the transpose of the file's camera-to-world
  EXPECT_FLOAT_EQ(c.rotation[1], 0.0f);
  EXPECT_FLOAT_EQ(c.rotation[5], 1.0f);
  EXPECT_FLOAT_EQ(c.rotation[7], -1.0f);
  EXPECT_FLOAT_EQ(c.position[2], 3.0f);
}

TEST(Cameras, ResizeKeepsTheFieldOfView) {
  const Camera c = parse_cameras(kGood, "cams.json")[0];
  const Camera r = c.resized(128, 64);
  EXPECT_NEAR(r.horizontal_fov_degrees(), c.horizontal_fov_degrees(), 1e-4);
  EXPECT_FLOAT_EQ(r.cx, 63.5f);
}

TEST(CamerasBad, MissingFile) {
  try {
    load_cameras("/nonexistent/cameras.json");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cameras.json: cannot open"), std::string::npos);
  }
}
TEST(CamerasBad, NotJson) { expect_error("[{\"width\": 3,", "not valid JSON"); }
TEST(CamerasBad, NotAList) { expect_error("{}", "array"); }
TEST(CamerasBad, EmptyList) { expect_error("[]", "empty"); }
TEST(CamerasBad, MissingField) { expect_error(replace(kGood, "\"fx\": 50, ", ""), "missing field \"fx\""); }
TEST(CamerasBad, NonFinitePosition) { expect_error(replace(kGood, "[1, 2, 3]", "[1, null, 3]"), "not a finite number"); }
TEST(CamerasBad, NonFiniteRotation) {
  expect_error(replace(kGood, "[0, 1, 0]]", "[0, 1, null]]"), "non-finite");
}
TEST(CamerasBad, HugeNumberIsNotFinite) { expect_error(replace(kGood, "\"fy\": 50", "\"fy\": 1e999"), "1e999"); }
TEST(CamerasBad, NonOrthonormalRotation) {
  expect_error(replace(kGood, "[[1, 0, 0]", "[[1.1, 0, 0]"), "not orthonormal");
}
TEST(CamerasBad, ReflectionIsNotARotation) {
  expect_error(replace(kGood, "[[1, 0, 0]", "[[-1, 0, 0]"), "not orthonormal");
}
TEST(CamerasBad, BadSize) { expect_error(replace(kGood, "\"width\": 64", "\"width\": 0"), "width"); }
TEST(CamerasBad, NegativeFocal) { expect_error(replace(kGood, "\"fx\": 50", "\"fx\": -5"), "positive"); }

// Doubles that JSON holds but a float does not: checked after the conversion.
TEST(CamerasBad, FocalBeyondTheFloatRange) { expect_error(replace(kGood, "\"fx\": 50", "\"fx\": 1e300"), "fx"); }
TEST(CamerasBad, FocalThatIsZeroAsAFloat) {
  expect_error(replace(kGood, "\"fy\": 50", "\"fy\": 1e-300"), "fx and fy must be between 0.001 and 1e+09 pixels");
}
TEST(CamerasBad, DenormalFocal) { expect_error(replace(kGood, "\"fx\": 50", "\"fx\": 1e-40"), "fy = 50"); }
TEST(CamerasBad, PositionBeyondTheFloatRange) {
  expect_error(replace(kGood, "[1, 2, 3]", "[1, 1e300, 3]"), "\"position\"[1] is not a finite float (1e+300)");
}
TEST(CamerasBad, EmptyText) { expect_error(" \n", "the file is empty"); }

// img_name is shown in messages and the viewer: control characters escaped, length cut.
TEST(Cameras, NameIsMadePrintableAndShort) {
  const Camera odd = parse_cameras(replace(kGood, "\"a\"", "\"a\\u001b[2J\\nb\""), "cams.json")[0];
  EXPECT_EQ(odd.name, "a\\x1b[2J\\x0ab");
  const Camera unicode = parse_cameras(replace(kGood, "\"a\"", "\"caf\u00e9\""), "cams.json")[0];
  EXPECT_EQ(unicode.name, "caf\u00e9");
  const Camera huge = parse_cameras(replace(kGood, "\"a\"", "\"" + std::string(1 << 20, 'n') + "\""), "cams.json")[0];
  EXPECT_LT(huge.name.size(), 250u);
  EXPECT_NE(huge.name.find("(1048576 bytes)"), std::string::npos) << huge.name;
}

TEST(CamerasReal, EverySharedSceneHas52Cameras) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) EXPECT_EQ(test::load_shared_cameras(name).size(), 52u) << name;
}

}  // namespace
}  // namespace flashgs
