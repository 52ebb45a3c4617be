// Coarser levels of detail: neighbouring Gaussians merged into one by moment matching.
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/lod_set.h"
#include "flashgs/scene.h"

namespace flashgs {

// The longest side of the box around the points xyz[3 i .. 3 i + 2] for i in ids[0 .. n), and its
// length: where the builder's k-d tree and a level's pairing split a group.
int longest_axis(const std::vector<float>& xyz, const std::uint32_t* ids, std::size_t n, float* length);

// A Gaussian's weight in a merge: opacity times the area of its ellipsoid's principal sections
// (s0 s1 + s1 s2 + s2 s0, up to pi), so that what covers more of the image counts more.
double merge_weight(const Scene& scene, std::size_t i);

// Appends to `out` one Gaussian matching the weighted moments of scene[first .. first + count):
// position = weighted mean; covariance = weighted mean of (covariance + offset offset^T);
// colour and SH = weighted means; opacity = sum of weights / merged area, clamped to 1, so
// the opacity mass (opacity x area) is kept unless the clamp applies.
void append_merged(const Scene& scene, const std::uint32_t* indices, std::size_t count, Scene& out);

// The next coarser level of one leaf's Gaussians: about half as many, each a merge of a pair
// of near neighbours (split by split along the longest axis; a lone last one is kept as it is).
Scene coarser_level(const Scene& level);

}  // namespace flashgs
