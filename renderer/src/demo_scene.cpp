// The demo scene's paths (see demo_scene.h); FLASHGS_ASSET_DIR is set by renderer/CMakeLists.txt.
#include "flashgs/demo_scene.h"

namespace flashgs {

std::string demo_scene_path() { return std::string(FLASHGS_ASSET_DIR) + "/demo/point_cloud.ply"; }

std::string demo_cameras_path() { return std::string(FLASHGS_ASSET_DIR) + "/demo/cameras.json"; }

}  // namespace flashgs
