// settings.ini: "key = value" lines; every value checked against its range, any bad line and the whole file is ignored.
#include "settings_store.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/options.h"

namespace flashgs::viewer {
namespace {

// What the viewer writes is a few KB; anything past this is not its settings file.
constexpr std::size_t kMaxSettingsFileBytes = 1 << 20;

bool parse_number(const std::string& text, float* out) {
  char* end = nullptr;
  errno = 0;
  const float v = std::strtof(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool parse_bool(const std::string& text, bool* out) {
  if (text == "1" || text == "true") *out = true;
  else if (text == "0" || text == "false") *out = false;
  else return false;
  return true;
}

bool ranged(const std::string& text, const ValueRange& range, float* out) {
  float v = 0;
  if (!parse_number(text, &v) || !range.contains(v)) return false;
  *out = v;
  return true;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

// One "key = value": false when the key is unknown or the value out of range.
bool apply_line(const std::string& key, const std::string& value, StoredSettings& st) {
  ViewerSettings& s = st.settings;
  RenderOptions& o = s.options;
  if (key == "backend") {
    if (value != "auto" && value != "cpu" && value != "cuda") return false;
    st.backend = value;
    return true;
  }
  if (key == "recent") {
    if (value.empty() || st.recent.size() >= kMaxRecentFiles) return false;
    st.recent.push_back(value);
    return true;
  }
  if (key == "algorithm") {
    if (value != "flash" && value != "baseline") return false;
    switch_algorithm(o, value == "flash" ? Algorithm::flash : Algorithm::baseline);
    return true;
  }
  for (const RenderSwitch& sw : kRenderSwitches)
    if (key == std::string("switch.") + sw.cli_name) return parse_bool(value, &(o.*(sw.member)));
  if (key == "tau") return ranged(value, kTauRange, &o.tau);
  if (key == "sh_degree_cap") {
    float v = 0;
    if (!parse_number(value, &v) || v != std::floor(v) || v < 0 || v > kMaxShDegree) return false;
    o.sh_degree_cap = int(v);
    return true;
  }
  if (key == "fp16_sh") return parse_bool(value, &o.fp16_sh);
  if (key == "fp16_shape") return parse_bool(value, &o.fp16_shape);
  if (key == "fp16_blend") return parse_bool(value, &o.fp16_blend);
  if (key == "background") {
    std::stringstream ss(value);
    std::string part;
    float rgb[3];
    int n = 0;
    while (std::getline(ss, part, ',')) {
      if (n == 3 || !ranged(trim(part), kBackgroundRange, &rgb[n])) return false;
      ++n;
    }
    if (n != 3) return false;
    std::copy(rgb, rgb + 3, o.background);
    return true;
  }
  if (key == "navigation") {
    if (value != "fly" && value != "orbit") return false;
    s.mode = value == "fly" ? NavigationMode::fly : NavigationMode::orbit;
    return true;
  }
  if (key == "render_scale") return ranged(value, kRenderScaleRange, &s.render_scale);
  if (key == "adaptive_resolution") return parse_bool(value, &s.adaptive_resolution);
  if (key == "move_speed") return ranged(value, kMoveSpeedRange, &s.move_speed);
  if (key == "look_sensitivity") return ranged(value, kLookSensitivityRange, &s.look_sensitivity);
  if (key == "heatmap_log") return parse_bool(value, &s.heatmap_log);
  if (key == "heatmap_opacity") return ranged(value, kHeatmapOpacityRange, &s.heatmap_opacity);
  if (key == "vsync") return parse_bool(value, &s.vsync);
  if (key == "path_seconds_per_camera") return ranged(value, kPathSecondsRange, &s.path_seconds_per_camera);
  return false;
}

}  // namespace

std::string config_dir() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  if (xdg && *xdg == '/') return std::string(xdg) + "/flashgs";  // the spec: relative paths are ignored
  const char* home = std::getenv("HOME");
  if (home && *home) return std::string(home) + "/.config/flashgs";
  return "";
}

std::string read_settings_file(const std::string& path, StoredSettings& stored) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || status.type() == std::filesystem::file_type::not_found) return "";  // first run
  const std::string ignored = ": ignored, using the defaults";
  std::vector<char> bytes;
  try {  // checked and read in one step: a FIFO, folder or huge file put there is refused, never waited on
    bytes = read_regular_file(path, kMaxSettingsFileBytes);
  } catch (const Error& e) {
    return e.what() + ignored;
  }
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  StoredSettings parsed = stored;
  parsed.recent.clear();
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto eq = t.find('=');
    const std::string key = eq == std::string::npos ? t : trim(t.substr(0, eq));
    const std::string value = eq == std::string::npos ? "" : trim(t.substr(eq + 1));
    if (eq == std::string::npos || !apply_line(key, value, parsed))
      return path + " line " + std::to_string(number) + ": \"" + t.substr(0, 80) + "\" is not a valid setting" + ignored;
  }
  stored = std::move(parsed);
  return "";
}

