// Instanced LOD sets: an instance moves positions, orientations and view-dependent colour
// exactly; a city of instances streams the frame of its Gaussians moved for real; each
// instance's copy of a chunk is loaded and keyed apart; malformed instances are one line.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <unistd.h>

#include <gtest/gtest.h>

#include "flashgs/compressed_formats.h"
#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/gaussian_math.h"
#include "flashgs/io.h"
#include "flashgs/lod_build.h"
#include "flashgs/lod_city.h"
#include "flashgs/lod_stream.h"
#include "flashgs/renderer.h"
#include "flashgs/rotation.h"
#include "test_support.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

// Each test runs in its own process, several at once: each has its own folders, removed at exit.
struct ProcessFolders {
  std::vector<std::string> paths;
  ~ProcessFolders() {
    std::error_code ignored;
    for (const std::string& p : paths) fs::remove_all(p, ignored);
  }
};

std::string scratch(const std::string& name) {
  static ProcessFolders folders;
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/lod_instances_" + name + "_" + std::to_string(getpid());
  fs::remove_all(dir);
  folders.paths.push_back(dir);
  return dir;
}

// The demo scene's set (y up), built once per process.
const std::string& base_set() {
  static const std::string folder = [] {
    const std::string out = scratch("base");
    LodBuildOptions options;
    options.leaf_gaussians = 4096;
    options.file_gaussians = 16384;
    build_lod_set(demo_scene_path(), out, options);
    return out;
  }();
  return folder;
}

std::string city_of(int blocks, const std::string& name, bool materialize = false,
                    LodChunkFormat format = LodChunkFormat::ply) {
  const std::string out = scratch(name);
  LodCityOptions options;
  options.blocks = blocks;
  options.up = "+y";
  options.path_cameras = 6;
  options.width = 320;
  options.height = 180;
  options.materialize = materialize;
  options.chunk_format = format;
  write_lod_city(base_set(), out, options);
  return out;
}

// The city's overview: the last camera of its path, which sees every block.
Camera overview(const std::string& city) {
  return load_cameras(city + "/cameras.json").back();
}

TEST(LodInstance, MovesPositionsOrientationsScalesAndViewDependentColour) {
  Scene s;
  s.sh_degree = 3;
  s.positions = {0.3f, -0.2f, 1.1f, -2.0f, 0.5f, 0.25f};
  s.scales = {0.2f, 0.05f, 0.1f, 0.01f, 0.3f, 0.02f};
  s.rotations = {0.9238795f, 0.3826834f, 0, 0, 0.5f, 0.5f, 0.5f, 0.5f};
  s.opacities = {0.7f, 0.3f};
  s.sh_dc = {0.1f, 0.2f, 0.3f, -0.1f, 0.0f, 0.4f};
  for (int i = 0; i < 2 * 45; ++i) s.sh_rest.push_back(0.3f * std::sin(1.7f * static_cast<float>(i) + 0.4f));
  LodInstance instance;
  const double q[4] = {0.8, 0.1, -0.5, 0.3};
  const double n = std::sqrt(0.64 + 0.01 + 0.25 + 0.09);
  for (int k = 0; k < 4; ++k) instance.rotation[static_cast<std::size_t>(k)] = q[k] / n;
  instance.translation = {10.0, -3.0, 0.5};
  instance.scale = 2.0;
  Scene moved = s;
  transform_gaussians(moved, instance);
  double r[9];
  matrix_from_quaternion(instance.rotation.data(), r);
  const float camera[3] = {4.0f, 1.0f, -3.0f};
  float moved_camera[3];
  for (int row = 0; row < 3; ++row)
    moved_camera[row] = static_cast<float>(2.0 * (r[row * 3] * camera[0] + r[row * 3 + 1] * camera[1] + r[row * 3 + 2] * camera[2]) +
                                           instance.translation[static_cast<std::size_t>(row)]);
  for (std::size_t i = 0; i < 2; ++i) {
    const float* p = &s.positions[i * 3];
    for (int row = 0; row < 3; ++row)
      EXPECT_NEAR(moved.positions[i * 3 + static_cast<std::size_t>(row)],
                  2.0 * (r[row * 3] * p[0] + r[row * 3 + 1] * p[1] + r[row * 3 + 2] * p[2]) + instance.translation[static_cast<std::size_t>(row)],
                  1e-5);
    // The covariance's axes: R times the old rotation's columns, scales doubled.
    double before[9], after[9];
    const double qb[4] = {s.rotations[i * 4], s.rotations[i * 4 + 1], s.rotations[i * 4 + 2], s.rotations[i * 4 + 3]};
    const double qa[4] = {moved.rotations[i * 4], moved.rotations[i * 4 + 1], moved.rotations[i * 4 + 2], moved.rotations[i * 4 + 3]};
    matrix_from_quaternion(qb, before);
    matrix_from_quaternion(qa, after);
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col)
        EXPECT_NEAR(after[row * 3 + col],
                    r[row * 3] * before[col] + r[row * 3 + 1] * before[3 + col] + r[row * 3 + 2] * before[6 + col], 1e-6);
    for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(moved.scales[i * 3 + static_cast<std::size_t>(k)], 2.0f * s.scales[i * 3 + static_cast<std::size_t>(k)]);
    // Seen from the moved camera, the moved Gaussian has the colour it had (every SH band).
    float rgb[3], moved_rgb[3];
    gm::sh_to_rgb<3>(camera, p, &s.sh_dc[i * 3], &s.sh_rest[i * 45], rgb);
    gm::sh_to_rgb<3>(moved_camera, &moved.positions[i * 3], &moved.sh_dc[i * 3], &moved.sh_rest[i * 45], moved_rgb);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(moved_rgb[ch], rgb[ch], 1e-5) << "Gaussian " << i << " channel " << ch;
    // ... which differs from the unrotated bands' colour there: the bands did turn.
    float unturned[3];
    gm::sh_to_rgb<3>(moved_camera, &moved.positions[i * 3], &s.sh_dc[i * 3], &s.sh_rest[i * 45], unturned);
    EXPECT_GT(std::fabs(unturned[0] - rgb[0]) + std::fabs(unturned[1] - rgb[1]) + std::fabs(unturned[2] - rgb[2]), 1e-3);
  }
  // The moved bound holds every moved corner.
  LodBox box;
  box.min = {-1, -2, -3};
  box.max = {1, 2, 3};
  const LodBox moved_box = transformed_bound(box, instance);
  for (int corner = 0; corner < 8; ++corner) {
    const double v[3] = {corner & 1 ? 1.0 : -1.0, corner & 2 ? 2.0 : -2.0, corner & 4 ? 3.0 : -3.0};
    for (int row = 0; row < 3; ++row) {
      const double p = 2.0 * (r[row * 3] * v[0] + r[row * 3 + 1] * v[1] + r[row * 3 + 2] * v[2]) + instance.translation[static_cast<std::size_t>(row)];
      EXPECT_GE(p, moved_box.min[static_cast<std::size_t>(row)] - 1e-4);
      EXPECT_LE(p, moved_box.max[static_cast<std::size_t>(row)] + 1e-4);
    }
  }
}

