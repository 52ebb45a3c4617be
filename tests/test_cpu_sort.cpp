// The CPU sort stage: the depth order of the visible Gaussians (order_by_depth) and the tile
// lists that emit and sort_by_tile build from it, which must come out in (depth, id) order
// without a per-tile sort, the same for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "cpu_frame.h"  // order_by_depth
#include "cpu_stages.h"
#include "flashgs/stress_scenes.h"
#include "test_support.h"

namespace flashgs {
namespace {

// A frame holding only what order_by_depth reads: the cull reasons and depths of n Gaussians,
// and the count of visible ones (as project leaves them).
cpu::Frame frame_with(const std::vector<std::uint8_t>& cull, const std::vector<float>& depths) {
  cpu::Frame frame;
  frame.cull = cull;
  frame.visible_count = static_cast<std::size_t>(std::count(cull.begin(), cull.end(), gm::kVisible));
  frame.depth_bits.resize(depths.size());
  for (std::size_t i = 0; i < depths.size(); ++i) frame.depth_bits[i] = gm::depth_bits(depths[i]);
  return frame;
}

// The visible ids by (depth, id): what order_by_depth must produce.
std::vector<std::uint32_t> expected_order(const std::vector<std::uint8_t>& cull, const std::vector<float>& depths) {
  std::vector<std::uint32_t> ids;
  for (std::uint32_t i = 0; i < cull.size(); ++i)
    if (cull[i] == gm::kVisible) ids.push_back(i);
  std::stable_sort(ids.begin(), ids.end(), [&](std::uint32_t a, std::uint32_t b) { return depths[a] < depths[b]; });
  return ids;
}

std::vector<std::uint32_t> ordered_ids(const cpu::Frame& frame) {
  std::vector<std::uint32_t> ids(frame.visible_count);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    EXPECT_EQ(frame.depth_order[k] >> 32, frame.depth_bits[static_cast<std::uint32_t>(frame.depth_order[k])]);
    ids[k] = static_cast<std::uint32_t>(frame.depth_order[k]);
  }
  return ids;
}

void expect_depth_order(const std::vector<std::uint8_t>& cull, const std::vector<float>& depths,
                        const char* what) {
  const std::vector<std::uint32_t> expected = expected_order(cull, depths);
  for (const int threads : {1, 2, 3, 8}) {  // uneven slices too, on any machine
    cpu::Frame frame = frame_with(cull, depths);
    cpu::order_by_depth_on(frame, static_cast<std::int64_t>(cull.size()), threads);
    ASSERT_EQ(frame.visible_count, expected.size()) << what << ", " << threads << " threads";
    EXPECT_EQ(ordered_ids(frame), expected) << what << ", " << threads << " threads";
  }
}

TEST(CpuDepthOrder, VisibleGaussiansByDepthThenIdForAnyThreadCount) {
  std::mt19937 rng(7);
  const std::size_t n = 20011;
  std::vector<std::uint8_t> cull(n);
  std::vector<float> depths(n);
  // Depths over several binades (every byte of the bits varies) with many exact ties; a third
  // of the Gaussians culled for one reason or another.
  std::uniform_real_distribution<float> depth(0.2f, 900.0f);
  std::vector<float> tied(37);
  for (float& d : tied) d = depth(rng);
  for (std::size_t i = 0; i < n; ++i) {
    cull[i] = static_cast<std::uint8_t>(rng() % 3 == 0 ? 1 + rng() % (gm::kCullReasonCount - 1) : unsigned{gm::kVisible});
    depths[i] = rng() % 2 ? tied[rng() % tied.size()] : depth(rng);
  }
  expect_depth_order(cull, depths, "random depths with ties");
}

TEST(CpuDepthOrder, EqualDepthsKeepIdOrderAndEmptyFramesAreEmpty) {
  const std::size_t n = 5000;
  std::vector<std::uint8_t> cull(n, gm::kVisible);
  std::vector<float> depths(n, 3.5f);  // every radix pass skipped: the keys share every byte
  expect_depth_order(cull, depths, "one depth");
  for (std::size_t i = 0; i < n; i += 2) depths[i] = 3.5000002f;  // the lowest byte alone differs
  expect_depth_order(cull, depths, "two adjacent depths");
  std::fill(cull.begin(), cull.end(), static_cast<std::uint8_t>(gm::kCulledOffscreen));
  expect_depth_order(cull, depths, "nothing visible");
  expect_depth_order({}, {}, "no Gaussians");
}

// The tile lists of a scene and the depths they are ordered by.
struct TileLists {
  std::vector<std::uint64_t> tile_start;
  std::vector<std::uint32_t> ids;
  std::vector<std::uint32_t> depth_bits;
};

TileLists tile_lists(const Scene& scene, const Camera& camera, const RenderOptions& options, int threads) {
  cpu::Frame frame;
  FrameStats stats;
  test::build_tile_lists(scene, camera, options, threads, frame, stats);
  TileLists lists;
  lists.tile_start = frame.tile_start;
  lists.ids.assign(frame.tile_ids.begin(), frame.tile_ids.begin() + static_cast<std::ptrdiff_t>(stats.kv_pairs));
  lists.depth_bits = frame.depth_bits;
  EXPECT_EQ(lists.tile_start.back(), stats.kv_pairs);
  return lists;
}

void expect_tile_lists_in_depth_order(const Scene& scene, const Camera& camera, const char* what) {
  for (const RenderOptions& options : {RenderOptions{}, RenderOptions::baseline()}) {
    const TileLists one = tile_lists(scene, camera, options, 1);
    ASSERT_GT(one.ids.size(), 0u) << what;
    std::size_t out_of_order = 0, tiles_with_many = 0;
    for (std::size_t tile = 0; tile + 1 < one.tile_start.size(); ++tile) {
      const std::uint64_t begin = one.tile_start[tile], end = one.tile_start[tile + 1];
      tiles_with_many += end - begin >= 2;
      for (std::uint64_t k = begin + 1; k < end; ++k) {
        const std::uint32_t a = one.ids[k - 1], b = one.ids[k];
        const bool ordered = one.depth_bits[a] < one.depth_bits[b] || (one.depth_bits[a] == one.depth_bits[b] && a < b);
        out_of_order += !ordered;
      }
    }
    EXPECT_GT(tiles_with_many, 0u) << what;
    EXPECT_EQ(out_of_order, 0u) << what << " " << options.label() << ": pairs after a deeper one in their tile";
    for (const int threads : {2, 5}) {
      const TileLists more = tile_lists(scene, camera, options, threads);
      EXPECT_EQ(more.tile_start, one.tile_start) << what << " " << options.label() << ", " << threads << " threads";
      EXPECT_EQ(more.ids, one.ids) << what << " " << options.label() << ", " << threads << " threads";
    }
  }
}

TEST(CpuTileLists, InDepthOrderAndTheSameForAnyThreadCount) {
  const auto scene = test::load_demo_scene();
  Camera camera = test::load_demo_cameras().at(0);
  camera = camera.resized(301, 173);
  expect_tile_lists_in_depth_order(*scene, camera, "demo scene");
}

TEST(CpuTileLists, StressScenesOfEqualAndFarApartDepths) {
  // 10000 overlapping Gaussians at exactly one depth (the order within a tile is the ids', over
  // several emit chunks), and depths from 0.21 to 1e6 (every byte of the depth bits varies).
  for (const char* name : {"equal_depth", "depth_range", "stacked"}) {
    const StressCase c = make_stress_case(name);
    expect_tile_lists_in_depth_order(c.scene, c.cameras.at(0), name);
  }
}

}  // namespace
}  // namespace flashgs
