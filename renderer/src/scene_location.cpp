// Finding the scene file and cameras.json of a scene named as a file, a scene folder, a SOG
// folder or a 3DGS training output folder.
#include <filesystem>
#include <string>
#include <system_error>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

// Something is there, be it a dangling link or a loop: the later check says what is wrong with it.
bool something_at(const fs::path& path) {
  std::error_code error;
  return fs::exists(fs::symlink_status(path, error));
}

// The N of a folder named iteration_<N> as its digits without leading zeros ("0" for zero), or
// empty. Kept as text: a number of any length still compares (a shorter one is smaller).
std::string iteration_number(const std::string& folder_name) {
  const std::string prefix = "iteration_";
  if (folder_name.compare(0, prefix.size(), prefix) != 0 || folder_name.size() == prefix.size() ||
      folder_name.find_first_not_of("0123456789", prefix.size()) != std::string::npos)
    return "";
  const std::size_t first = folder_name.find_first_not_of('0', prefix.size());
  return first == std::string::npos ? "0" : folder_name.substr(first);
}

bool iteration_before(const std::string& a, const std::string& b) {
  return a.size() != b.size() ? a.size() < b.size() : a < b;
}

// <model>/point_cloud/iteration_<highest N>/point_cloud.ply, or empty when there is none.
fs::path latest_training_iteration(const fs::path& model) {
  std::error_code error;
  fs::path best;
  std::string best_n;
  for (fs::directory_iterator it(model / "point_cloud", error), end; !error && it != end; it.increment(error)) {
    const std::string n = iteration_number(it->path().filename().string());
    if (!n.empty() && (best_n.empty() || iteration_before(best_n, n)) && something_at(it->path() / "point_cloud.ply")) {
      best_n = n;
      best = it->path() / "point_cloud.ply";
    }
  }
  return best;
}

}  // namespace

std::string default_cameras_path(const std::string& ply_path) {
  const fs::path folder = fs::path(ply_path).parent_path();
  const fs::path beside = folder / "cameras.json";
  if (something_at(beside)) return beside.string();
  const fs::path model = folder.parent_path().parent_path();
  if (!iteration_number(folder.filename().string()).empty() && folder.parent_path().filename() == "point_cloud" &&
      something_at(model / "cameras.json"))
    return (model / "cameras.json").string();
  return beside.string();
}

SceneLocation locate_scene(const std::string& path) {
  if (path.empty()) throw Error("the scene path is empty: name a PLY file or a folder holding point_cloud.ply");
  fs::path ply = path;
  if (path_kind(path) == PathKind::folder) {
    // A scene folder, a SOG LOD set, one SOG chunk, or a training output, in that order.
    ply = fs::path(path) / "point_cloud.ply";
    for (const char* sog_file : {"lod-meta.json", "meta.json"})
      if (!something_at(ply)) ply = fs::path(path) / sog_file;
    if (!something_at(ply)) ply = latest_training_iteration(path);
    if (ply.empty())
      throw Error(path + ": a folder without point_cloud.ply (nor point_cloud/iteration_<N>/point_cloud.ply, "
                         "as a 3DGS training writes, nor a SOG lod-meta.json or meta.json)");
  }
  check_regular_file(ply.string());
  return {ply.string(), default_cameras_path(ply.string())};
}

}  // namespace flashgs
