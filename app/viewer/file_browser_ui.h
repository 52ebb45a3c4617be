// FileBrowser: the in-app "open a scene" window (ImGui) for desktops without zenity or kdialog: a path field, folders to walk, the scene files and scene folders of every format the viewer reads, sorted, and a training output's iterations.
#pragma once

#include <string>
#include <vector>

#include "folder_listing.h"

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
  std::string m_typed;         // the path field
  FolderSort m_sort = FolderSort::name;
  std::vector<FolderEntry> m_entries;
  std::string m_error;
};

}  // namespace flashgs::viewer
