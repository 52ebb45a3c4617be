// PathExport: the camera path written as an image sequence (frame_00000.png, ...) in a folder, one frame per step so the window stays live, then a video when ffmpeg is on PATH.
#pragma once

#include <string>

namespace flashgs::viewer {

class PathExport {
 public:
  static constexpr const char* kVideoName = "path.mp4";

  // Starts an export of `frames` frames over one loop of the path into `folder` (created).
  // Returns an empty string, or why it cannot start (the folder cannot be made, no frames).
  std::string start(const std::string& folder, int frames);
  bool active() const { return m_next < m_frames; }
  // The loop parameter (0..1) and file of the next frame; advance() after writing it.
  double next_t() const { return double(m_next) / double(m_frames); }
  std::string next_file() const;
  void advance() { ++m_next; }
  void cancel() { m_frames = m_next; }
  int done_frames() const { return m_next; }
  int total_frames() const { return m_frames; }
  const std::string& folder() const { return m_folder; }
  // The video the frames are joined into.
  std::string video_file() const { return m_folder + "/" + kVideoName; }

  // The command that makes path.mp4 from the written frames at `fps`, when ffmpeg is on PATH
  // (found at run time), else empty.
  std::string video_command(int fps) const;

 private:
  std::string m_folder;
  int m_frames = 0, m_next = 0;
};

}  // namespace flashgs::viewer
