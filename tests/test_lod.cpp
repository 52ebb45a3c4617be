// The LOD set builder, the cut through it and the streamer: merges keep opacity mass and bounds,
// the cut is deterministic and within its budget, streamed frames equal the in-memory renderer's
// at full detail, caps hold, and a broken chunk costs only its part of the scene.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <numeric>

#include <unistd.h>

#include <gtest/gtest.h>

#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"
#include "flashgs/lod_build.h"
#include "flashgs/lod_cut.h"
#include "flashgs/lod_feed.h"
#include "flashgs/lod_stream.h"
#include "flashgs/lod_tint.h"
#include "flashgs/model_constants.h"
#include "flashgs/renderer.h"
#include "lod_merge.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

std::string fresh_folder(const std::string& name) {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/lod_" + name;
  fs::remove_all(dir);
  return dir;
}

// A set built once per process from the demo scene: 30,000 Gaussians in cells of about 2,048.
// Each test runs in its own process, several at once: each builds its own copy.
struct ProcessFolder {
  std::string path;
  ~ProcessFolder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

const std::string& demo_set() {
  static const ProcessFolder folder = [] {
    const std::string out = fresh_folder("demo_" + std::to_string(getpid()));
    LodBuildOptions options;
    options.leaf_gaussians = 2048;
    options.file_gaussians = 8192;
    build_lod_set(demo_scene_path(), out, options);
    return ProcessFolder{out};
  }();
  return folder.path;
}

double opacity_mass(const Scene& s) {
  double mass = 0;
  for (std::size_t i = 0; i < s.size(); ++i) mass += merge_weight(s, i);
  return mass;
}

Scene two_gaussians(float opacity, float distance) {
  Scene s;
  s.positions = {0, 0, 0, distance, 0.5f, 0};
  s.scales = {0.2f, 0.1f, 0.05f, 0.1f, 0.3f, 0.02f};
  s.rotations = {1, 0, 0, 0, 0.9238795f, 0, 0.3826834f, 0};
  s.opacities = {opacity, opacity * 0.5f};
  s.sh_dc = {1, 0, 0, 0, 1, 0};
  return s;
}

TEST(LodMerge, KeepsOpacityMassAndStaysInsideTheBounds) {
  const Scene s = two_gaussians(0.2f, 3.0f);
  const std::uint32_t both[2] = {0, 1};
  Scene merged;
  append_merged(s, both, 2, merged);
  ASSERT_EQ(merged.size(), 1u);
  EXPECT_LT(merged.opacities[0], 1.0f);  // no clamp here: the mass is kept
  EXPECT_NEAR(opacity_mass(merged), opacity_mass(s), 1e-6 * opacity_mass(s));
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(merged.positions[k], std::min(s.positions[k], s.positions[3 + k]));
    EXPECT_LE(merged.positions[k], std::max(s.positions[k], s.positions[3 + k]));
  }
  // The merged covariance spans both: its largest axis is at least half the centres' distance.
  EXPECT_GT(*std::max_element(merged.scales.begin(), merged.scales.end()), 1.0f);
  // Colour: the weighted mean lies between the two.
  EXPECT_GT(merged.sh_dc[0], 0.0f);
  EXPECT_GT(merged.sh_dc[1], 0.0f);
  EXPECT_NEAR(merged.sh_dc[0] + merged.sh_dc[1], 1.0f, 1e-6f);
}

// A coarser level merges near neighbours: over a random cloud, the two Gaussians of a merge lie
// 1.64 times as far apart as a Gaussian and its nearest neighbour, on average. Consecutive
// Gaussians of a Morton curve, paired before, lay 2.28 times as far (the same cloud): pairs
// across the curve's jumps.
TEST(LodMerge, ACoarserLevelPairsNearNeighbours) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  Scene s;
  const std::size_t n = 4096;
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) s.positions.push_back(unit(rng));
    for (int k = 0; k < 3; ++k) s.scales.push_back(0.001f);
    for (float q : {1.0f, 0.0f, 0.0f, 0.0f}) s.rotations.push_back(q);
    s.opacities.push_back(0.5f);
    for (int k = 0; k < 3; ++k) s.sh_dc.push_back(0.0f);
  }
  const Scene coarser = coarser_level(s);
  ASSERT_EQ(coarser.size(), n / 2);
  // Equal weights: a merge's centre is its pair's midpoint, and its largest variance holds the
  // pair's half distance squared (plus the sources' tiny own variance).
  double pair_distance = 0;
  for (std::size_t i = 0; i < coarser.size(); ++i)
    pair_distance += 2.0 * *std::max_element(&coarser.scales[i * 3], &coarser.scales[i * 3 + 3]) / static_cast<double>(coarser.size());
  double nearest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double best = 1e9;
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += double(s.positions[i * 3 + k] - s.positions[j * 3 + k]) * (s.positions[i * 3 + k] - s.positions[j * 3 + k]);
      best = std::min(best, d2);
    }
    nearest += std::sqrt(best) / static_cast<double>(n);
  }
  std::printf("mean distance within a merged pair %.4f, to the nearest neighbour %.4f\n", pair_distance, nearest);
  EXPECT_LT(pair_distance, 1.9 * nearest);
}

// Two opaque Gaussians on top of each other cover no more than one: the merge clamps opacity at
// 1 and keeps as much mass as its area holds.
TEST(LodMerge, OpacityClampsAtOneWhereTheMassExceedsTheMergedArea) {
  Scene s = two_gaussians(0.95f, 0.0f);
  s.positions[4] = 0.0f;
  s.opacities[1] = 0.95f;
  const std::uint32_t both[2] = {0, 1};
  Scene merged;
  append_merged(s, both, 2, merged);
  EXPECT_EQ(merged.opacities[0], 1.0f);
  EXPECT_NEAR(opacity_mass(merged), merge_weight(merged, 0), 1e-9);
  EXPECT_LT(opacity_mass(merged), opacity_mass(s));
}