// At full detail with every leaf in view, the streamed city is the base's chunks moved block by
// block: the same Gaussians in the same order, so the same bytes in the frame.
TEST(LodInstance, ACityStreamsTheFrameOfItsGaussiansMovedForReal) {
  const std::string city = city_of(3, "stream");
  const LodSet set = read_lod_set(city);
  const LodSet base = read_lod_set(base_set());
  ASSERT_EQ(set.instances.size(), 3u);
  ASSERT_EQ(set.leaves.size(), 3 * base.leaves.size());
  EXPECT_EQ(set.gaussians(0), 3 * base.gaussians(0));
  // Each leaf's bound is its base leaf's moved by its block (the cut tests these), and reads back
  // from the meta's short decimals as the same floats.
  for (std::size_t i = 0; i < set.leaves.size(); ++i) {
    const LodBox expected = transformed_bound(base.leaves[i % base.leaves.size()].bound,
                                              set.instances[static_cast<std::size_t>(set.leaves[i].instance)]);
    EXPECT_EQ(set.leaves[i].bound.min, expected.min) << "leaf " << i;
    EXPECT_EQ(set.leaves[i].bound.max, expected.max) << "leaf " << i;
  }
  const Camera camera = overview(city);
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  LodStreamer streamer(set, options);
  streamer.update(camera);
  streamer.wait_until_idle();
  const std::shared_ptr<const Scene> streamed = streamer.update(camera);
  ASSERT_EQ(streamer.stats().leaves_drawn, static_cast<int>(set.leaves.size())) << "the overview sees every leaf";
  EXPECT_EQ(streamer.stats().leaves_coarser, 0);

  // The reference: the base's level-0 chunks read plainly, each leaf's range moved by its block.
  std::map<std::string, Scene> chunks;
  Scene reference;
  for (const LodLeaf& leaf : set.leaves) {
    const LodRange& range = leaf.levels[0];
    const std::string name = fs::path(set.files[static_cast<std::size_t>(range.file)]).filename().string();
    if (!chunks.count(name)) chunks[name] = read_lod_chunk(base.folder + "/" + name);
    Scene part;
    part.sh_degree = chunks[name].sh_degree;
    part.append_range(chunks[name], range.offset, range.count);
    transform_gaussians(part, set.instances[static_cast<std::size_t>(leaf.instance)]);
    if (reference.size() == 0) reference.sh_degree = part.sh_degree, reference.trained_kernel = chunks[name].trained_kernel;
    reference.append(part);
  }
  ASSERT_EQ(streamed->size(), reference.size());
  EXPECT_EQ(streamed->positions, reference.positions);
  EXPECT_EQ(streamed->sh_rest, reference.sh_rest);
  auto renderer = make_cpu_renderer(2);
  Image a, b;
  renderer->set_scene(streamed);
  renderer->render(camera, RenderOptions{}, a, nullptr);
  renderer->set_scene(std::make_shared<Scene>(reference));
  renderer->render(camera, RenderOptions{}, b, nullptr);
  EXPECT_EQ(a.rgb, b.rgb);
  // read_sog_lod (what --psnr-every compares with) reads the same level 0, moved.
  const Scene whole = read_sog_lod(set.meta_path, 0);
  EXPECT_EQ(whole.size(), reference.size());
}

