// flashgs-viewer: the interactive (and scriptable) 3D Gaussian Splatting viewer.
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "scene_loader.h"

#include "viewer_app_gl.h"
#include "viewer_args.h"

int main(int argc, char** argv) {
  flashgs::viewer::ViewerArgs args;
  const int parsed = flashgs::viewer::parse_viewer_args(argc, argv, &args);
  if (parsed >= 0) return parsed;
  // OpenImageIO's module is not loaded here: PNG screenshots and exports go through libpng, and
  // the module loads only for a scripted --screenshot in another format.
  int code = 3;
  try {
    flashgs::viewer::ViewerApp app(args);
    code = app.run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flashgs-viewer: error: %s\n", e.what());
  }
  // A scene load still running (blocked in open(), or abandoned) must neither delay the exit
  // nor run while static objects are destroyed: leave without destructors then.
  if (flashgs::viewer::SceneLoader::running() > 0) {
    std::fflush(nullptr);
    std::_Exit(code);
  }
  return code;
}
