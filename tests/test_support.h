// Helpers shared by the test suites: scene paths, cached scene loading, image dumps.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/scene.h"

namespace flashgs::test {

// ../shared/scenes/<name>; empty when the folder is absent.
std::string shared_scene_dir(const std::string& name);
// ../shared/scenes/formats/<file> (the compressed samples: biker.compressed.ply, biker.spz,
// playbot_sog, ...); empty when it is absent.
std::string shared_format_file(const std::string& file);
// Names of the real scenes present (pc_biker, pc_guitar, ...); empty when none.
std::vector<std::string> shared_scene_names();
// Loads (once per process) the scene and its cameras.
std::shared_ptr<const Scene> load_shared_scene(const std::string& name);
std::vector<Camera> load_shared_cameras(const std::string& name);
// The bundled demo scene.
std::shared_ptr<const Scene> load_demo_scene();
std::vector<Camera> load_demo_cameras();
// Writes expected, actual and |difference| x 10 images to the test output folder.
void dump_images(const std::string& stem, const Image& expected, const Image& actual);

}  // namespace flashgs::test

// Skips the current test when ../shared/scenes is absent.
#define FLASHGS_REQUIRE_SHARED_SCENES()                                                     \
  do {                                                                                      \
    if (::flashgs::test::shared_scene_names().empty())                                      \
      GTEST_SKIP() << "../shared/scenes is absent: real-scene test skipped";                \
  } while (0)
