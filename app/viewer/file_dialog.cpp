// The desktop file dialog run as a child process on a detached thread, its answer read from its standard output.
#include "file_dialog.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <thread>

#include <unistd.h>

namespace flashgs::viewer {

struct FileDialog::Shared {
  std::mutex mutex;
  bool busy = false;
  std::string choice;
};

namespace {

// Single quotes for the shell, with embedded ones closed, escaped and reopened.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

std::string find_on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (!path) return "";
  const std::string all = path;
  std::size_t start = 0;
  while (start <= all.size()) {
    const std::size_t end = std::min(all.find(':', start), all.size());
    const std::string folder = all.substr(start, end - start);
    const std::string candidate = (folder.empty() ? std::string(".") : folder) + "/" + program;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec) && access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return "";
}

bool FileDialog::busy() const {
  if (!m_shared) return false;
  std::lock_guard<std::mutex> lock(m_shared->mutex);
  return m_shared->busy;
}

bool FileDialog::open_native(const std::string& start_folder) {
  if (busy()) return false;
  std::string command;
  const std::string folder = start_folder.empty() ? std::string(".") : start_folder;
  if (const std::string zenity = find_on_path("zenity"); !zenity.empty()) {
    m_tool = "zenity";
    command = quoted(zenity) + " --file-selection --title='Open a scene (PLY, or cancel to pick a folder)' --filename=" +
              quoted(folder + "/") + " --file-filter='Gaussian scenes | *.ply' --file-filter='All files | *'";
  } else if (const std::string kdialog = find_on_path("kdialog"); !kdialog.empty()) {
    m_tool = "kdialog";
    command = quoted(kdialog) + " --getopenfilename " + quoted(folder) + " '*.ply'";
  } else {
    m_tool.clear();
    return false;
  }
  auto shared = std::make_shared<Shared>();
  shared->busy = true;
  m_shared = shared;
  // Detached: the dialog stays up as long as the user wants; closing the viewer does not wait.
  std::thread([shared, command]() {
    std::string out;
    if (FILE* pipe = popen((command + " 2>/dev/null").c_str(), "r")) {
      char buffer[4096];
      while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
      pclose(pipe);
    }
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    std::lock_guard<std::mutex> lock(shared->mutex);
    shared->choice = out;
    shared->busy = false;
  }).detach();
  return true;
}

std::string FileDialog::take_choice() {
  if (!m_shared) return "";
  std::lock_guard<std::mutex> lock(m_shared->mutex);
  std::string c;
  c.swap(m_shared->choice);
  return c;
}

}  // namespace flashgs::viewer
