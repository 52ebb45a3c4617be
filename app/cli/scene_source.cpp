// Scene, camera, option and backend selection shared by the CLI subcommands.
#include "scene_source.h"

#include <cstdio>
#include <fstream>

#include "flashgs/compressed_formats.h"
#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "flashgs/parse.h"
#include "option_checks.h"

namespace flashgs::cli {

void SceneArgs::add_to(CLI::App* command) {
  m_scene_option = command->add_option("scene", scene_path, kSceneArgumentHelp);
  m_cameras_option = command->add_option("--cameras", cameras_path, "cameras.json (default: the scene's own)");
  command->add_option("--lod", lod, kLodOptionHelp)->check(whole_number())
      ->check(CLI::NonNegativeNumber);
  command->add_option("--spz-axes", spz_axes, kSpzAxesHelp)->check(CLI::IsMember({"niantic", "none"}));
}

SceneReadOptions SceneArgs::read_options() const {
  SceneReadOptions options;
  parse_spz_axes(spz_axes, options.spz_axes);  // the option's check admits only valid values
  return options;
}

SceneLocation SceneArgs::locate() const {
  // Only a scene left out means the demo: an empty one is a mistake (an unset shell variable).
  const bool scene_given = m_scene_option && m_scene_option->count() > 0;
  if (scene_given && scene_path.empty())
    throw Error("the scene path is empty: name a PLY file or a scene folder, or leave it out for the demo scene");
  SceneLocation location = scene_given ? locate_scene(scene_path)
                                       : SceneLocation{demo_scene_path(), default_cameras_path(demo_scene_path())};
  if (m_cameras_option && m_cameras_option->count() > 0) {
    if (cameras_path.empty()) throw Error("--cameras: the path is empty");
    location.cameras = cameras_path;
  }
  return location;
}

std::string describe_lod_levels(const std::string& path) {
  if (!is_sog_lod_set(path)) return "";
  const SogLodSet set = describe_sog_lod(path);
  std::string text = "SOG LOD set: " + std::to_string(set.levels.size()) + " levels (--lod N), bounds [" +
                     std::to_string(set.bounds_min[0]) + ", " + std::to_string(set.bounds_min[1]) + ", " +
                     std::to_string(set.bounds_min[2]) + "] .. [" + std::to_string(set.bounds_max[0]) + ", " +
                     std::to_string(set.bounds_max[1]) + ", " + std::to_string(set.bounds_max[2]) + "]\n";
  for (const SogLodLevel& level : set.levels) {
    char line[160];
    std::snprintf(line, sizeof line, "  level %d: %zu Gaussians, SH degree %d, %s to decode, %zu chunk file%s\n",
                  level.level, level.gaussians, level.sh_degree, format_bytes(sog_lod_level_bytes(level)).c_str(),
                  level.files.size(), level.files.size() == 1 ? "" : "s");
    text += line;
  }
  return text;
}

std::shared_ptr<const Scene> load_scene_verbose(const std::string& path, int lod, const SceneReadOptions& options) {
  LoadReport report;
  auto scene = std::make_shared<Scene>(load_scene_at_level(path, lod, &report, options));
  if (report.dropped_non_finite)
    std::fprintf(stderr, "%s: dropped %zu Gaussians with NaN/Inf attributes (or exp(scale) overflow)\n",
                 path.c_str(), report.dropped_non_finite);
  if (report.repaired_zero_quaternion)
    std::fprintf(stderr, "%s: %zu zero quaternions set to identity\n", path.c_str(), report.repaired_zero_quaternion);
  return scene;
}

void RenderArgs::add_to(CLI::App* command) {
  command->add_option("--algorithm,-a", algorithm, "flash or baseline")->check(CLI::IsMember({"flash", "baseline"}));
  switches.add_to(command);
  kernel.add_to(command);
  command->add_option("--tau", tau, "alpha threshold of the opacity-aware extent")->check(finite_in(1e-6, 0.99));
  command->add_option("--background", background, "background colour r,g,b in [0, 1]")
      ->delimiter(',')->expected(3)->check(finite_in(0.0, 1.0));
  command->add_option("--sh-degree", sh_degree, "use at most this many SH bands")->check(whole_number())->check(CLI::Range(0, 3));
  command->add_flag("--fp16-sh", fp16_sh, "use the SH coefficients as half values (not exact; see flashgs report)");
  command->add_flag("--fp16-shape", fp16_shape,
                    "use each Gaussian's rotation, scale and opacity as half values (not exact; see flashgs report)");
  command->add_flag("--fp16-blend", fp16_blend,
                    "CUDA: blend in half arithmetic (not exact; see flashgs report; the CPU renders exactly)");
  command->add_option("--backend", backend, "cpu, cuda or auto")->check(CLI::IsMember({"cpu", "cuda", "auto"}));
}

RenderOptions RenderArgs::options(const Scene& scene) const {
  RenderOptions o = algorithm == "baseline" ? RenderOptions::baseline() : RenderOptions{};
  if (algorithm != "baseline") switches.apply(&o);
  o.kernel = kernel.resolve(scene);
  o.tau = tau;
  for (int k = 0; k < 3; ++k) o.background[k] = background[k];
  o.sh_degree_cap = sh_degree;
  o.fp16_sh = fp16_sh;
  o.fp16_shape = fp16_shape;
  o.fp16_blend = fp16_blend;
  return o;
}

void CameraArgs::add_to(CLI::App* command) {
  command->add_option("--camera,-c", index, "camera index in cameras.json")->check(whole_number());
  command->add_option("--resolution,-r", resolution, "render size WxH (field of view kept)")->check(resolution_text());
  const CLI::Validator coordinate = finite_in(-kMaxCoordinate, kMaxCoordinate);
  auto* eye_option = command->add_option("--eye", eye, "explicit camera: position x,y,z")
      ->delimiter(',')->expected(3)->check(coordinate);
  command->add_option("--look-at", look_at, "explicit camera: target x,y,z")
      ->delimiter(',')->expected(3)->check(coordinate)->needs(eye_option);
  eye_option->needs("--look-at");
  command->add_option("--up", up, "explicit camera: world up x,y,z (default 0,-1,0: y down, as in most 3DGS scenes)")
      ->delimiter(',')->expected(3)->check(coordinate);
  command->add_option("--fov", fov_degrees, "explicit camera: horizontal field of view in degrees")
      ->check(finite_in(1.0, 179.0));
}

Camera CameraArgs::select(const std::string& cameras_path) const {
  if (is_explicit()) {
    check_look_at(eye, look_at, up);
    const Resolution size = resolution.empty() ? Resolution{1920, 1080} : parse_resolution(resolution);
    Camera camera = look_at_camera(eye.data(), look_at.data(), up.data(), size.width, size.height, fov_degrees);
    camera.name = "explicit";
    return camera;
  }
  const std::vector<Camera> cameras = load_cameras(cameras_path);
  check_camera_indices("--camera", {index}, cameras.size(), cameras_path);
  Camera camera = cameras[index];
  if (!resolution.empty()) {
    const Resolution size = parse_resolution(resolution);
    camera = camera.resized(size.width, size.height);
  }
  return camera;
}

}  // namespace flashgs::cli
