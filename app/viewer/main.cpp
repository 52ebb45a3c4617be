// flashgs-viewer: the interactive (and scriptable) 3D Gaussian Splatting viewer.
#include <cstdio>
#include <exception>

#include "viewer_app_gl.h"
#include "viewer_args.h"

int main(int argc, char** argv) {
  flashgs::viewer::ViewerArgs args;
  const int parsed = flashgs::viewer::parse_viewer_args(argc, argv, &args);
  if (parsed >= 0) return parsed;
  try {
    flashgs::viewer::ViewerApp app(args);
    return app.run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flashgs-viewer: error: %s\n", e.what());
    return 3;
  }
}
