// Assembling a scene from parts, which is what Renderer::set_scene_parts does by default.
#include "flashgs/scene_parts.h"

#include "flashgs/renderer.h"

namespace flashgs {

std::uint64_t scene_parts_size(const std::vector<ScenePart>& parts) {
  std::uint64_t total = 0;
  for (const ScenePart& p : parts) total += p.count;
  return total;
}

std::shared_ptr<Scene> assemble_scene_parts(const std::vector<ScenePart>& parts) {
  auto scene = std::make_shared<Scene>();
  assemble_scene_parts_into(parts, *scene);
  return scene;
}

void assemble_scene_parts_into(const std::vector<ScenePart>& parts, Scene& scene) {
  for (std::vector<float>* v : {&scene.positions, &scene.scales, &scene.rotations, &scene.opacities, &scene.sh_dc,
                                &scene.sh_rest})
    v->clear();
  scene.sh_degree = 0;
  scene.trained_kernel = TrainedKernel{};
  if (parts.empty()) return;
  scene.sh_degree = parts.front().source->sh_degree;
  scene.trained_kernel = parts.front().source->trained_kernel;
  scene.reserve(scene_parts_size(parts));
  for (const ScenePart& p : parts) scene.append_range(*p.source, p.first, p.count);  // checks the degree
}

void Renderer::set_scene_parts(const std::vector<ScenePart>& parts, std::uint64_t) {
  set_scene(assemble_scene_parts(parts));
}

}  // namespace flashgs
