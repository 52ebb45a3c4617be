// Helpers shared by the test suites (see test_support.h).
#include "test_support.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <map>
#include <mutex>
#include <numeric>
#include <random>

#include <sys/resource.h>

#include "flashgs/demo_scene.h"
#include "flashgs/io.h"
#include "flashgs/netpbm.h"

namespace flashgs::test {

double children_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_CHILDREN, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

std::string shared_scene_dir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(FLASHGS_SHARED_SCENES) / name;
  return std::filesystem::exists(dir / "point_cloud.ply") ? dir.string() : std::string();
}

std::string shared_format_file(const std::string& file) {
  const std::filesystem::path path = std::filesystem::path(FLASHGS_SHARED_SCENES) / "formats" / file;
  return std::filesystem::exists(path) ? path.string() : std::string();
}

std::vector<SplatKernel> kernels() { return {std::begin(kTrainerKernels), std::end(kTrainerKernels)}; }

std::vector<std::string> shared_scene_names() {
  std::vector<std::string> names;
  for (const char* name : {"pc_biker", "pc_guitar", "v3dg_donut", "kacytran_try", "pc_playbot"})
    if (!shared_scene_dir(name).empty()) names.push_back(name);
  return names;
}

std::shared_ptr<const Scene> load_shared_scene(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const Scene>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[name];
  if (!slot) slot = std::make_shared<Scene>(load_ply(shared_scene_dir(name) + "/point_cloud.ply"));
  return slot;
}

std::vector<Camera> load_shared_cameras(const std::string& name) {
  return load_cameras(shared_scene_dir(name) + "/cameras.json");
}

std::shared_ptr<const Scene> load_demo_scene() {
  static std::shared_ptr<const Scene> scene =
      std::make_shared<Scene>(load_ply(demo_scene_path()));
  return scene;
}

std::vector<Camera> load_demo_cameras() {
  return load_cameras(demo_cameras_path());
}

Scene permuted(const Scene& scene, const std::vector<std::uint32_t>& order) {
  Scene out;
  out.sh_degree = scene.sh_degree;
  out.reserve(order.size());
  const std::size_t rest = static_cast<std::size_t>(scene.sh_rest_per_gaussian());
  auto take = [](std::vector<float>& to, const std::vector<float>& from, std::size_t i, std::size_t width) {
    to.insert(to.end(), from.begin() + i * width, from.begin() + (i + 1) * width);
  };
  for (std::uint32_t i : order) {
    take(out.positions, scene.positions, i, 3);
    take(out.scales, scene.scales, i, 3);
    take(out.rotations, scene.rotations, i, 4);
    take(out.opacities, scene.opacities, i, 1);
    take(out.sh_dc, scene.sh_dc, i, 3);
    if (rest) take(out.sh_rest, scene.sh_rest, i, rest);
  }
  return out;
}

std::vector<std::uint32_t> random_order(std::size_t n, unsigned seed) {
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), std::mt19937(seed));
  return order;
}

void dump_images(const std::string& stem, const Image& expected, const Image& actual) {
  std::filesystem::create_directories(FLASHGS_TEST_OUTPUT_DIR);
  const std::string base = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/" + stem;
  write_pfm(expected, base + "_expected.pfm");
  write_pfm(actual, base + "_actual.pfm");
  Image diff = expected;
  for (std::size_t i = 0; i < diff.rgb.size() && i < actual.rgb.size(); ++i)
    diff.rgb[i] = std::abs(expected.rgb[i] - actual.rgb[i]) * 10.0f;
  write_pfm(diff, base + "_diff_x10.pfm");
}

double fraction_over(const Image& a, const Image& b, double tolerance) {
  std::size_t over = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) over += std::abs(double(a.rgb[i]) - b.rgb[i]) > tolerance;
  return a.rgb.empty() ? 0.0 : double(over) / double(a.rgb.size());
}

}  // namespace flashgs::test