TEST(LodMerge, ASingleGaussianMergesIntoItself) {
  const Scene s = two_gaussians(0.7f, 1.0f);
  const std::uint32_t second = 1;
  Scene merged;
  append_merged(s, &second, 1, merged);
  EXPECT_NEAR(merged.opacities[0], s.opacities[1], 1e-6f);
  std::vector<float> a(s.scales.begin() + 3, s.scales.end()), b(merged.scales.begin(), merged.scales.end());
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 1e-5f * a[2]);
}

TEST(LodBuild, Level0HoldsEveryGaussianAndCoarserLevelsHalveAndStayInTheirCells) {
  const Scene input = load_ply(demo_scene_path());
  const LodSet set = read_lod_set(demo_set());
  ASSERT_GE(set.level_count, 3);
  ASSERT_GT(set.leaves.size(), 8u);
  EXPECT_EQ(set.gaussians(0), input.size());
  for (int level = 1; level < set.level_count; ++level) {
    EXPECT_LE(set.gaussians(level), set.gaussians(level - 1) / 2 + set.leaves.size()) << "level " << level;
    EXPECT_GE(set.gaussians(level), set.gaussians(level - 1) / 2) << "level " << level;
  }
  // The root bound is the input's bound of centres.
  for (int k = 0; k < 3; ++k) {
    float lo = input.positions[k], hi = input.positions[k];
    for (std::size_t i = 0; i < input.size(); ++i) {
      lo = std::min(lo, input.positions[i * 3 + k]);
      hi = std::max(hi, input.positions[i * 3 + k]);
    }
    EXPECT_EQ(set.bound.min[k], lo);
    EXPECT_EQ(set.bound.max[k], hi);
  }
  // Every level of every leaf: its centres inside the leaf's cell, its opacity mass at most the
  // finest level's and not less than half of it (merges keep the mass unless opacity clamps at 1).
  std::vector<Scene> chunks;
  for (std::size_t f = 0; f < set.files.size(); ++f) chunks.push_back(read_lod_chunk(set.file_path(static_cast<int>(f))));
  std::vector<double> level_mass(static_cast<std::size_t>(set.level_count), 0.0);
  for (const LodLeaf& leaf : set.leaves)
    for (int level = 0; level < set.level_count; ++level) {
      const LodRange& r = leaf.levels[static_cast<std::size_t>(level)];
      ASSERT_GE(r.file, 0);
      const Scene& c = chunks[static_cast<std::size_t>(r.file)];
      ASSERT_LE(r.offset + r.count, c.size());
      for (std::uint64_t i = r.offset; i < r.offset + r.count; ++i) {
        level_mass[static_cast<std::size_t>(level)] += merge_weight(c, i);
        for (int k = 0; k < 3; ++k) {
          EXPECT_GE(c.positions[i * 3 + k], leaf.bound.min[k] - 1e-4f);
          EXPECT_LE(c.positions[i * 3 + k], leaf.bound.max[k] + 1e-4f);
        }
      }
    }
  // Merges keep the mass where opacity stays below 1; overlapping opaque pairs lose what their
  // overlap covered twice, so each level holds at most its finer level's mass.
  std::printf("opacity mass per level relative to level 0:");
  for (double m : level_mass) std::printf(" %.4f", m / level_mass[0]);
  std::printf("\n");
  EXPECT_NEAR(level_mass[0], opacity_mass(input), 1e-4 * level_mass[0]);
  for (std::size_t level = 1; level < level_mass.size(); ++level) {
    EXPECT_LE(level_mass[level], level_mass[level - 1] * (1 + 1e-5));
    EXPECT_GT(level_mass[level], 0.0);
  }
}

TEST(LodBuild, RefusesAFolderThatIsNotEmptyAndAMissingInput) {
  const std::string dir = fresh_folder("occupied");
  fs::create_directories(dir);
  std::ofstream(dir + "/keep.txt") << "x";
  try {
    build_lod_set(demo_scene_path(), dir, LodBuildOptions{});
    FAIL() << "built into a folder that holds a file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is not empty"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::exists(dir + "/keep.txt"));
  EXPECT_THROW(build_lod_set(dir + "/none.ply", fresh_folder("missing_input"), LodBuildOptions{}), Error);
}

TEST(LodBuild, ASmallMemoryCapBucketsTheSceneOnTheDisk) {
  const std::string dir = fresh_folder("small_memory");
  LodBuildOptions options;
  options.leaf_gaussians = 1024;
  options.memory_bytes = 1 << 20;  // 1 MiB: the 30,000 Gaussians (2.2 MB as records) cannot be held at once
  const LodBuildReport report = build_lod_set(demo_scene_path(), dir, options);
  EXPECT_TRUE(report.streamed);
  EXPECT_EQ(report.gaussians, 30000u);
  EXPECT_LE(report.bucket_bytes, (1u << 20) / 4 + 4096) << "a bucket larger than a quarter of the cap";
  EXPECT_EQ(read_lod_set(dir).gaussians(0), 30000u);
  EXPECT_FALSE(fs::exists(dir + "/.lod-build-tmp"));
}

// Leaves are merged on several threads; the set must be byte for byte the one a single thread
// writes (several buckets, several groups of leaves per bucket, chunk files shared by leaves).
TEST(LodBuild, AnyThreadCountWritesTheSameBytes) {
  auto build = [](int threads) {
    const std::string dir = fresh_folder("threads_" + std::to_string(threads) + "_" + std::to_string(getpid()));
    LodBuildOptions options;
    options.leaf_gaussians = 512;
    options.file_gaussians = 3000;
    options.memory_bytes = 1 << 20;
    options.threads = threads;
    build_lod_set(demo_scene_path(), dir, options);
    return dir;
  };
  const std::string one = build(1), four = build(4);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(one)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(static_cast<std::size_t>(std::distance(fs::directory_iterator(four), fs::directory_iterator())), names.size());
  EXPECT_GT(names.size(), 10u);
  for (const std::string& name : names) {
    const std::vector<char> a = read_regular_file(one + "/" + name), b = read_regular_file(four + "/" + name);
    EXPECT_EQ(a.size(), b.size()) << name;
    EXPECT_TRUE(a == b) << name << " differs between 1 and 4 threads";
  }
  fs::remove_all(one);
  fs::remove_all(four);
}

