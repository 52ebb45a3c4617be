// Checks of the CLI's inputs made before any work starts (see option_checks.h).
#include "option_checks.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "flashgs/scene_formats.h"
#include "flashgs/image_io.h"

namespace flashgs::cli {

namespace fs = std::filesystem;

constexpr double kFloatMax = 3.4028234663852886e38;

std::vector<int> parse_index_list(const std::string& option, const std::string& text) {
  if (text.empty()) throw Error(option + ": the list is empty; expected indices such as 0,2,4");
  std::vector<int> indices;
  std::size_t begin = 0;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i < text.size() && text[i] != ',') continue;
    const std::string item = text.substr(begin, i - begin);
    if (item.empty())
      throw Error(option + ": item " + std::to_string(indices.size() + 1) + " of \"" + printable_file_text(text) +
                  "\" is empty");
    if (item.find_first_not_of("0123456789") != std::string::npos || item.size() > 9)
      throw Error(option + ": \"" + printable_file_text(item) + "\" is not a camera index (decimal digits only)");
    indices.push_back(std::stoi(item));
    begin = i + 1;
  }
  return indices;
}

CLI::Validator resolution_text() {
  return CLI::Validator(
      [](std::string& text) -> std::string { return text.empty() ? "the value is empty; expected WxH" : ""; }, "WxH",
      "WxH");
}

void check_camera_indices(const std::string& option, const std::vector<int>& indices, std::size_t count,
                          const std::string& cameras_path) {
  for (int i : indices)
    if (i < 0 || static_cast<std::size_t>(i) >= count)
      throw Error(option + ": camera " + std::to_string(i) + " does not exist (" + cameras_path + " has " +
                  std::to_string(count) + (count ? ": 0.." + std::to_string(count - 1) : std::string()) + ")");
}

void check_output_file(const std::string& option, const std::string& path) {
  if (path.empty()) throw Error(option + ": the output path is empty");
  try {
    flashgs::check_output_file(path);
  } catch (const Error& e) {
    throw Error(option + " " + e.what());
  }
}

void check_output_image(const std::string& option, const std::string& path) {
  check_output_file(option, path);
  if (!image_format_writable(path))
    throw Error(option + " " + path + ": unknown image format (the extension picks it: " +
                (image_io_has_oiio() ? std::string(".png, .exr, .jpg, .tif, ")
                                     : image_io_writes_png() ? std::string(".png, ") : std::string()) +
                ".ppm or .pfm)");
}

std::vector<std::string> check_output_folder(const std::string& option, const std::string& dir) {
  if (dir.empty()) throw Error(option + ": the output folder is empty");
  std::vector<std::string> created;  // what create_directories is about to make
  std::error_code ec;
  for (fs::path p = fs::path(dir).lexically_normal(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created.insert(created.begin(), p.string());
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    remove_created_folders(created);
    throw Error(option + " " + dir + ": cannot create the folder (" + ec.message() + ")");
  }
  if (access(dir.c_str(), W_OK) != 0) {
    remove_created_folders(created);
    throw Error(option + " " + dir + ": the folder is not writable");
  }
  return created;
}

void remove_created_folders(const std::vector<std::string>& created) {
  std::error_code ec;  // fs::remove leaves a folder that is not empty, and that is wanted
  for (auto it = created.rbegin(); it != created.rend(); ++it) fs::remove(*it, ec);
}

void check_frame_fits(const Renderer& renderer, const Camera& camera, std::size_t gaussians,
                      const std::string& option) {
  const bool cpu = renderer.name().rfind("cpu", 0) == 0;
  // The pairs are unknown before the frame: one per Gaussian is the floor of a scene in view.
  const FrameMemory need =
      estimate_frame_memory(cpu ? BackendKind::cpu : BackendKind::cuda, gaussians, camera.width, camera.height,
                            gaussians, static_cast<int>(std::thread::hardware_concurrency()));
  const AvailableMemory available = available_host_memory();
  const std::string shortfall = frame_memory_shortfall(need, camera.width, camera.height, available);
  if (!shortfall.empty()) throw Error(option + ": " + shortfall);
  if (need.host > 1000000000ull)
    std::fprintf(stderr, "note: a %dx%d frame needs about %s of memory (%s available)\n", camera.width, camera.height,
                 format_bytes(need.host).c_str(),
                 available.limited_by.empty() ? "unknown" : format_bytes(available.bytes).c_str());
}

void check_declared_scene_fits(BackendKind kind, const Camera& camera, const std::string& scene_path,
                               const std::string& option) {
  const SceneDeclaration declared = declare_scene_file(scene_path);
  if (declared.gaussians == 0) return;
  const int threads = static_cast<int>(std::thread::hardware_concurrency());
  // One pair per Gaussian: the floor, as in check_frame_fits.
  const FrameMemory frame =
      estimate_frame_memory(kind, declared.gaussians, camera.width, camera.height, declared.gaussians, threads);
  const AvailableMemory available = available_host_memory();
  if (available.limited_by.empty() || declared.load_bytes + frame.host <= available.bytes) return;
  // A frame too large by its size alone is the size option's fault: check_frame_fits says so.
  if (estimate_frame_memory(kind, 0, camera.width, camera.height, 0, threads).host > available.bytes) return;
  throw Error(scene_path + ": " + std::to_string(declared.gaussians) + " Gaussians need about " +
              format_bytes(declared.load_bytes) + " to load and " + format_bytes(frame.host) + " for a " +
              std::to_string(camera.width) + "x" + std::to_string(camera.height) + " frame (" + option + "), but " +
              format_bytes(available.bytes) + " is available (" + available.limited_by + ")");
}

void check_look_at(const std::vector<float>& eye, const std::vector<float>& target, const std::vector<float>& up) {
  const double f[3] = {double(target[0]) - eye[0], double(target[1]) - eye[1], double(target[2]) - eye[2]};
  const double u[3] = {up[0], up[1], up[2]};
  const double f_len = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  const double u_len = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  if (!(f_len > 0)) throw Error("--eye and --look-at are the same point: there is no view direction");
  if (!(f_len < kFloatMax)) throw Error("--look-at minus --eye is beyond float range");
  if (!(u_len > 0)) throw Error("--up is the zero vector");
  const double c[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]};
  const double sin_angle = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / (f_len * u_len);
  if (!(sin_angle > 1e-6)) throw Error("--up is parallel to the view direction (--look-at minus --eye)");
}

}  // namespace flashgs::cli
