// Scene bookkeeping: size, reservation and concatenation.
#include "flashgs/scene.h"

#include "flashgs/error.h"
#include "huge_pages.h"

namespace flashgs {

std::size_t Scene::byte_size() const {
  return (positions.size() + scales.size() + rotations.size() + opacities.size() + sh_dc.size() +
          sh_rest.size()) * sizeof(float);
}

void Scene::reserve(std::size_t n) {
  positions.reserve(n * 3);
  scales.reserve(n * 3);
  rotations.reserve(n * 4);
  opacities.reserve(n);
  sh_dc.reserve(n * 3);
  sh_rest.reserve(n * static_cast<std::size_t>(sh_rest_per_gaussian()));
  // Freshly reserved, filled once by a reader: fewer page faults (huge_pages.h).
  for (const std::vector<float>* array : {&positions, &scales, &rotations, &opacities, &sh_dc, &sh_rest})
    advise_huge_pages(array->data(), array->capacity() * sizeof(float));
}

void Scene::append(const Scene& other) {
  if (other.sh_degree != sh_degree && size() > 0)
    throw Error("cannot append a scene of SH degree " + std::to_string(other.sh_degree) +
                " to one of degree " + std::to_string(sh_degree));
  if (size() == 0) sh_degree = other.sh_degree;
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  scales.insert(scales.end(), other.scales.begin(), other.scales.end());
  rotations.insert(rotations.end(), other.rotations.begin(), other.rotations.end());
  opacities.insert(opacities.end(), other.opacities.begin(), other.opacities.end());
  sh_dc.insert(sh_dc.end(), other.sh_dc.begin(), other.sh_dc.end());
  sh_rest.insert(sh_rest.end(), other.sh_rest.begin(), other.sh_rest.end());
}

}  // namespace flashgs
