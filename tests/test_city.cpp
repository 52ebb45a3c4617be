// The city generator: every source's Gaussians in every block, each block upright on the ground
// at its grid place, headings distinct, the camera path from street level to an overview; and
// the rotation helpers it builds on.
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "flashgs/city_scene.h"
#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/io.h"
#include "flashgs/rotation.h"
#include "test_support.h"

namespace flashgs {
namespace {

TEST(Rotation, QuaternionsAndMatricesRoundTripAndCompose) {
  const double q[4] = {0.8, 0.1, -0.5, 0.3};
  double m[9], back[4];
  matrix_from_quaternion(q, m);
  quaternion_from_matrix(m, back);
  const double n = std::sqrt(0.64 + 0.01 + 0.25 + 0.09);
  const double sign = back[0] * q[0] > 0 ? 1 : -1;
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(sign * back[k], q[k] / n, 1e-12);
  // q * q^-1 is the identity.
  const double inverse[4] = {q[0], -q[1], -q[2], -q[3]};
  double product[4];
  multiply_quaternions(q, inverse, product);
  EXPECT_NEAR(product[0], n * n, 1e-12);
  for (int k = 1; k < 4; ++k) EXPECT_NEAR(product[k], 0.0, 1e-12);
}

TEST(CityScene, BlocksHoldEverySourceUprightAtTheirPlacesWithAPathFromTheStreetUp) {
  const Scene demo = load_ply(demo_scene_path());  // y up
  std::vector<CitySource> sources(1);
  sources[0].name = "demo";
  sources[0].scene = demo;
  sources[0].up = "+y";
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/city";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::vector<Camera> path;
  const CityReport r = write_city_scene(sources, 4, dir + "/city.ply", 20, 320, 180, &path);
  EXPECT_EQ(r.gaussians, 4 * demo.size());
  const Scene city = load_ply(dir + "/city.ply");
  ASSERT_EQ(city.size(), 4 * demo.size());
  EXPECT_EQ(city.sh_degree, 0);
  // The demo's height (its y range) became the city's z range, from the ground up.
  float y_lo = demo.positions[1], y_hi = y_lo, z_lo = city.positions[2], z_hi = z_lo;
  for (std::size_t i = 0; i < demo.size(); ++i) y_lo = std::min(y_lo, demo.positions[i * 3 + 1]), y_hi = std::max(y_hi, demo.positions[i * 3 + 1]);
  for (std::size_t i = 0; i < city.size(); ++i) z_lo = std::min(z_lo, city.positions[i * 3 + 2]), z_hi = std::max(z_hi, city.positions[i * 3 + 2]);
  EXPECT_NEAR(z_hi - z_lo, y_hi - y_lo, 1e-3f * (y_hi - y_lo));
  EXPECT_LE(z_lo, 0.0f);  // the ground (2nd percentile of height) is at 0: at most a few lie below it
  EXPECT_GT(z_lo, -0.05f * (y_hi - y_lo));
  EXPECT_GT(z_hi, 0.0f);
  // Each block's centre of mass sits in its own grid cell (2 x 2), the cells block_size apart.
  for (int b = 0; b < 4; ++b) {
    double cx = 0, cy = 0;
    for (std::size_t i = b * demo.size(); i < (b + 1) * demo.size(); ++i) cx += city.positions[i * 3], cy += city.positions[i * 3 + 1];
    cx /= double(demo.size()), cy /= double(demo.size());
    EXPECT_NEAR(cx, (b % 2) * r.block_size, 0.25 * r.block_size) << "block " << b;
    EXPECT_NEAR(cy, (b / 2) * r.block_size, 0.25 * r.block_size) << "block " << b;
  }
  // Headings differ: the first Gaussian's offset from its block's cell differs between blocks.
  const float dx0 = city.positions[0], dx1 = city.positions[demo.size() * 3] - r.block_size;
  EXPECT_GT(std::fabs(dx0 - dx1), 1e-3f * r.block_size);
  // Rotations stay unit quaternions.
  for (std::size_t i = 0; i < city.size(); i += 997) {
    const float* q = &city.rotations[i * 4];
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0f, 1e-5f);
  }
  ASSERT_EQ(path.size(), 20u);
  EXPECT_LT(path.front().position[2], 0.05f * r.block_size);
  EXPECT_GT(path.back().position[2], 1.0f * r.block_size);
}

TEST(CityScene, AnUnknownUpAxisIsNamed) {
  std::vector<CitySource> sources(1);
  sources[0].name = "demo";
  sources[0].scene = load_ply(demo_scene_path());
  sources[0].up = "up";
  try {
    write_city_scene(sources, 1, std::string(FLASHGS_TEST_OUTPUT_DIR) + "/city_bad.ply", 0, 320, 180, nullptr);
    FAIL() << "an unknown up axis was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("demo: up axis \"up\""), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flashgs
