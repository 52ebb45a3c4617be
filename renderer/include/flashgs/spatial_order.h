// Spatial order of a scene's Gaussians: the CUDA backend lays them out so that neighbours in
// memory are neighbours in space. A warp's Gaussians then meet the same few bins, so the sort's
// counting and scatter passes write runs into each bin rather than a word here and there, and
// the chunk cull sees compact chunks. Scenes in the PlayCanvas formats are stored that way
// already; raw training output is not (pc_playbot in random order: frames 7-10% longer on the
// H200, docs/PERFORMANCE.md).
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/scene.h"

namespace flashgs {

// A permutation of the scene's Gaussians (order[k] = the scene index of the k-th) along a
// Morton curve over 128^3 cells of their bounding box; within a cell, in scene order. A
// non-finite position counts as the first cell's.
std::vector<std::uint32_t> spatial_order(const Scene& scene);

// spatial_order(scene) where it makes runs of 256 consecutive Gaussians (a sample of them)
// markedly more compact than the stored order does; empty where the stored order is about as
// good (then the order is not computed at all when the stored runs are compact already).
std::vector<std::uint32_t> spatial_order_where_it_pays(const Scene& scene);

}  // namespace flashgs
