// A scene drawn as pieces of other scenes (a streamed LOD cut): each part names its contents by
// a key, so that a backend holding the scene on the GPU uploads only the parts it lacks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "flashgs/scene.h"

namespace flashgs {

// Gaussians per page of a GPU backend's pool of parts (the CUDA backend's chunk): a part takes
// whole pages, so a cap on GPU memory must allow for each part's last page partly empty.
constexpr std::size_t kScenePartPageGaussians = 256;

// Gaussians [first, first + count) of `source`. Two parts with the same key hold the same
// Gaussians for as long as either is in use (a LOD set's chunk file and offset).
struct ScenePart {
  std::uint64_t key = 0;
  std::shared_ptr<const Scene> source;
  std::size_t first = 0, count = 0;
};

// The parts' Gaussians one after another in one scene (their SH degree and kernel are the
// first part's; every part must share the degree).
std::shared_ptr<Scene> assemble_scene_parts(const std::vector<ScenePart>& parts);
// The same into `scene`, whose arrays are emptied first and keep their capacity: a renderer
// that assembles a new cut every frame reuses the memory of one it no longer draws.
void assemble_scene_parts_into(const std::vector<ScenePart>& parts, Scene& scene);

// The Gaussians of all parts together.
std::uint64_t scene_parts_size(const std::vector<ScenePart>& parts);

}  // namespace flashgs
