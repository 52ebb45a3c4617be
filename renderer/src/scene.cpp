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

void Scene::append(const Scene& other) { append_range(other, 0, other.size()); }

void Scene::append_range(const Scene& other, std::size_t first, std::size_t count) {
  if (other.sh_degree != sh_degree && size() > 0)
    throw Error("cannot append a scene of SH degree " + std::to_string(other.sh_degree) +
                " to one of degree " + std::to_string(sh_degree));
  if (first > other.size() || count > other.size() - first)
    throw Error("cannot append Gaussians " + std::to_string(first) + ".." + std::to_string(first + count) +
                " of a scene of " + std::to_string(other.size()));
  if (size() == 0) sh_degree = other.sh_degree;
  auto take = [first, count](const std::vector<float>& from, std::size_t per, std::vector<float>& to) {
    to.insert(to.end(), from.begin() + static_cast<std::ptrdiff_t>(first * per),
              from.begin() + static_cast<std::ptrdiff_t>((first + count) * per));
  };
  take(other.positions, 3, positions);
  take(other.scales, 3, scales);
  take(other.rotations, 4, rotations);
  take(other.opacities, 1, opacities);
  take(other.sh_dc, 3, sh_dc);
  take(other.sh_rest, static_cast<std::size_t>(other.sh_rest_per_gaussian()), sh_rest);
}

}  // namespace flashgs