TEST(LodCut, IsDeterministicWithinItsBudgetAndFinerForASmallerError) {
  const LodSet set = read_lod_set(demo_set());
  const Camera camera = test::load_demo_cameras()[3].resized(640, 360);
  LodCutOptions options;
  options.max_error_px = 0.5f;
  const LodCut a = choose_lod_cut(set, camera, options), b = choose_lod_cut(set, camera, options);
  EXPECT_EQ(a.level, b.level);
  EXPECT_EQ(a.gaussians, b.gaussians);
  options.budget = a.gaussians / 3;
  const LodCut tight = choose_lod_cut(set, camera, options);
  EXPECT_LE(tight.gaussians, options.budget);
  EXPECT_TRUE(tight.budget_bound);
  EXPECT_EQ(tight.level, choose_lod_cut(set, camera, options).level);
  options.budget = 0;
  options.max_error_px = 8.0f;
  const LodCut coarse = choose_lod_cut(set, camera, options);
  EXPECT_LT(coarse.gaussians, a.gaussians);
  options.max_error_px = 0.0f;
  const LodCut full = choose_lod_cut(set, camera, options);
  for (std::size_t leaf = 0; leaf < full.level.size(); ++leaf) EXPECT_LE(full.level[leaf], 0) << "leaf " << leaf;
}

// Given what each chunk file takes, a cut draws only from files that fit together, counting
// each file once however many of its leaves use it, and the files always held from the start.
TEST(LodCut, KeepsToTheFilesThatFitTheFileBudget) {
  const LodSet set = read_lod_set(demo_set());
  const Camera camera = test::load_demo_cameras()[3].resized(640, 360);
  LodCutOptions options;
  options.max_error_px = 0.0f;
  LodFileBudget files;
  for (std::size_t f = 0; f < set.files.size(); ++f) files.bytes.push_back(1000 + f);
  files.always_held.assign(set.files.size(), false);
  files.always_held[0] = true;
  auto files_used = [&](const LodCut& cut) {
    std::set<int> used = {0};
    for (std::size_t leaf = 0; leaf < cut.level.size(); ++leaf)
      if (cut.level[leaf] >= 0) used.insert(set.leaves[leaf].levels[static_cast<std::size_t>(cut.level[leaf])].file);
    std::uint64_t bytes = 0;
    for (int f : used) bytes += files.bytes[static_cast<std::size_t>(f)];
    return std::make_pair(used.size(), bytes);
  };
  const LodCut free = choose_lod_cut(set, camera, options, nullptr, &files);
  const auto [all_files, all_bytes] = files_used(free);
  EXPECT_EQ(free.file_bytes, all_bytes);
  EXPECT_FALSE(free.files_bound);
  ASSERT_GT(all_files, 3u);
  files.limit = all_bytes / 2;
  const LodCut bound = choose_lod_cut(set, camera, options, nullptr, &files);
  const auto [bound_files, bound_bytes] = files_used(bound);
  EXPECT_TRUE(bound.files_bound);
  EXPECT_LE(bound_bytes, files.limit);
  EXPECT_EQ(bound.file_bytes, bound_bytes);
  EXPECT_LT(bound_files, all_files);
  EXPECT_LT(bound.gaussians, free.gaussians);
  EXPECT_GT(bound.gaussians, 0u);
}

// Every leaf in view at level 0 is the whole scene; the frame must then be the in-memory one.
TEST(LodStream, AtFullDetailTheFrameEqualsTheInMemoryRenderersFrame) {
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  LodStreamer streamer(read_lod_set(demo_set()), options);
  const std::vector<Camera> cameras = test::load_demo_cameras();
  auto renderer = make_cpu_renderer(2);
  auto reference = make_cpu_renderer(2);
  reference->set_scene(test::load_demo_scene());
  for (int index : {0, 11, 23}) {
    const Camera camera = cameras[static_cast<std::size_t>(index)].resized(320, 180);
    streamer.update(camera);
    streamer.wait_until_idle();
    const std::shared_ptr<const Scene> scene = streamer.update(camera);
    EXPECT_EQ(streamer.stats().leaves_coarser, 0);
    EXPECT_EQ(streamer.stats().leaves_missing, 0);
    renderer->set_scene(scene);
    Image streamed, whole;
    renderer->render(camera, RenderOptions{}, streamed, nullptr);
    reference->render(camera, RenderOptions{}, whole, nullptr);
    const ImageDifference d = compare_images(streamed, whole);
    std::printf("camera %d: %zu Gaussians drawn, PSNR %.1f dB, max |difference| %.2e\n", index, scene->size(), d.psnr_db,
                d.max_abs);
    // The chunks hold the Gaussians as PLY does (log scale, logit opacity): a float round trip.
    EXPECT_GT(d.psnr_db, 90.0) << "camera " << index;
    EXPECT_LT(d.max_abs, 1e-3) << "camera " << index;
  }
}

// The cut as parts (for a renderer that keeps them on the GPU) holds the Gaussians of the
// assembled cut in the same order; parts are keyed by chunk file and offset, so a key names
// one range; a renderer's default set_scene_parts draws the assembled frame; and the parts
// change only when the drawn set does.
TEST(LodStream, TheCutAsPartsHoldsTheAssembledScene) {
  LodStreamOptions options;
  options.cut.max_error_px = 2.0f;
  LodStreamer parts_streamer(read_lod_set(demo_set()), options);
  LodStreamer scene_streamer(read_lod_set(demo_set()), options);
  const std::vector<Camera> cameras = test::load_demo_cameras();
  auto from_parts = make_cpu_renderer(2);
  auto from_scene = make_cpu_renderer(2);
  for (int index : {0, 11, 23}) {
    const Camera camera = cameras[static_cast<std::size_t>(index)].resized(320, 180);
    for (LodStreamer* s : {&parts_streamer, &scene_streamer}) {
      s->update(camera);
      s->wait_until_idle();
    }
    bool changed = false;
    const std::vector<ScenePart> parts = parts_streamer.update_parts(camera, &changed);
    const std::shared_ptr<const Scene> scene = scene_streamer.update(camera);
    ASSERT_FALSE(parts.empty());
    EXPECT_EQ(scene_parts_size(parts), scene->size());
    EXPECT_EQ(parts_streamer.stats().drawn_gaussians, scene->size());
    const std::shared_ptr<Scene> assembled = assemble_scene_parts(parts);
    EXPECT_EQ(assembled->positions, scene->positions) << "camera " << index;
    EXPECT_EQ(assembled->sh_dc, scene->sh_dc) << "camera " << index;
    std::map<std::uint64_t, std::size_t> counts;
    for (const ScenePart& p : parts) {
      EXPECT_EQ(p.key, static_cast<std::uint64_t>(p.key >> 40) << 40 | p.first);
      const auto [it, fresh] = counts.emplace(p.key, p.count);
      EXPECT_TRUE(fresh || it->second == p.count);
    }
    parts_streamer.update_parts(camera, &changed);
    EXPECT_FALSE(changed) << "the same view and nothing new in memory changed the parts";
    from_parts->set_scene_parts(parts, 0);
    from_scene->set_scene(scene);
    Image a, b;
    from_parts->render(camera, RenderOptions{}, a, nullptr);
    from_scene->render(camera, RenderOptions{}, b, nullptr);
    EXPECT_EQ(a.rgb, b.rgb) << "camera " << index;
  }
}

