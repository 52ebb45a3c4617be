// Scene: the Gaussians of a trained 3DGS model as a structure of arrays, activations applied.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "flashgs/splat_kernel.h"

namespace flashgs {

// Number of SH coefficients per colour channel for a degree (1, 4, 9, 16).
constexpr int sh_coefficient_count(int degree) { return (degree + 1) * (degree + 1); }

struct Scene {
  int sh_degree = 0;  // 0..3; degree 0 scenes store no sh_rest at all
  // Per Gaussian, 3 floats each: world position, linear scale (exp applied).
  std::vector<float> positions;
  std::vector<float> scales;
  // Per Gaussian, 4 floats: unit quaternion (w, x, y, z).
  std::vector<float> rotations;
  // Per Gaussian: opacity in [0, 1] (sigmoid applied).
  std::vector<float> opacities;
  // Per Gaussian, 3 floats: the degree-0 SH coefficient (RGB).
  std::vector<float> sh_dc;
  // Per Gaussian, (sh_coefficient_count(sh_degree) - 1) * 3 floats, coefficient-major:
  // [k][channel], k = 1..K-1. Empty for degree 0.
  std::vector<float> sh_rest;
  // The kernel the file says the scene was trained with (classic and unmarked when it says
  // nothing): what `--kernel auto` and the viewer draw it with.
  TrainedKernel trained_kernel;

  std::size_t size() const { return opacities.size(); }
  int sh_rest_per_gaussian() const { return (sh_coefficient_count(sh_degree) - 1) * 3; }
  // Bytes of Gaussian data (what a backend has to keep resident).
  std::size_t byte_size() const;
  void reserve(std::size_t n);
  // Appends every Gaussian of `other` (same SH degree required; throws otherwise); the trained
  // kernel stays this scene's.
  void append(const Scene& other);
  // Appends Gaussians [first, first + count) of `other` (the same rule for the SH degree).
  void append_range(const Scene& other, std::size_t first, std::size_t count);
};

// What a loader dropped or repaired, reported by `flashgs info` and the viewer.
struct LoadReport {
  std::string path;
  std::size_t vertices_in_file = 0;
  std::size_t dropped_non_finite = 0;       // NaN/Inf in any used attribute
  std::size_t repaired_zero_quaternion = 0; // |q| == 0 replaced by identity
  std::size_t ignored_properties = 0;       // properties present but not used (normals, ...)
  std::vector<std::string> ignored_property_names;
  int sh_degree_in_file = 0;
  // Filled by load_scene_file: format_name() and format_quantisation() of the file's format,
  // and the seconds spent reading the bytes and decoding them.
  std::string format;
  std::string quantisation;
  double read_seconds = 0;
  double decode_seconds = 0;
};

}  // namespace flashgs
