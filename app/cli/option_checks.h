// Checks of the CLI's inputs made before any work starts: finite option values, camera
// indices, output paths, and whether a frame fits in memory. Each failure is one line naming
// the option or file.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "finite_option.h"
#include "flashgs/camera.h"
#include "flashgs/frame_memory.h"
#include "flashgs/renderer.h"

namespace flashgs::cli {

using flashgs::finite_in;  // app/common/finite_option.h

// The indices of a comma-separated list such as "0,2,4", as typed after `option`: every item
// decimal digits, none empty. Throws flashgs::Error naming the option otherwise.
std::vector<int> parse_index_list(const std::string& option, const std::string& text);

// CLI11 validator of a WxH option: an empty value is refused (it would mean "not given").
CLI::Validator resolution_text();

// Throws flashgs::Error naming `option` and `cameras_path` when an index is not a camera of
// the file (which holds `count`).
void check_camera_indices(const std::string& option, const std::vector<int>& indices, std::size_t count,
                          const std::string& cameras_path);

// The output file `path` (given with `option`) may be written: flashgs::check_output_file
// (file_access.h), its message led by the option. Throws flashgs::Error otherwise.
void check_output_file(const std::string& option, const std::string& path);
// Same, and write_image knows the format of its extension.
void check_output_image(const std::string& option, const std::string& path);
// Creates the folder `dir` (given with `option`) if needed and checks that it is writable.
// Returns the folders it created, outermost first (none when `dir` existed).
std::vector<std::string> check_output_folder(const std::string& option, const std::string& dir);
// Removes those of `created` (check_output_folder's) that are still empty, innermost first, so
// that a command that failed leaves no folder of its own behind.
void remove_created_folders(const std::vector<std::string>& created);

// Refuses (flashgs::Error naming the option) a frame of `camera` whose estimated working
// memory on `renderer` exceeds what this process can still allocate; prints the estimate
// when the frame is large (above 1 GB) and fits.
void check_frame_fits(const Renderer& renderer, const Camera& camera, std::size_t gaussians,
                      const std::string& option);

// Refuses (flashgs::Error naming the scene file, with the figures) a scene whose file declares
// more Gaussians than loading them and one frame of `camera` on a `backend` leave room for,
// before the file is read (declare_scene_file; formats that cannot say so cheaply pass).
void check_declared_scene_fits(BackendKind backend, const Camera& camera, const std::string& scene_path,
                               const std::string& option);

// Turns an explicit camera's --eye / --look-at / --up into an error naming them when they do
// not define a view (eye at the target, or looking along up).
void check_look_at(const std::vector<float>& eye, const std::vector<float>& target, const std::vector<float>& up);

}  // namespace flashgs::cli
