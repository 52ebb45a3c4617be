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

// A source turned up (its up axis to +z): `align`, then minus `centre` (the middle of its
// 2%-98% range across, its ground at 2% of the height), stands it on the origin; `width` is its
// diagonal across that range, which any heading fits in.
struct CityPlacement {
  double align[9];
  double centre[3];
  double width = 0;
};
CityPlacement place_city_source(const Scene& scene, const std::string& up, const std::string& name);

// The grid: blocks per row, for `blocks` blocks.
int city_side(int blocks);
// Block `block`'s rigid move of a source placed by `placement`: p' = rotation p + translation
// (row-major 3x3), at its grid cell (block_size apart, `side` per row) and heading
// block x 137.5 degrees about +z.
void city_block_transform(const CityPlacement& placement, int block, int side, double block_size, double rotation[9],
                          double translation[3]);
// `count` cameras (width x height, 60 degrees across) from eye height along the first row of
// blocks up to a view of the whole city.
std::vector<Camera> city_camera_path(int side, double block_size, int count, int width, int height);

// Writes `blocks` blocks (source i % sources) to `ply_path` at SH degree 0: the view-dependent
// bands are not rotated with the copies, so only the base colour is kept. Each block's up axis
// becomes +z, its ground (2nd percentile of height) z = 0, its heading i x 137.5 degrees.
// `path` gets `path_cameras` cameras (width x height, 60 degrees across) from eye height along
// the first row of blocks up to a view of the whole city. Throws flashgs::Error naming the
// source or file.
CityReport write_city_scene(const std::vector<CitySource>& sources, int blocks, const std::string& ply_path,
                            int path_cameras, int width, int height, std::vector<Camera>* path);

}  // namespace flashgs