// Assembling into a scene that held another cut (the CPU renderer reuses the cut before last):
// its old Gaussians, degree and kernel are gone, and the result is the fresh assembly's.
TEST(ScenePartsAssembly, IntoAUsedSceneEqualsAFreshAssembly) {
  const std::shared_ptr<const Scene> demo = test::load_demo_scene();
  const std::vector<ScenePart> parts = {{1, demo, 100, 50}, {2, demo, 7, 3}, {3, demo, 20000, 1000}};
  Scene used = two_gaussians(0.5f, 1.0f);
  used.append(used);
  for (int round = 0; round < 3; ++round) used.append(used);
  used.trained_kernel.kernel = SplatKernel::antialiased();
  const std::size_t capacity_before = used.positions.capacity();
  assemble_scene_parts_into(parts, used);
  const std::shared_ptr<Scene> fresh = assemble_scene_parts(parts);
  EXPECT_EQ(used.size(), 1053u);
  EXPECT_EQ(used.sh_degree, fresh->sh_degree);
  EXPECT_EQ(used.positions, fresh->positions);
  EXPECT_EQ(used.scales, fresh->scales);
  EXPECT_EQ(used.rotations, fresh->rotations);
  EXPECT_EQ(used.opacities, fresh->opacities);
  EXPECT_EQ(used.sh_dc, fresh->sh_dc);
  EXPECT_EQ(used.sh_rest, fresh->sh_rest);
  EXPECT_TRUE(used.trained_kernel.kernel == fresh->trained_kernel.kernel);
  EXPECT_GE(used.positions.capacity(), capacity_before) << "the arrays were not reused";
  assemble_scene_parts_into({}, used);
  EXPECT_EQ(used.size(), 0u);
  EXPECT_TRUE(used.sh_rest.empty());
}

TEST(LodStream, UnderATinyCapEveryFrameStillRendersAndTheCapHolds) {
  const LodSet set = read_lod_set(demo_set());
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  options.host_bytes = 2u << 20;  // 2 MiB: the coarsest level's file fits, the finest level (2.8 MB) never
  LodStreamer streamer(set, options);
  const std::vector<Camera> cameras = test::load_demo_cameras();
  for (std::size_t i = 0; i < 12; ++i) {
    const Camera camera = cameras[i * 3].resized(160, 90);
    streamer.update(camera);
    streamer.wait_until_idle();
    const std::shared_ptr<const Scene> scene = streamer.update(camera);
    const LodStreamStats s = streamer.stats();
    EXPECT_GT(scene->size(), 0u) << "camera " << i * 3;
    EXPECT_LE(s.host_high_water, options.host_bytes) << "camera " << i * 3;
    EXPECT_LE(scene->size(), s.budget);
    EXPECT_EQ(s.drawn_per_level[0], 0u) << "the finest level cannot be in memory";
  }
}

// A cap that holds the budget's Gaussians but not every chunk file they come from (a file holds
// many leaves' ranges): the cut keeps to the files that fit beside each other, so a still view
// settles and stops reading, and the drawn scene stays within the budget and the cap.
TEST(LodStream, AStillViewSettlesUnderACapThatHoldsTheBudgetButNotItsFiles) {
  const std::vector<Camera> cameras = test::load_demo_cameras();
  for (std::uint64_t cap_mib : {3, 4, 6}) {
    LodStreamOptions options;
    options.cut.max_error_px = 0.0f;
    options.host_bytes = cap_mib << 20;
    options.prefetch = false;
    LodStreamer streamer(read_lod_set(demo_set()), options);
    for (int index : {5, 20}) {
      const Camera camera = cameras[static_cast<std::size_t>(index)].resized(320, 180);
      std::uint64_t settled_read = 0;
      for (int frame = 0; frame < 16; ++frame) {
        if (frame == 8) settled_read = streamer.stats().bytes_read;
        const std::shared_ptr<const Scene> scene = streamer.update(camera);
        streamer.wait_until_idle();
        const LodStreamStats s = streamer.stats();
        EXPECT_LE(scene->size(), s.budget) << cap_mib << " MiB, camera " << index;
        EXPECT_LE(s.host_high_water, options.host_bytes) << cap_mib << " MiB, camera " << index;
      }
      const LodStreamStats s = streamer.stats();
      std::printf("%llu MiB, camera %d: %llu Gaussians drawn of a budget of %llu, %d leaves coarser than the cut, %d files resident, "
                  "%llu bytes read\n",
                  static_cast<unsigned long long>(cap_mib), index, static_cast<unsigned long long>(s.drawn_gaussians),
                  static_cast<unsigned long long>(s.budget), s.leaves_coarser, s.files_resident,
                  static_cast<unsigned long long>(s.bytes_read));
      EXPECT_EQ(s.bytes_read, settled_read) << cap_mib << " MiB, camera " << index << ": a still view kept reading";
      EXPECT_EQ(s.leaves_missing, 0) << cap_mib << " MiB, camera " << index;
      EXPECT_EQ(s.leaves_coarser, 0) << cap_mib << " MiB, camera " << index << ": the cut wants what cannot be in memory";
    }
  }
}