// Two instances of one chunk range are two chunks in the host cache and two part keys.
TEST(LodInstance, EachInstanceOfAChunkIsLoadedAndKeyedApart) {
  const std::string city = city_of(2, "keys");
  const LodSet set = read_lod_set(city);
  const LodSet base = read_lod_set(base_set());
  ASSERT_EQ(set.files.size(), 2 * base.files.size());
  LodStreamOptions options;
  options.cut.max_error_px = 0.0f;
  LodStreamer streamer(set, options);
  const Camera camera = overview(city);
  bool changed = false;
  streamer.update_parts(camera, &changed);
  streamer.wait_until_idle();
  const std::vector<ScenePart> parts = streamer.update_parts(camera, &changed);
  // Per range of a base chunk file: the keys and the chunks in memory its parts come from.
  std::map<std::pair<std::string, std::size_t>, std::set<std::uint64_t>> keys_of_range;
  std::map<std::pair<std::string, std::size_t>, std::set<const Scene*>> chunks_of_range;
  std::set<std::uint64_t> keys;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const LodRange& r = streamer.drawn_ranges()[i];
    const auto range = std::make_pair(set.files[static_cast<std::size_t>(r.file)], parts[i].first);
    keys_of_range[range].insert(parts[i].key);
    chunks_of_range[range].insert(parts[i].source.get());
    keys.insert(parts[i].key);
  }
  EXPECT_EQ(keys.size(), parts.size()) << "no two parts share a key";
  ASSERT_FALSE(keys_of_range.empty());
  for (const auto& [range, k] : keys_of_range) EXPECT_EQ(k.size(), 2u) << range.first << " at " << range.second;
  for (const auto& [range, c] : chunks_of_range) EXPECT_EQ(c.size(), 2u) << range.first << " at " << range.second;
}

TEST(LodInstance, AMaterializedCityIsAPlainSetOfTheSameGaussians) {
  const std::string instanced = city_of(2, "instanced");
  const std::string plain = city_of(2, "plain", true);
  std::ifstream meta(plain + "/lod-meta.json");
  const std::string text((std::istreambuf_iterator<char>(meta)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("instance"), std::string::npos);
  EXPECT_FALSE(fs::exists(plain + "/base"));
  const LodSet set = read_lod_set(plain);
  EXPECT_TRUE(set.instances.empty());
  for (int level = 0; level < set.level_count; ++level) check_lod_ranges(set, level);
  const Scene a = read_sog_lod(instanced + "/lod-meta.json", 0), b = read_sog_lod(plain + "/lod-meta.json", 0);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i) ASSERT_NEAR(a.positions[i], b.positions[i], 1e-5f) << i;
  // PLY keeps scales as logarithms and opacities as logits: a float round trip, not bytes.
  auto renderer = make_cpu_renderer(2);
  const Camera camera = overview(plain);
  Image x, y;
  renderer->set_scene(std::make_shared<Scene>(a));
  renderer->render(camera, RenderOptions{}, x, nullptr);
  renderer->set_scene(std::make_shared<Scene>(b));
  renderer->render(camera, RenderOptions{}, y, nullptr);
  EXPECT_GT(compare_images(x, y).psnr_db, 80.0);
  // SOG chunks (what PlayCanvas's viewers stream) hold the same Gaussians, quantised.
  const std::string sog = city_of(2, "sog", true, LodChunkFormat::sog);
  EXPECT_TRUE(fs::exists(sog + "/chunk-0/meta.json"));
  const Scene c = read_sog_lod(sog + "/lod-meta.json", 0);
  ASSERT_EQ(c.size(), a.size());
  renderer->set_scene(std::make_shared<Scene>(c));
  renderer->render(camera, RenderOptions{}, y, nullptr);
  EXPECT_GT(compare_images(x, y).psnr_db, 25.0);
}

