// A city made of one LOD set's instances in seconds: a grid of blocks at distinct headings whose
// leaves name the base set's chunk files (nothing copied), and an instanced set made plain.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/lod_build.h"
#include "flashgs/lod_set.h"

namespace flashgs {

struct LodCityOptions {
  int blocks = 0;
  double spacing = 0;  // between block centres, in scene units; 0: 1.1 x the base's width across
  std::string up = "+z";  // the base's up axis: +x -x +y -y +z -z
  int path_cameras = 60;  // the fly-through written to cameras.json
  int width = 1920, height = 1080;
  bool materialize = false;  // write each block's chunks moved for real: a plain set, blocks x the base's bytes
  LodChunkFormat chunk_format = LodChunkFormat::ply;  // of the chunks `materialize` writes
};

struct LodCityReport {
  int blocks = 0, side = 0;
  double spacing = 0;
  std::vector<std::uint64_t> level_gaussians;
  LodBox bound;
  int files = 0;                   // chunk files the city's meta names
  std::uint64_t chunk_bytes = 0;   // of the chunk files as the city streams them (each block's own)
  std::uint64_t written_bytes = 0; // to the city's folder
};

// Writes the city of `options.blocks` instances of the set at `base` (lod-meta.json or its
// folder) into `out_folder` (new or empty): lod-meta.json whose files are the base's, reached
// through the link `out_folder`/base -> the base's folder (relative, so that the two folders
// move together), and cameras.json with the city's fly-through. Each block stands the base up
// (`up` to +z), puts its ground (2nd percentile of the coarsest level's heights) at z = 0 and
// turns it to heading block x 137.5 degrees, on the grid of `generate city`. With `materialize`
// the chunks are written moved instead, and the set is plain. Throws flashgs::Error naming the
// file or option.
LodCityReport write_lod_city(const std::string& base, const std::string& out_folder, const LodCityOptions& options);

// Writes `set` into `out_folder` (new or empty) as a plain set: each entry of set.files read,
// moved by its instance and written as a chunk of its own (`format`), the leaves in the same
// order. Returns the bytes written.
std::uint64_t materialize_lod_set(const LodSet& set, const std::string& out_folder, LodChunkFormat format);

}  // namespace flashgs
