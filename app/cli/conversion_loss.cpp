// Measuring and printing what `flashgs convert` loses (see conversion_loss.h).
#include "conversion_loss.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>

#include "flashgs/generators.h"
#include "flashgs/image.h"
#include "flashgs/io.h"
#include "flashgs/options.h"
#include "flashgs/renderer.h"

namespace flashgs::cli {
namespace {

constexpr int kViews = 3;

// Accumulates |a - b| over one attribute.
struct ErrorSum {
  double max = 0, sum = 0;
  std::size_t count = 0;
  void add(double e) {
    max = std::max(max, e);
    sum += e;
    ++count;
  }
  AttributeLoss as(const std::string& name, const std::string& unit = "") const {
    return {name, unit, max, count ? sum / double(count) : 0.0};
  }
};

// The angle between two rotations (q and -q are the same one).
double rotation_degrees(const float* a, const float* b) {
  double dot = 0;
  for (int k = 0; k < 4; ++k) dot += double(a[k]) * b[k];
  return 2.0 * std::acos(std::min(1.0, std::abs(dot))) * 180.0 / M_PI;
}

std::vector<AttributeLoss> attribute_losses(const Scene& written, const Scene& back) {
  ErrorSum position, scale, rotation, opacity, colour, bands;
  const int rest_w = written.sh_rest_per_gaussian(), rest_b = back.sh_rest_per_gaussian();
  const int shared = std::min(rest_w, rest_b);
  for (std::size_t i = 0; i < written.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      position.add(std::abs(double(written.positions[i * 3 + k]) - back.positions[i * 3 + k]));
      scale.add(std::abs(std::log(double(written.scales[i * 3 + k])) - std::log(double(back.scales[i * 3 + k]))));
      colour.add(std::abs(double(written.sh_dc[i * 3 + k]) - back.sh_dc[i * 3 + k]));
    }
    rotation.add(rotation_degrees(&written.rotations[i * 4], &back.rotations[i * 4]));
    opacity.add(std::abs(double(written.opacities[i]) - back.opacities[i]));
    for (int c = 0; c < shared; ++c)
      bands.add(std::abs(double(written.sh_rest[i * rest_w + c]) - back.sh_rest[i * rest_b + c]));
  }
  std::vector<AttributeLoss> losses = {position.as("position"), scale.as("log-scale"),
                                       rotation.as("rotation", "degrees"), opacity.as("opacity"),
                                       colour.as("f_dc")};
  if (shared > 0) losses.push_back(bands.as("SH bands (f_rest)"));
  return losses;
}

Image render(Renderer& renderer, const std::shared_ptr<const Scene>& scene, const Camera& camera) {
  renderer.set_scene(scene);
  RenderOptions options;
  options.kernel = scene->trained_kernel.kernel;
  Image image;
  renderer.render(camera, options, image, nullptr);
  return image;
}

// The value below which `fraction` of `values` lie.
float quantile(std::vector<float> values, double fraction) {
  const std::size_t at = std::min(values.size() - 1, static_cast<std::size_t>(fraction * double(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(at), values.end());
  return values[at];
}

}  // namespace

std::vector<Camera> loss_views(const Scene& scene, const std::string& cameras_path, int width) {
  std::vector<Camera> views;
  std::error_code error;
  if (!cameras_path.empty() && std::filesystem::is_regular_file(cameras_path, error)) {
    const std::vector<Camera> all = load_cameras(cameras_path);
    for (int v = 0; v < kViews && !all.empty(); ++v) {
      const Camera& c = all[all.size() * static_cast<std::size_t>(v) / kViews];
      views.push_back(c.width > width ? c.resized(width, std::max(1, c.height * width / c.width)) : c);
    }
    if (!views.empty()) return views;
  }
  // Around the median centre, at twice the distance within which 80% of the Gaussians lie:
  // a few far outliers must not shrink the scene to a dot.
  float centre[3];
  for (int k = 0; k < 3; ++k) {
    std::vector<float> axis(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) axis[i] = scene.positions[i * 3 + k];
    centre[k] = quantile(axis, 0.5);
  }
  std::vector<float> distance(scene.size());
  for (std::size_t i = 0; i < scene.size(); ++i) {
    double d = 0;
    for (int k = 0; k < 3; ++k) d += std::pow(double(scene.positions[i * 3 + k]) - centre[k], 2.0);
    distance[i] = static_cast<float>(std::sqrt(d));
  }
  const float radius = std::max(1e-3f, 2.0f * quantile(distance, 0.8));
  const float up[3] = {0, -1, 0};  // 3DGS scenes: y down
  views = make_orbit_cameras(centre, up, radius, 0.3f * radius, kViews, width, width * 9 / 16, 60.0f);
  for (std::size_t v = 0; v < views.size(); ++v)
    if (views[v].name.empty()) views[v].name = "orbit " + std::to_string(v);
  return views;
}

ConversionLoss measure_conversion_loss(const Scene& input, const Scene& written, const Scene& read_back,
                                       const std::vector<Camera>& views) {
  ConversionLoss loss;
  loss.written = written.size();
  loss.read_back = read_back.size();
  loss.sh_degree_written = written.sh_degree;
  loss.sh_degree_read_back = read_back.sh_degree;
  if (written.size() == read_back.size()) loss.attributes = attribute_losses(written, read_back);
  auto in = std::make_shared<const Scene>(input);
  auto back = std::make_shared<const Scene>(read_back);
  std::unique_ptr<Renderer> renderer = make_cpu_renderer();
  for (const Camera& camera : views) {
    const Image a = render(*renderer, in, camera);
    const Image b = render(*renderer, back, camera);
    loss.views.push_back({camera.name, compare_images(a, b).psnr_db});
  }
  return loss;
}

std::string format_conversion_loss(const ConversionLoss& loss) {
  char line[256];
  std::string text;
  std::snprintf(line, sizeof line, "loss: %zu Gaussians written, %zu read back, SH degree %d%s\n", loss.written,
                loss.read_back, loss.sh_degree_read_back,
                loss.sh_degree_read_back < loss.sh_degree_written ? " (higher bands not kept)" : "");
  text += line;
  for (const AttributeLoss& a : loss.attributes) {
    std::snprintf(line, sizeof line, "loss:   %-18s max %.3g, mean %.3g%s%s\n", a.name.c_str(), a.max_error,
                  a.mean_error, a.unit.empty() ? "" : " ", a.unit.c_str());
    text += line;
  }
  for (const ViewLoss& v : loss.views) {
    if (std::isinf(v.psnr_db))
      std::snprintf(line, sizeof line, "loss:   image %-12s identical to the input's\n", v.camera.c_str());
    else
      std::snprintf(line, sizeof line, "loss:   image %-12s PSNR %.1f dB against the input's\n", v.camera.c_str(),
                    v.psnr_db);
    text += line;
  }
  return text;
}

}  // namespace flashgs::cli
