// Screenshot file names: a timestamped, never-reused name in the chosen folder (default: the XDG pictures folder, else the working directory).
#pragma once

#include <ctime>
#include <string>

namespace flashgs::viewer {

// The XDG pictures folder ($XDG_PICTURES_DIR, or XDG_PICTURES_DIR in
// $XDG_CONFIG_HOME/user-dirs.dirs, or ~/Pictures) when it exists as a folder, else ".".
std::string default_screenshot_folder();

// "<folder>/flashgs_<tag>_YYYY-MM-DD_HH-MM-SS.png" for local time `when` (tag "" gives
// "flashgs_YYYY-..."), with "_2", "_3", ... added while that file exists: two shots in one
// second never overwrite each other. `extension` includes its dot.
std::string timestamped_screenshot_path(const std::string& folder, const std::string& tag, std::time_t when,
                                        const std::string& extension = ".png");

// The same for now; an empty folder means the working directory.
std::string next_screenshot_path(const std::string& folder, const std::string& tag);

}  // namespace flashgs::viewer
