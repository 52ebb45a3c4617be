// The viewer's settings file in the user's config folder: what is kept between runs (backend, options, navigation, render scale, recent scenes), read and written robustly.
#pragma once

#include <string>
#include <vector>

#include "viewer_settings.h"

namespace flashgs::viewer {

inline constexpr std::size_t kMaxRecentFiles = 10;

// What a run keeps for the next one.
struct StoredSettings {
  ViewerSettings settings;
  std::string backend = "auto";     // auto | cpu | cuda
  std::vector<std::string> recent;  // newest first, at most kMaxRecentFiles
};

// $XDG_CONFIG_HOME/flashgs, else $HOME/.config/flashgs; empty when neither is set.
std::string config_dir();

// Reads `path` into `stored` (which keeps its values for what the file does not name). A
// missing file is not a problem (empty return). An unreadable or corrupt one leaves `stored`
// as it was and returns one line naming the file, the line and the problem.
std::string read_settings_file(const std::string& path, StoredSettings& stored);
// Writes `stored` to `path` (creating its folder; the file is replaced whole, never left half
// written). Returns one line naming the file and the problem, or empty.
std::string write_settings_file(const std::string& path, const StoredSettings& stored);

// `path` first in `recent`, once, the list cut to kMaxRecentFiles.
void add_recent_file(std::vector<std::string>& recent, const std::string& path);

}  // namespace flashgs::viewer
