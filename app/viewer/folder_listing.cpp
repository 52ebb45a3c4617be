// The browser's folder listing: scene files by name, scene folders by what they hold, training iterations, sorting.
#include "folder_listing.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>

namespace flashgs::viewer {
namespace {

namespace fs = std::filesystem;

bool ends_with(const std::string& s, const std::string& tail) {
  // `tail` is lower case; `s` matches it in any case.
  return s.size() >= tail.size() && std::equal(tail.rbegin(), tail.rend(), s.rbegin(), [](char t, char c) {
           return std::tolower(static_cast<unsigned char>(c)) == t;
         });
}

bool something_at(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

// point_cloud/iteration_<N>/point_cloud.ply of a training output, highest N first.
std::vector<std::pair<long long, std::string>> training_iterations(const fs::path& folder) {
  std::vector<std::pair<long long, std::string>> out;
  std::error_code ec;
  for (fs::directory_iterator it(folder / "point_cloud", ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const std::string prefix = "iteration_";
    if (name.compare(0, prefix.size(), prefix) != 0 || name.size() == prefix.size() || name.size() > prefix.size() + 18 ||
        name.find_first_not_of("0123456789", prefix.size()) != std::string::npos)
      continue;
    const fs::path ply = it->path() / "point_cloud.ply";
    if (something_at(ply)) out.emplace_back(std::stoll(name.substr(prefix.size())), ply.string());
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  return out;
}

}  // namespace

bool is_scene_file_name(const std::string& name) {
  for (const char* ext : {".ply", ".splat", ".spz"})
    if (ends_with(name, ext)) return true;
  return name == "meta.json" || name == "lod-meta.json";
}

std::vector<FolderEntry> list_folder(const std::string& folder, FolderSort sort, std::string* error) {
  std::vector<FolderEntry> entries;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    FolderEntry e;
    e.name = it->path().filename().string();
    if (e.name.empty() || e.name[0] == '.') continue;
    std::error_code kind;
    if (it->is_directory(kind)) {
      const fs::path p = it->path();
      e.iterations = training_iterations(p);
      const bool scene = something_at(p / "point_cloud.ply") || something_at(p / "meta.json") ||
                         something_at(p / "lod-meta.json") ||
                         !e.iterations.empty();
      e.kind = scene ? FolderEntry::Kind::scene_folder : FolderEntry::Kind::folder;
    } else if (is_scene_file_name(e.name) && it->is_regular_file(kind)) {
      e.kind = FolderEntry::Kind::scene_file;
      e.bytes = it->file_size(kind);
    } else {
      continue;
    }
    std::error_code time_error;
    const auto t = it->last_write_time(time_error);
    if (!time_error) e.modified = std::chrono::duration_cast<std::chrono::seconds>(t.time_since_epoch()).count();
    entries.push_back(std::move(e));
  }
  if (ec) {
    if (error) *error = folder + ": " + ec.message();
    return {};
  }
  std::sort(entries.begin(), entries.end(), [sort](const FolderEntry& a, const FolderEntry& b) {
    const bool a_file = a.kind == FolderEntry::Kind::scene_file, b_file = b.kind == FolderEntry::Kind::scene_file;
    if (a_file != b_file) return !a_file;  // folders first
    if (sort == FolderSort::size && a.bytes != b.bytes) return a.bytes > b.bytes;
    if (sort == FolderSort::date && a.modified != b.modified) return a.modified > b.modified;
    return a.name < b.name;
  });
  return entries;
}

}  // namespace flashgs::viewer