// The renderer's working memory counts against the cap: the budget leaves room for it.
TEST(LodStream, TheFramesWorkingMemoryIsInsideTheCap) {
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  options.host_bytes = 4u << 20;
  lod_frame_costs(BackendKind::cpu, 160, 90, 2, &options.host_frame, &options.device_frame);
  EXPECT_GT(options.host_frame.fixed, 160u * 90 * 12 - 1);  // the float image at least
  EXPECT_GT(options.host_frame.per_gaussian, 50u);
  LodStreamer streamer(read_lod_set(demo_set()), options);
  const std::uint64_t scene_bytes = 4 * (14 + 9);  // the demo scene is SH degree 1
  const Camera camera = test::load_demo_cameras()[5].resized(160, 90);
  streamer.update(camera);
  streamer.wait_until_idle();
  const std::shared_ptr<const Scene> scene = streamer.update(camera);
  const LodStreamStats s = streamer.stats();
  EXPECT_EQ(s.budget, (options.host_bytes / 2 - options.host_frame.fixed) / (2 * scene_bytes + options.host_frame.per_gaussian));
  EXPECT_GT(scene->size(), 0u);
  EXPECT_LE(s.host_high_water, options.host_bytes);
  EXPECT_GE(s.host_bytes, options.host_frame.fixed + scene->size() * (scene_bytes + options.host_frame.per_gaussian));
  EXPECT_GE(s.host_high_water, s.host_bytes) << "the high-water mark is below what is held now";
}

TEST(LodStream, ACorruptChunkIsOneLineAndTheRestKeepsRendering) {
  const std::string dir = fresh_folder("corrupt_" + std::to_string(getpid()));
  fs::copy(demo_set(), dir, fs::copy_options::recursive);
  LodSet set = read_lod_set(dir);
  const std::string broken = set.file_path(0);  // a level-0 chunk
  std::ofstream(broken, std::ios::trunc | std::ios::binary) << "ply\nformat binary_little_endian 1.0\nend_header\n";
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  LodStreamer streamer(std::move(set), options);
  const Camera camera = test::load_demo_cameras()[0].resized(160, 90);
  streamer.update(camera);
  streamer.wait_until_idle();
  const std::shared_ptr<const Scene> scene = streamer.update(camera);
  const std::vector<std::string> errors = streamer.take_errors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find(broken), std::string::npos) << errors[0];
  EXPECT_EQ(errors[0].find('\n'), std::string::npos);
  EXPECT_GT(scene->size(), 0u);
  EXPECT_GT(streamer.stats().leaves_coarser, 0) << "the broken chunk's leaves are drawn at a coarser level";
  EXPECT_EQ(streamer.stats().files_failed, 1);
}

// A leaf whose wanted and coarser levels are not in memory may be drawn at a finer level that
// is: only while the drawn scene stays within the budget (the broken coarsest chunks here
// leave many leaves nothing coarser).
TEST(LodStream, FinerStandInsKeepTheDrawnSceneWithinTheBudget) {
  const std::string dir = fresh_folder("no_coarsest_" + std::to_string(getpid()));
  fs::copy(demo_set(), dir, fs::copy_options::recursive);
  LodSet set = read_lod_set(dir);
  std::set<int> coarsest;
  for (const LodLeaf& leaf : set.leaves)
    for (auto r = leaf.levels.rbegin(); r != leaf.levels.rend(); ++r)
      if (r->file >= 0) {
        coarsest.insert(r->file);
        break;
      }
  for (int f : coarsest)
    std::ofstream(set.file_path(f), std::ios::trunc | std::ios::binary) << "ply\nformat binary_little_endian 1.0\nend_header\n";
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  options.cut.budget = 6000;
  options.prefetch = false;
  LodStreamer streamer(std::move(set), options);
  const std::vector<Camera> cameras = test::load_demo_cameras();
  std::uint64_t most = 0;
  int leaves_missing = 0;
  for (int index : {0, 3, 5, 20, 0}) {
    const Camera camera = cameras[static_cast<std::size_t>(index)].resized(160, 90);
    for (int frame = 0; frame < 3; ++frame) {
      most = std::max<std::uint64_t>(most, streamer.update(camera)->size());
      streamer.wait_until_idle();
      leaves_missing = std::max(leaves_missing, streamer.stats().leaves_missing);
    }
  }
  std::printf("most drawn %llu of a budget of %llu; leaves missing at most %d\n", static_cast<unsigned long long>(most),
              static_cast<unsigned long long>(options.cut.budget), leaves_missing);
  EXPECT_GT(most, 0u);
  EXPECT_LE(most, options.cut.budget);
  EXPECT_EQ(streamer.stats().files_failed, static_cast<int>(coarsest.size()));
}

