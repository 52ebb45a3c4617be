// What the in-app browser lists in a folder: sub-folders, the scene files of every format the viewer reads, the folders that are a scene (point_cloud.ply, a SOG set, a 3DGS training output with its iterations), sorted by name, size or date.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace flashgs::viewer {

struct FolderEntry {
  enum class Kind { folder, scene_folder, scene_file };
  std::string name;
  Kind kind = Kind::folder;
  std::uint64_t bytes = 0;   // a file's size (0 for folders)
  std::int64_t modified = 0; // seconds, for sorting
  // A 3DGS training output: its iterations' point_cloud.ply paths, highest first, with their N.
  std::vector<std::pair<long long, std::string>> iterations;
};

enum class FolderSort { name, size, date };

// A file name the viewer opens as a scene: .ply (INRIA or compressed), .splat, .spz, and a SOG
// set's meta.json or lod-meta.json.
bool is_scene_file_name(const std::string& name);

// The entries of `folder` (hidden ones left out): folders first, then scene files, each group
// sorted by `sort` (size and date: largest / newest first; folders by name for size). Other
// files are left out. `error` is set (and the list empty) when the folder cannot be read.
std::vector<FolderEntry> list_folder(const std::string& folder, FolderSort sort, std::string* error);

}  // namespace flashgs::viewer