std::string write_settings_file(const std::string& path, const StoredSettings& st) {
  const ViewerSettings& s = st.settings;
  const RenderOptions& o = s.options;
  std::ostringstream out;
  out << "# flashgs-viewer settings, written at exit (delete the file for the defaults)\n";
  out << "backend = " << st.backend << "\n";
  out << "algorithm = " << (o.is_baseline() ? "baseline" : "flash") << "\n";
  for (const RenderSwitch& sw : kRenderSwitches) out << "switch." << sw.cli_name << " = " << (o.*(sw.member) ? 1 : 0) << "\n";
  out << "tau = " << o.tau << "\n";
  out << "sh_degree_cap = " << o.sh_degree_cap << "\n";
  out << "fp16_sh = " << o.fp16_sh << "\n";
  out << "fp16_shape = " << o.fp16_shape << "\n";
  out << "fp16_blend = " << o.fp16_blend << "\n";
  out << "background = " << o.background[0] << "," << o.background[1] << "," << o.background[2] << "\n";
  out << "navigation = " << (s.mode == NavigationMode::fly ? "fly" : "orbit") << "\n";
  out << "render_scale = " << s.render_scale << "\n";
  out << "adaptive_resolution = " << s.adaptive_resolution << "\n";
  out << "move_speed = " << s.move_speed << "\n";
  out << "look_sensitivity = " << s.look_sensitivity << "\n";
  out << "heatmap_log = " << s.heatmap_log << "\n";
  out << "heatmap_opacity = " << s.heatmap_opacity << "\n";
  out << "vsync = " << s.vsync << "\n";
  out << "path_seconds_per_camera = " << s.path_seconds_per_camera << "\n";
  for (const std::string& r : st.recent)
    if (r.find('\n') == std::string::npos) out << "recent = " << r << "\n";
  std::error_code ec;
  const std::filesystem::path target(path);
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path(), ec);
  if (ec) return path + ": not saved (" + ec.message() + ")";
  // Written beside it, then renamed over it: a crash or a full disk never leaves half a file.
  const std::string temp = path + ".tmp";
  {
    std::ofstream f(temp, std::ios::trunc);
    if (!f) return path + ": not saved (" + std::strerror(errno) + ")";
    f << out.str();
    f.flush();
    if (!f) {
      std::filesystem::remove(temp, ec);
      return path + ": not saved (write failed)";
    }
  }
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    return path + ": not saved (" + ec.message() + ")";
  }
  return "";
}

void add_recent_file(std::vector<std::string>& recent, const std::string& path) {
  recent.erase(std::remove(recent.begin(), recent.end(), path), recent.end());
  recent.insert(recent.begin(), path);
  if (recent.size() > kMaxRecentFiles) recent.resize(kMaxRecentFiles);
}

}  // namespace flashgs::viewer