// The level overlay of a cut's parts: every Gaussian takes its run's level colour, the geometry
// stays, each copy is keyed apart from its part and made once while cuts keep the part, and runs
// that do not fit the parts are refused.
TEST(LodTint, EachPartsGaussiansTakeTheirLevelsColourAndTheGeometryStays) {
  Scene scene = two_gaussians(0.5f, 1.0f);
  scene.append(two_gaussians(0.8f, 2.0f));
  scene.append(two_gaussians(0.3f, 3.0f));  // six Gaussians
  Scene with_sh;
  with_sh.sh_degree = 1;
  with_sh.positions = scene.positions;
  with_sh.scales = scene.scales;
  with_sh.rotations = scene.rotations;
  with_sh.opacities = scene.opacities;
  with_sh.sh_dc = scene.sh_dc;
  with_sh.sh_rest.assign(scene.size() * 9, 0.25f);
  const auto source = std::make_shared<const Scene>(with_sh);
  const std::vector<ScenePart> parts = {{10, source, 0, 2}, {20, source, 2, 3}, {30, source, 5, 1}};
  const std::vector<LodLevelRun> runs = {{0, 2}, {3, 3}, {0, 1}};
  TintedParts copies;
  const std::vector<ScenePart> tinted_parts = tint_parts_by_level(parts, runs, copies);
  ASSERT_EQ(tinted_parts.size(), parts.size());
  for (std::size_t p = 0; p < parts.size(); ++p) {
    EXPECT_EQ(tinted_parts[p].key, parts[p].key | kTintedPartKeyBit);
    EXPECT_EQ(tinted_parts[p].count, parts[p].count);
    EXPECT_NE(tinted_parts[p].source, source) << "the overlay changed the source scene";
  }
  EXPECT_EQ(copies.size(), 3u);
  const Scene tinted = *assemble_scene_parts(tinted_parts);
  ASSERT_EQ(tinted.size(), with_sh.size());
  EXPECT_EQ(tinted.sh_degree, 0);
  EXPECT_TRUE(tinted.sh_rest.empty());
  EXPECT_EQ(tinted.positions, with_sh.positions);
  EXPECT_EQ(tinted.scales, with_sh.scales);
  EXPECT_EQ(tinted.rotations, with_sh.rotations);
  EXPECT_EQ(tinted.opacities, with_sh.opacities);
  const int level_of[6] = {0, 0, 3, 3, 3, 0};
  for (std::size_t i = 0; i < tinted.size(); ++i) {
    const std::array<float, 3> want = lod_level_colour(level_of[i]);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(0.5 + model::kShC0 * tinted.sh_dc[i * 3 + k], want[static_cast<std::size_t>(k)], 1e-6) << "Gaussian " << i;
  }
  EXPECT_NE(lod_level_colour(0), lod_level_colour(3));
  EXPECT_EQ(lod_level_colour(lod_palette_size() + 2), lod_level_colour(2));
  EXPECT_EQ(source->sh_rest, std::vector<float>(scene.size() * 9, 0.25f));

  // The next cut keeps the second part and adds a fourth: the kept copy is the same one, the
  // dropped parts' copies leave the cache.
  const std::vector<ScenePart> next = {{20, source, 2, 3}, {40, source, 0, 1}};
  const std::vector<ScenePart> tinted_next = tint_parts_by_level(next, {{3, 3}, {1, 1}}, copies);
  EXPECT_EQ(tinted_next[0].source, tinted_parts[1].source);
  EXPECT_EQ(copies.size(), 2u);
  EXPECT_EQ(copies.count(10 | kTintedPartKeyBit), 0u);

  TintedParts fresh;
  EXPECT_THROW(tint_parts_by_level(parts, {{0, 2}, {1, 3}}, fresh), Error);          // do not cover the parts
  EXPECT_THROW(tint_parts_by_level(parts, {{0, 7}}, fresh), Error);                  // beyond them
  EXPECT_THROW(tint_parts_by_level(parts, {{0, 1}, {3, 4}, {0, 1}}, fresh), Error);  // a part across two runs
  EXPECT_THROW(tint_parts_by_level(tinted_parts, runs, fresh), Error);               // tinted twice
}

// A drawn scene's ranges become runs of levels by the chunk file each range is in.
TEST(LodTint, RangesBecomeRunsByTheirFilesLevel) {
  LodSet set;
  set.meta_path = "set/lod-meta.json";
  set.level_count = 2;
  set.files = {"0_0.ply", "1_0.ply", "0_1.ply"};
  set.leaves.resize(2);
  set.leaves[0].levels = {LodRange{0, 0, 10}, LodRange{1, 0, 5}};
  set.leaves[1].levels = {LodRange{2, 0, 8}, LodRange{1, 5, 4}};
  const std::vector<LodLevelRun> runs =
      lod_level_runs(set, {LodRange{0, 0, 10}, LodRange{2, 0, 8}, LodRange{1, 5, 4}, LodRange{1, 0, 5}});
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].level, 0);
  EXPECT_EQ(runs[0].count, 18u);
  EXPECT_EQ(runs[1].level, 1);
  EXPECT_EQ(runs[1].count, 9u);
  EXPECT_THROW(lod_level_runs(set, {LodRange{3, 0, 1}}), Error);
  set.leaves[1].levels[1].file = 0;  // a file of two levels
  EXPECT_THROW(lod_level_runs(set, {LodRange{0, 0, 10}}), Error);
}

// The streamer says which level each drawn Gaussian came from: the runs cover the drawn scene
// (the assembled one and the parts alike) and add up to its per-level counts; the overlay
// colours each run of the parts by its level.
TEST(LodStream, TheLevelRunsFollowTheDrawnScene) {
  const LodSet set = read_lod_set(demo_set());
  LodStreamOptions options;
  options.cut.max_error_px = 8.0f;  // at 320x180: all four levels of the demo set
  LodStreamer streamer(set, options);
  const Camera camera = test::load_demo_cameras()[3].resized(320, 180);
  streamer.update(camera);
  streamer.wait_until_idle();
  const std::shared_ptr<const Scene> scene = streamer.update(camera);
  const std::vector<LodLevelRun> runs = lod_level_runs(set, streamer.drawn_ranges());
  std::vector<std::uint64_t> per_level(static_cast<std::size_t>(set.level_count), 0);
  std::uint64_t total = 0;
  for (const LodLevelRun& r : runs) {
    ASSERT_GE(r.level, 0);
    ASSERT_LT(r.level, set.level_count);
    per_level[static_cast<std::size_t>(r.level)] += r.count;
    total += r.count;
  }
  EXPECT_EQ(total, scene->size());
  EXPECT_EQ(per_level, streamer.stats().drawn_per_level);
  EXPECT_GE(std::count_if(per_level.begin(), per_level.end(), [](std::uint64_t n) { return n > 0; }), 2)
      << "the view should mix levels at 8 px";
  const std::vector<ScenePart> parts = streamer.update_parts(camera, nullptr);
  const std::vector<LodLevelRun> part_runs = lod_level_runs(set, streamer.drawn_ranges());
  ASSERT_EQ(part_runs.size(), runs.size());
  TintedParts copies;
  const Scene tinted = *assemble_scene_parts(tint_parts_by_level(parts, part_runs, copies));
  ASSERT_EQ(tinted.size(), scene->size());
  std::size_t at = 0;
  for (const LodLevelRun& r : part_runs) {
    const std::array<float, 3> want = lod_level_colour(r.level);
    for (std::uint64_t i = 0; i < r.count; ++i, ++at)
      ASSERT_NEAR(0.5 + model::kShC0 * tinted.sh_dc[at * 3], want[0], 1e-6) << "Gaussian " << at;
  }
  EXPECT_EQ(tinted.positions, scene->positions);
}

