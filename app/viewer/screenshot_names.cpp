// Timestamped screenshot names and the XDG pictures folder.
#include "screenshot_names.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/image_io.h"

namespace flashgs::viewer {
namespace {

bool is_folder(const std::string& path) {
  std::error_code ec;
  return !path.empty() && std::filesystem::is_directory(path, ec);
}

// user-dirs.dirs names a handful of folders.
constexpr std::size_t kMaxUserDirsBytes = std::size_t{1} << 20;

// XDG_PICTURES_DIR="$HOME/Pictures" from user-dirs.dirs, $HOME expanded; empty if absent.
std::string pictures_from_user_dirs(const std::string& home) {
  const char* config = std::getenv("XDG_CONFIG_HOME");
  const std::string file = (config && *config ? std::string(config) : home + "/.config") + "/user-dirs.dirs";
  std::vector<char> text;
  try {  // read without blocking: a FIFO or a device there must not hang the viewer's start
    text = read_regular_file(file, kMaxUserDirsBytes);
  } catch (const Error&) {
    return "";  // absent or not a file: the next choice
  }
  std::istringstream in(std::string(text.begin(), text.end()));
  std::string line;
  while (std::getline(in, line)) {
    const std::string key = "XDG_PICTURES_DIR=";
    if (line.rfind(key, 0) != 0) continue;
    std::string value = line.substr(key.size());
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
    if (value.rfind("$HOME", 0) == 0) value = home + value.substr(5);
    return value;
  }
  return "";
}

}  // namespace

std::string default_screenshot_folder() {
  if (const char* env = std::getenv("XDG_PICTURES_DIR"); env && is_folder(env)) return env;
  const char* home = std::getenv("HOME");
  if (home && *home) {
    const std::string from_file = pictures_from_user_dirs(home);
    if (is_folder(from_file)) return from_file;
    if (is_folder(std::string(home) + "/Pictures")) return std::string(home) + "/Pictures";
  }
  return ".";
}

std::string timestamped_screenshot_path(const std::string& folder, const std::string& tag, std::time_t when,
                                        const std::string& extension) {
  std::tm local{};
  localtime_r(&when, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d_%H-%M-%S", &local);
  const std::string stem = (folder.empty() ? std::string(".") : folder) + "/flashgs_" + (tag.empty() ? "" : tag + "_") + stamp;
  std::string path = stem + extension;
  std::error_code ec;
  for (int n = 2; std::filesystem::exists(path, ec); ++n) path = stem + "_" + std::to_string(n) + extension;
  return path;
}

std::string next_screenshot_path(const std::string& folder, const std::string& tag) {
  // PNG where OpenImageIO is built in, else the built-in PPM writer's format.
  return timestamped_screenshot_path(folder, tag, std::time(nullptr), image_io_writes_png() ? ".png" : ".ppm");
}

}  // namespace flashgs::viewer
