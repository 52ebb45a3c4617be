// FileDialog: "open a scene" through the desktop's own dialog (zenity or kdialog, found on PATH at run time) on a thread of its own, else the in-app browser.
#pragma once

#include <memory>
#include <string>

namespace flashgs::viewer {

// The full path of `program` in a folder of $PATH, or empty.
std::string find_on_path(const std::string& program);

class FileDialog {
 public:
  // Opens the desktop dialog when one is on PATH and returns true; false means there is none
  // (the caller shows the in-app browser). Refused (false) while one is already open.
  bool open_native(const std::string& start_folder);
  bool busy() const;
  // The chosen path once the dialog has closed with a choice (then cleared); empty otherwise.
  std::string take_choice();
  const std::string& tool() const { return m_tool; }  // "zenity", "kdialog" or empty

 private:
  struct Shared;
  std::shared_ptr<Shared> m_shared;  // shared with the dialog's thread, which may outlive this
  std::string m_tool;
};

}  // namespace flashgs::viewer
