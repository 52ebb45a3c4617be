// The spatial order of a scene's Gaussians (the CUDA backend's device layout): a permutation,
// spatially coherent where the stored order is not, and the verdict on which scenes need it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "flashgs/generators.h"
#include "flashgs/spatial_order.h"
#include "test_support.h"

namespace flashgs {
namespace {

// The verdict: whether the upload would keep the stored order.
bool spatially_coherent(const Scene& scene) { return spatial_order_where_it_pays(scene).empty(); }

void expect_permutation(const std::vector<std::uint32_t>& order, std::size_t n, const char* what) {
  ASSERT_EQ(order.size(), n) << what;
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::uint32_t> all(n);
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(sorted, all) << what;
}

// The demo scene, stored as generated, shuffled, and put back in spatial order: only the
// shuffled one is incoherent, and the order restores coherence from any start.
TEST(SpatialOrder, RestoresCoherenceFromARandomOrder) {
  const Scene& demo = *test::load_demo_scene();
  const Scene shuffled = test::permuted(demo, test::random_order(demo.size(), 7));
  EXPECT_FALSE(spatially_coherent(shuffled));
  const std::vector<std::uint32_t> order = spatial_order(shuffled);
  expect_permutation(order, shuffled.size(), "shuffled demo");
  EXPECT_TRUE(spatially_coherent(test::permuted(shuffled, order)));
  // Stable within a cell: a scene already in spatial order keeps that order.
  const Scene ordered = test::permuted(shuffled, order);
  const std::vector<std::uint32_t> again = spatial_order(ordered);
  std::vector<std::uint32_t> identity(again.size());
  std::iota(identity.begin(), identity.end(), 0u);
  EXPECT_EQ(again, identity);
}

// The scenes converted from the PlayCanvas formats (pc_*) are stored spatially coherent, so the
// upload leaves them as they are, but not in random order; raw trainer output (v3dg_donut's
// mip-splatting file, kacytran_try) is stored in an order as good as random (runs of 256
// consecutive Gaussians span 54-63 of the 64 cells along an axis, against 2-7 for pc_*).
TEST(SpatialOrder, RealScenesNeedItWhereRawFromATrainer) {
  FLASHGS_REQUIRE_SHARED_SCENES();
  for (const std::string& name : test::shared_scene_names()) {
    const auto scene = test::load_shared_scene(name);
    const bool playcanvas = name.rfind("pc_", 0) == 0;
    EXPECT_EQ(spatially_coherent(*scene), playcanvas) << name;
    const Scene shuffled = test::permuted(*scene, test::random_order(scene->size(), 3));
    EXPECT_FALSE(spatially_coherent(shuffled)) << name;
    const std::vector<std::uint32_t> order = spatial_order(shuffled);
    expect_permutation(order, scene->size(), name.c_str());
    const Scene ordered = test::permuted(shuffled, order);
    EXPECT_TRUE(spatially_coherent(ordered)) << name;
    // Stable over the threads' shares too (pc_playbot is split over several).
    const std::vector<std::uint32_t> again = spatial_order(ordered);
    std::size_t moved = 0;
    for (std::size_t k = 0; k < again.size(); ++k) moved += again[k] != k;
    EXPECT_EQ(moved, 0u) << name;
  }
}

// Shuffled scenes copied side by side: each run stays within one copy, which is small beside
// the whole, yet the runs are as loose as the copy allows and the order pays; copies of a scene
// in spatial order need none.
TEST(SpatialOrder, ManyShuffledCopiesNeedIt) {
  const Scene& demo = *test::load_demo_scene();
  const Scene shuffled = test::permuted(demo, test::random_order(demo.size(), 5));
  const Scene ordered = test::permuted(shuffled, spatial_order(shuffled));
  for (int copies : {4, 64, 200}) {
    EXPECT_FALSE(spatially_coherent(tile_scene(shuffled, copies))) << copies;
    EXPECT_TRUE(spatially_coherent(tile_scene(ordered, copies))) << copies;
  }
}

// Non-finite and coincident positions, and scenes of zero, one and two Gaussians: still a
// permutation, no crash.
TEST(SpatialOrder, DegenerateScenes) {
  Scene scene = test::permuted(*test::load_demo_scene(), test::random_order(test::load_demo_scene()->size(), 1));
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < scene.size(); i += 7) scene.positions[i * 3 + i % 3] = (i % 2) ? inf : nan;
  expect_permutation(spatial_order(scene), scene.size(), "non-finite positions");
  (void)spatially_coherent(scene);
  Scene flat = scene;
  for (float& p : flat.positions) p = 1.0f;  // every Gaussian at one point: a box of no extent
  expect_permutation(spatial_order(flat), flat.size(), "one point");
  EXPECT_TRUE(spatially_coherent(flat));  // no distance to gain
  for (std::size_t n : {0, 1, 2}) {
    const Scene small = test::permuted(*test::load_demo_scene(), std::vector<std::uint32_t>(n, 0u));
    expect_permutation(spatial_order(small), n, "tiny scene");
    EXPECT_TRUE(spatially_coherent(small));  // coincident or too few: nothing to gain
  }
}

}  // namespace
}  // namespace flashgs