// A renderer that counts what it is handed and draws with the CPU backend.
class HandOverCounter final : public Renderer {
 public:
  std::string name() const override { return "counting cpu"; }
  void set_scene(std::shared_ptr<const Scene> scene) override {
    ++scenes;
    m_cpu->set_scene(std::move(scene));
  }
  void set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t resident) override {
    if (refuse) throw Error("refused");
    ++part_sets;
    last_parts = parts;
    resident_bytes = resident;
    Renderer::set_scene_parts(parts, resident);  // assembled, through set_scene
  }
  void render(const Camera& camera, const RenderOptions& options, Image& out, FrameStats* stats) override {
    m_cpu->render(camera, options, out, stats);
  }
  int scenes = 0, part_sets = 0;
  bool refuse = false;
  std::vector<ScenePart> last_parts;
  std::uint64_t resident_bytes = 0;

 private:
  std::unique_ptr<Renderer> m_cpu = make_cpu_renderer(2);
};

// The feed hands the cut over as parts, under the streamer's GPU cap, only when it changed (or
// when asked to, or the overlay changed); never an empty cut; a refused hand-over is tried again;
// the frame is the assembled cut's; with the overlay the parts are the tinted copies.
TEST(LodFeed, HandsTheCutOverAsPartsWhenItChanges) {
  const LodSet set = read_lod_set(demo_set());
  LodStreamOptions options;
  options.cut.max_error_px = 8.0f;
  options.device_bytes = 64u << 20;
  options.parts_on_device = true;
  LodStreamer streamer(set, options);
  LodStreamer reference(set, options);
  LodCutFeed feed(streamer);
  HandOverCounter renderer;
  const Camera camera = test::load_demo_cameras()[3].resized(320, 180);
  EXPECT_FALSE(feed.update(camera, renderer)) << "nothing is in memory before the first update";
  EXPECT_EQ(feed.cut_gaussians(), 0u);
  EXPECT_EQ(renderer.part_sets, 0);
  streamer.wait_until_idle();
  ASSERT_TRUE(feed.update(camera, renderer));
  EXPECT_EQ(renderer.part_sets, 1);
  EXPECT_EQ(renderer.resident_bytes, streamer.device_resident_bytes());
  EXPECT_GT(renderer.resident_bytes, 0u);
  EXPECT_EQ(feed.stats().hand_overs, 1u);
  EXPECT_EQ(feed.stats().parts, renderer.last_parts.size());
  EXPECT_EQ(feed.stats().new_parts, renderer.last_parts.size());
  EXPECT_EQ(feed.handed_parts().size(), renderer.last_parts.size());
  EXPECT_EQ(feed.cut_gaussians(), scene_parts_size(renderer.last_parts));

  reference.update(camera);
  reference.wait_until_idle();
  const std::shared_ptr<const Scene> whole = reference.update(camera);
  auto cpu = make_cpu_renderer(2);
  cpu->set_scene(whole);
  Image from_parts, from_scene;
  renderer.render(camera, RenderOptions{}, from_parts, nullptr);
  cpu->render(camera, RenderOptions{}, from_scene, nullptr);
  EXPECT_EQ(from_parts.rgb, from_scene.rgb);

  EXPECT_FALSE(feed.update(camera, renderer)) << "the same cut was handed over again";
  feed.hand_over_again();
  EXPECT_TRUE(feed.update(camera, renderer));
  EXPECT_EQ(feed.stats().new_parts, 0u);
  EXPECT_EQ(renderer.part_sets, 2);

  feed.set_level_overlay(true);
  ASSERT_TRUE(feed.update(camera, renderer));
  for (const ScenePart& p : renderer.last_parts) ASSERT_NE(p.key & kTintedPartKeyBit, 0u);
  EXPECT_EQ(feed.stats().new_parts, renderer.last_parts.size()) << "a tinted part shares a key with an untinted one";
  const std::vector<LodLevelRun> runs = lod_level_runs(set, streamer.drawn_ranges());
  const std::shared_ptr<const Scene> tinted = assemble_scene_parts(renderer.last_parts);
  std::size_t at = 0;
  for (const LodLevelRun& r : runs)
    for (std::uint64_t i = 0; i < r.count; ++i, ++at)
      ASSERT_NEAR(0.5 + model::kShC0 * tinted->sh_dc[at * 3 + 1], lod_level_colour(r.level)[1], 1e-6) << "Gaussian " << at;
  EXPECT_EQ(at, tinted->size());
  EXPECT_FALSE(feed.update(camera, renderer));

  feed.set_level_overlay(false);
  renderer.refuse = true;
  EXPECT_THROW(feed.update(camera, renderer), Error);
  renderer.refuse = false;
  ASSERT_TRUE(feed.update(camera, renderer)) << "a refused cut was not handed over again";
  for (const ScenePart& p : renderer.last_parts) ASSERT_EQ(p.key & kTintedPartKeyBit, 0u);
  EXPECT_EQ(renderer.part_sets, 4);
  EXPECT_EQ(feed.stats().hand_overs, 4u);
  EXPECT_EQ(renderer.scenes, 4) << "the default set_scene_parts assembles the parts for set_scene";
}

