// A city of real scenes for large-scene tests: copies of each source at distinct places and
// headings on a grid, written as one INRIA PLY as they are made (the city is never held whole),
// with a camera path from street level up to an overview.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/scene.h"

namespace flashgs {

// A source scene and which of its axes points up: "+x", "-x", "+y", "-y", "+z" or "-z".
struct CitySource {
  std::string name;  // for messages
  Scene scene;
  std::string up = "+z";
};

struct CityReport {
  std::uint64_t gaussians = 0;
  int blocks = 0;
  float block_size = 0;  // the grid's spacing, in scene units
  std::uint64_t bytes = 0;
  bool dropped_sh = false;  // a source had SH bands the rotated copies cannot keep
};

// Writes `blocks` blocks (source i % sources) to `ply_path` at SH degree 0: the view-dependent
// bands are not rotated with the copies, so only the base colour is kept. Each block's up axis
// becomes +z, its ground (2nd percentile of height) z = 0, its heading i x 137.5 degrees.
// `path` gets `path_cameras` cameras (width x height, 60 degrees across) from eye height along
// the first row of blocks up to a view of the whole city. Throws flashgs::Error naming the
// source or file.
CityReport write_city_scene(const std::vector<CitySource>& sources, int blocks, const std::string& ply_path,
                            int path_cameras, int width, int height, std::vector<Camera>* path);

}  // namespace flashgs