// A set whose meta is `tree` with `instances` (JSON text) beside the base's first chunk.
std::string meta_with(const std::string& name, const std::string& instances, const std::string& leaf_extra) {
  const std::string dir = scratch(name);
  fs::create_directories(dir);
  const LodSet base = read_lod_set(base_set());
  fs::copy_file(base.file_path(base.leaves[0].levels[0].file), dir + "/chunk.ply");
  std::ofstream out(dir + "/lod-meta.json");
  out << "{\"lodLevels\": 1, \"filenames\": [\"chunk.ply\"], " << instances
      << "\"tree\": {\"bound\": {\"min\": [0,0,0], \"max\": [1,1,1]}, " << leaf_extra
      << "\"lods\": {\"0\": {\"file\": 0, \"offset\": 0, \"count\": 1}}}}";
  return dir + "/lod-meta.json";
}

TEST(LodInstance, MalformedInstancesAreOneLineNamingTheFile) {
  const std::string good = "\"instances\": [{\"rotation\": [1, 0, 0, 0], \"translation\": [1, 2, 3]}], ";
  EXPECT_EQ(read_lod_set(meta_with("good", good, "\"instance\": 0, ")).instances.size(), 1u);
  const struct {
    const char* name;
    std::string instances, leaf, says;
  } cases[] = {
      {"non_unit", "\"instances\": [{\"rotation\": [2, 0, 0, 0], \"translation\": [0, 0, 0]}], ", "\"instance\": 0, ",
       "instances[0]: its rotation is not a unit quaternion"},
      {"short", "\"instances\": [{\"rotation\": [1, 0, 0], \"translation\": [0, 0, 0]}], ", "",
       "instances[0].rotation must be an array of 4 numbers"},
      {"infinite", "\"instances\": [{\"rotation\": [1, 0, 0, 0], \"translation\": [1e999, 0, 0]}], ", "",
       "not valid JSON"},  // JSON has no infinity or NaN: an overflowing number is refused by the parser
      {"text", "\"instances\": [{\"rotation\": [1, 0, 0, 0], \"translation\": [\"a\", 0, 0]}], ", "",
       "instances[0].translation holds a value that is not a finite number"},
      {"scale", "\"instances\": [{\"rotation\": [1, 0, 0, 0], \"translation\": [0, 0, 0], \"scale\": -1}], ", "",
       "instances[0]: its scale is not a number in 1e-6..1e6"},
      {"far", "\"instances\": [{\"rotation\": [1, 0, 0, 0], \"translation\": [0, 1e13, 0]}], ", "",
       "instances[0]: its translation holds a value that is not a number within +-1e12"},
      {"out_of_range", good, "\"instance\": 1, ", "a leaf's instance index must be a whole number in 0..0"},
      {"negative", good, "\"instance\": -1, ", "a leaf's instance index must be a whole number in 0..0"},
      {"no_list", "", "\"instance\": 0, ", "a tree leaf names an instance but the set has no \"instances\""},
      {"empty_list", "\"instances\": [], ", "", "\"instances\" must be an array of 1.."},
  };
  for (const auto& c : cases) {
    const std::string path = meta_with(c.name, c.instances, c.leaf);
    try {
      read_lod_set(path);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
      EXPECT_NE(what.find(c.says), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

// A base named by its bare lod-meta.json (its folder is the working directory) is linked too.
TEST(LodCity, ABaseInTheWorkingFolderIsLinkedRelatively) {
  const std::string out = fs::absolute(scratch("from_here")).string();
  const fs::path before = fs::current_path();
  fs::current_path(base_set());
  LodCityOptions options;
  options.blocks = 2;
  options.up = "+y";
  EXPECT_NO_THROW(write_lod_city("lod-meta.json", out, options));
  fs::current_path(before);
  EXPECT_TRUE(fs::is_symlink(out + "/base"));
  EXPECT_FALSE(fs::read_symlink(out + "/base").is_absolute());
  const LodSet set = read_lod_set(out);
  EXPECT_EQ(read_sog_lod(set.meta_path, set.level_count - 1).size(), set.gaussians(set.level_count - 1));
}

TEST(LodCity, RefusesAnInstancedBaseABadUpAxisAndAFolderInUse) {
  const std::string city = city_of(2, "refusals");
  LodCityOptions options;
  options.blocks = 2;
  const std::string out = scratch("refused");
  EXPECT_THROW(write_lod_city(city, out, options), Error);
  options.up = "up";
  try {
    write_lod_city(base_set(), out, options);
    ADD_FAILURE() << "an unknown up axis was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("up axis \"up\""), std::string::npos) << e.what();
  }
  options.up = "+y";
  EXPECT_THROW(write_lod_city(base_set(), city, options), Error);  // not empty
  EXPECT_FALSE(fs::exists(out + "/lod-meta.json"));
}

}  // namespace
}  // namespace flashgs