// The host's count holds the scene a host renderer assembles from the parts, and none where the
// renderer keeps them on the GPU. No cap: the same chunks in memory, whatever the loads' timing.
// The level overlay's tinted copies of the drawn parts count against the host cap: with the
// overlay on, the budget makes room for a third copy of the drawn scene (the one drawn, the
// next, the tinted one), the high-water mark stays inside the cap, and it is given back when
// the overlay goes off.
TEST(LodFeed, TheOverlaysCopiesCountAgainstTheHostCap) {
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  options.host_bytes = 4u << 20;
  const std::uint64_t scene_bytes = 4 * (14 + 9);  // per Gaussian: the demo scene is SH degree 1
  const std::uint64_t plain_budget = (options.host_bytes / 2) / (2 * scene_bytes);
  const std::uint64_t overlay_budget = (options.host_bytes / 2) / (3 * scene_bytes);
  const Camera camera = test::load_demo_cameras()[5].resized(160, 90);
  auto renderer = make_cpu_renderer(2);
  LodStreamer streamer(read_lod_set(demo_set()), options);
  LodCutFeed feed(streamer);
  feed.set_level_overlay(true);
  for (int frame = 0; frame < 4; ++frame) {
    feed.update(camera, *renderer);
    streamer.wait_until_idle();
  }
  LodStreamStats s = streamer.stats();
  EXPECT_EQ(s.budget, overlay_budget);
  EXPECT_GT(s.drawn_gaussians, 0u);
  EXPECT_LE(s.drawn_gaussians, s.budget);
  EXPECT_LE(s.host_high_water, options.host_bytes);
  EXPECT_GE(s.host_bytes, s.drawn_gaussians * 2 * scene_bytes) << "the copies are not counted";
  feed.set_level_overlay(false);
  feed.update(camera, *renderer);
  EXPECT_EQ(streamer.stats().budget, plain_budget);
}

TEST(LodStream, TheHostCapCountsTheScenePartsAreAssembledInto) {
  const std::uint64_t scene_bytes = 4 * (14 + 9);  // the demo scene is SH degree 1
  const Camera camera = test::load_demo_cameras()[5].resized(160, 90);
  std::uint64_t held[2] = {0, 0}, drawn_of[2] = {0, 0};
  for (const bool on_device : {false, true}) {
    LodStreamOptions options;
    options.cut.max_error_px = 0.0f;
    options.parts_on_device = on_device;
    lod_frame_costs(BackendKind::cpu, 160, 90, 2, &options.host_frame, &options.device_frame);
    LodStreamer streamer(read_lod_set(demo_set()), options);
    streamer.update_parts(camera, nullptr);
    streamer.wait_until_idle();
    const std::uint64_t drawn = scene_parts_size(streamer.update_parts(camera, nullptr));
    const LodStreamStats s = streamer.stats();
    ASSERT_GT(drawn, 0u);
    EXPECT_GE(s.host_bytes, options.host_frame.fixed + drawn * options.host_frame.per_gaussian);
    EXPECT_GE(s.host_high_water, s.host_bytes) << "the high-water mark is below what is held now";
    held[on_device] = s.host_bytes;
    drawn_of[on_device] = drawn;
  }
  ASSERT_EQ(drawn_of[0], drawn_of[1]);
  EXPECT_EQ(held[0] - held[1], drawn_of[0] * scene_bytes) << "the assembled scene is not what differs";
}

// A set built with SOG chunks (L_K/meta.json, as PlayCanvas's tools write them) streams the
// frame of the same set built with PLY chunks, within SOG's quantisation.
TEST(LodBuild, SogChunksStreamThePlySetsFrameWithinQuantisation) {
  const std::string dir = fresh_folder("sog_chunks_" + std::to_string(getpid()));
  LodBuildOptions options;
  options.leaf_gaussians = 2048;
  options.file_gaussians = 8192;
  options.chunk_format = LodChunkFormat::sog;
  const LodBuildReport report = build_lod_set(demo_scene_path(), dir, options);
  const LodSet sog = read_lod_set(dir), ply = read_lod_set(demo_set());
  ASSERT_EQ(sog.files.size(), ply.files.size());
  for (const std::string& f : sog.files) EXPECT_EQ(f.substr(f.size() - 10), "/meta.json") << f;
  std::uint64_t ply_bytes = 0;
  for (std::size_t f = 0; f < ply.files.size(); ++f) ply_bytes += fs::file_size(ply.file_path(static_cast<int>(f)));
  std::printf("SOG chunks: %.2f MB, PLY chunks: %.2f MB\n", double(report.bytes_written) / 1e6, double(ply_bytes) / 1e6);
  EXPECT_LT(report.bytes_written, ply_bytes / 2);
  LodStreamOptions stream;
  stream.cut.max_error_px = 8.0f;  // every level's chunks drawn
  LodStreamer from_sog(sog, stream), from_ply(ply, stream);
  auto renderer = make_cpu_renderer(2);
  for (int index : {3, 17}) {
    const Camera camera = test::load_demo_cameras()[static_cast<std::size_t>(index)].resized(320, 180);
    Image images[2];
    LodStreamer* streamers[2] = {&from_sog, &from_ply};
    for (int k = 0; k < 2; ++k) {
      streamers[k]->update(camera);
      streamers[k]->wait_until_idle();
      renderer->set_scene(streamers[k]->update(camera));
      renderer->render(camera, RenderOptions{}, images[k], nullptr);
    }
    EXPECT_EQ(from_sog.stats().drawn_per_level, from_ply.stats().drawn_per_level) << "camera " << index;
    EXPECT_TRUE(from_sog.take_errors().empty());
    const ImageDifference d = compare_images(images[0], images[1]);
    std::printf("camera %d: SOG chunks vs PLY chunks %.1f dB\n", index, d.psnr_db);
    EXPECT_GT(d.psnr_db, 30.0) << "camera " << index;
  }
  fs::remove_all(dir);
}

// A set written by PlayCanvas's tools (SOG chunks) streams the same way.
TEST(LodStream, StreamsAPlayCanvasSogSet) {
  const std::string sog = test::shared_format_file("playbot_sog");
  if (sog.empty()) GTEST_SKIP() << "../shared/scenes/formats/playbot_sog is absent";
  LodStreamOptions options;
  options.cut.max_error_px = 2.0f;
  options.cut.budget = 200000;
  LodStreamer streamer(read_lod_set(sog), options);
  const Camera camera = test::load_shared_cameras("pc_playbot").empty()
                            ? Camera{}
                            : test::load_shared_cameras("pc_playbot")[0].resized(320, 180);
  if (camera.width == 0) GTEST_SKIP() << "pc_playbot's cameras are absent";
  streamer.update(camera);
  streamer.wait_until_idle();
  const std::shared_ptr<const Scene> scene = streamer.update(camera);
  EXPECT_GT(scene->size(), 0u);
  EXPECT_LE(scene->size(), 200000u);
  EXPECT_TRUE(streamer.take_errors().empty());
}

}  // namespace
}  // namespace flashgs
