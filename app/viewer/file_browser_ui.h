// FileBrowser: the in-app "open a scene" window (ImGui) for desktops without zenity or kdialog: folders to walk, PLY files and 3DGS output folders to open.
#pragma once

#include <string>
#include <vector>

namespace flashgs::viewer {

class FileBrowser {
 public:
  void open(const std::string& folder);
  bool is_open() const { return m_open; }
  // Draws the window while open; returns the chosen file or folder (empty: none this frame).
  std::string draw(float ui_scale);

 private:
  void list(const std::string& folder);

  bool m_open = false;
  bool m_just_opened = false;  // takes the focus in its first frame
  std::string m_folder;
  std::vector<std::string> m_folders, m_files;  // names in m_folder
  std::string m_error;
};

}  // namespace flashgs::viewer
