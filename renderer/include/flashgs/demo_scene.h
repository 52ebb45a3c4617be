// Where the bundled demo scene lives (assets/demo of the source tree; CMake sets the folder).
#pragma once

#include <string>

namespace flashgs {

std::string demo_scene_path();    // the demo scene's PLY
std::string demo_cameras_path();  // its cameras.json

}  // namespace flashgs
