// Chooses the reader for a scene file.
#include "flashgs/scene_formats.h"

#include "flashgs/io.h"

namespace flashgs {

Scene load_scene_file(const std::string& path, LoadReport* report, LoadProgress* /*progress*/) {
  return load_ply(path, report);
}

}  // namespace flashgs
