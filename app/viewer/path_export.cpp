// Frame numbering of the path export and the ffmpeg command that joins the frames.
#include "path_export.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "file_dialog.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/image_io.h"

namespace flashgs::viewer {
namespace {

const char* frame_extension() { return image_io_writes_png() ? ".png" : ".ppm"; }

}  // namespace

std::string PathExport::start(const std::string& folder, int frames) {
  if (frames <= 0) return "path export: needs at least one frame";
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (!std::filesystem::is_directory(folder, ec)) return "path export: " + folder + " is not a folder that can be made";
  if (::access(folder.c_str(), W_OK) != 0) return "path export: the folder " + folder + " is not writable";
  // Checked now, not after the frames: ffmpeg would wait for ever on a FIFO there. Each frame
  // file is checked as it is written (write_image).
  try {
    check_output_file(folder + "/" + kVideoName);
  } catch (const Error& e) {
    return std::string("path export: ") + e.what();
  }
  m_folder = folder;
  m_frames = frames;
  m_next = 0;
  return "";
}

std::string PathExport::next_file() const {
  char name[32];
  std::snprintf(name, sizeof name, "/frame_%05d", m_next);
  return m_folder + name + frame_extension();
}

std::string PathExport::video_command(int fps) const {
  const std::string ffmpeg = find_on_path("ffmpeg");
  if (ffmpeg.empty()) return "";
  return "'" + ffmpeg + "' -y -loglevel error -framerate " + std::to_string(fps) + " -i '" + m_folder + "/frame_%05d" +
         frame_extension() + "' -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' '" + video_file() + "'";
}

}  // namespace flashgs::viewer
