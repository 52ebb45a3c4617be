// flashgs.Scene, load_scene and Scene.from_arrays: a scene from any file we read or from arrays
// in gsplat's layout, its arrays as read-only numpy views.
#include <cmath>
#include <utility>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "flashgs/error.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "scene_level.h"

namespace flashgs::python {

namespace {

// Throws naming the array and the first row with a value that `ok` refuses.
template <typename Ok>
void check_rows(const std::vector<float>& values, int per_row, const std::string& name, const char* rule, Ok ok) {
  for (std::size_t k = 0; k < values.size(); ++k)
    if (!ok(values[k]))
      throw Error(name + ": row " + std::to_string(k / per_row) + " holds " + std::to_string(values[k]) + "; " + rule);
}

bool finite(float v) { return std::isfinite(v); }

// The SH degree whose coefficient count per channel is `count` (1, 4, 9, 16), or -1.
int degree_of(py::ssize_t count) {
  for (int degree = 0; degree <= 3; ++degree)
    if (sh_coefficient_count(degree) == count) return degree;
  return -1;
}

PyScene scene_from_arrays(py::handle means_in, py::handle quats_in, py::handle scales_in, py::handle opacities_in,
                          py::handle sh_in, py::handle kernel) {
  const py::array_t<float> means = host_float_array(means_in, "means");
  const py::ssize_t n = means.ndim() == 2 ? means.shape(0) : -1;
  Scene scene;
  scene.positions = checked_floats(means, "means", {-1, 3});
  scene.rotations = checked_floats(host_float_array(quats_in, "quats"), "quats", {n, 4});
  scene.scales = checked_floats(host_float_array(scales_in, "scales"), "scales", {n, 3});
  py::array_t<float> opacities = host_float_array(opacities_in, "opacities");
  if (opacities.ndim() == 2 && opacities.shape(1) == 1) opacities = opacities.reshape({n});
  scene.opacities = checked_floats(opacities, "opacities", {n});
  py::array_t<float> sh = host_float_array(sh_in, "sh");
  if (sh.ndim() == 2 && sh.shape(1) == 3) sh = sh.reshape({n, py::ssize_t{1}, py::ssize_t{3}});
  scene.sh_degree = sh.ndim() == 3 ? degree_of(sh.shape(1)) : -1;
  if (scene.sh_degree < 0)
    throw Error("sh: expected shape (N, K, 3) with K = 1, 4, 9 or 16 coefficients (SH degree 0-3), got " +
                shape_text(sh));
  const std::vector<float> coefficients = checked_floats(sh, "sh", {n, sh.shape(1), 3});

  check_rows(scene.positions, 3, "means", "every value must be finite", finite);
  check_rows(scene.scales, 3, "scales", "scales must be finite and positive (linear, not log)",
             [](float v) { return std::isfinite(v) && v > 0; });
  check_rows(scene.opacities, 1, "opacities", "opacities must be in [0, 1] (after the sigmoid)",
             [](float v) { return v >= 0 && v <= 1; });
  check_rows(coefficients, sh.shape(1) * 3, "sh", "every value must be finite", finite);
  check_rows(scene.rotations, 4, "quats", "every value must be finite", finite);
  for (std::size_t i = 0; i < scene.opacities.size(); ++i) {
    float* q = &scene.rotations[i * 4];
    const double norm = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
    if (!(norm > 0) || !std::isfinite(norm))
      throw Error("quats: row " + std::to_string(i) + " has no direction (a zero quaternion)");
    // One of unit length to float rounding stays as it is, so that a scene's own arrays come back
    // bit for bit (normalising again would move some components by an ulp).
    if (std::abs(norm - 1.0) > 1e-6)
      for (int k = 0; k < 4; ++k) q[k] = static_cast<float>(q[k] / norm);
  }

  // gsplat's (N, K, 3) coefficients split into the DC term and the rest, [k][channel] per Gaussian.
  const std::size_t per_gaussian = coefficients.size() / std::max<std::size_t>(scene.opacities.size(), 1);
  for (std::size_t i = 0; i < scene.opacities.size(); ++i) {
    const float* c = &coefficients[i * per_gaussian];
    scene.sh_dc.insert(scene.sh_dc.end(), c, c + 3);
    scene.sh_rest.insert(scene.sh_rest.end(), c + 3, c + per_gaussian);
  }
  if (!kernel.is_none()) scene.trained_kernel = {kernel_from(kernel, "kernel"), "Scene.from_arrays(kernel=...)"};
  return PyScene{std::make_shared<const Scene>(std::move(scene)), std::nullopt};
}

PyScene load(const std::string& path, std::optional<int> lod) {
  if (lod && *lod < 0) throw Error("lod: " + std::to_string(*lod) + " is not a level (0 = finest)");
  py::gil_scoped_release unlocked;
  const SceneLocation location = locate_scene(path);
  LoadReport report;
  auto scene = std::make_shared<const Scene>(load_scene_at_level(location.ply, lod.value_or(-1), &report));
  return PyScene{std::move(scene), std::move(report)};
}

py::object report_dict(const PyScene& s) {
  if (!s.report) return py::none();
  const LoadReport& r = *s.report;
  py::dict d;
  d["path"] = r.path;
  d["format"] = r.format;
  d["quantisation"] = r.quantisation;
  d["vertices_in_file"] = r.vertices_in_file;
  d["dropped_non_finite"] = r.dropped_non_finite;
  d["repaired_zero_quaternion"] = r.repaired_zero_quaternion;
  d["ignored_property_names"] = r.ignored_property_names;
  d["sh_degree_in_file"] = r.sh_degree_in_file;
  d["read_seconds"] = r.read_seconds;
  d["decode_seconds"] = r.decode_seconds;
  return std::move(d);
}

void save(const PyScene& s, const std::string& path) {
  if (!writable_format_for(path))
    throw Error(path + ": unknown scene format (the name picks it: " + writable_scene_extensions() + ")");
  py::gil_scoped_release unlocked;
  save_scene_file(*s.scene, path);
}

}  // namespace

void bind_scene(py::module_& m) {
  using N = py::ssize_t;
  py::class_<PyScene>(m, "Scene", "Gaussians as the renderer holds them (activations applied), read-only.")
      .def_static("from_arrays", &scene_from_arrays, py::arg("means"), py::arg("quats"), py::arg("scales"),
                  py::arg("opacities"), py::arg("sh"), py::arg("kernel") = py::none(),
                  "A scene from arrays in gsplat's layout: means (N, 3), quats (N, 4) w x y z (normalised here), "
                  "scales (N, 3) linear, opacities (N,) in [0, 1], sh (N, K, 3) with K = 1, 4, 9 or 16 (or (N, 3) "
                  "for the DC term alone). numpy arrays, torch tensors or CUDA arrays (copied once); the kernel it "
                  "was trained with (`render(kernel=\"auto\")` draws with it) is classic unless given.")
      .def("__len__", [](const PyScene& s) { return s.scene->size(); })
      .def("__repr__", [](const PyScene& s) {
        return "<flashgs.Scene " + std::to_string(s.scene->size()) + " Gaussians, SH degree " +
               std::to_string(s.scene->sh_degree) + ", kernel " + s.scene->trained_kernel.kernel.spec() + ">";
      })
      .def_property_readonly("sh_degree", [](const PyScene& s) { return s.scene->sh_degree; })
      .def_property_readonly(
          "means", [](py::object self) {
            const Scene& s = *self.cast<const PyScene&>().scene;
            return readonly_view(s.positions, {N(s.size()), 3}, self);
          }, "(N, 3) float32 world positions (a read-only view)")
      .def_property_readonly(
          "quats", [](py::object self) {
            const Scene& s = *self.cast<const PyScene&>().scene;
            return readonly_view(s.rotations, {N(s.size()), 4}, self);
          }, "(N, 4) float32 unit quaternions, w x y z (a read-only view)")
      .def_property_readonly(
          "scales", [](py::object self) {
            const Scene& s = *self.cast<const PyScene&>().scene;
            return readonly_view(s.scales, {N(s.size()), 3}, self);
          }, "(N, 3) float32 linear scales (a read-only view)")
      .def_property_readonly(
          "opacities", [](py::object self) {
            const Scene& s = *self.cast<const PyScene&>().scene;
            return readonly_view(s.opacities, {N(s.size())}, self);
          }, "(N,) float32 opacities in [0, 1] (a read-only view)")
      .def_property_readonly(
          "sh_dc", [](py::object self) {
            const Scene& s = *self.cast<const PyScene&>().scene;
            return readonly_view(s.sh_dc, {N(s.size()), 3}, self);
          }, "(N, 3) float32 degree-0 SH coefficients (a read-only view)")
      .def_property_readonly(
          "sh_rest", [](py::object self) {
            const Scene& s = *self.cast<const PyScene&>().scene;
            return readonly_view(s.sh_rest, {N(s.size()), N(sh_coefficient_count(s.sh_degree) - 1), 3}, self);
          }, "(N, K - 1, 3) float32 higher SH coefficients (a read-only view; K - 1 = 0 at degree 0)")
      .def_property_readonly(
          "sh", [](const PyScene& self) {
            const Scene& s = *self.scene;
            const std::size_t rest = static_cast<std::size_t>(s.sh_rest_per_gaussian());
            std::vector<float> all;
            all.reserve(s.size() * (rest + 3));
            for (std::size_t i = 0; i < s.size(); ++i) {
              all.insert(all.end(), &s.sh_dc[i * 3], &s.sh_dc[i * 3] + 3);
              all.insert(all.end(), s.sh_rest.begin() + i * rest, s.sh_rest.begin() + (i + 1) * rest);
            }
            return array_owning(std::move(all), {N(s.size()), N(sh_coefficient_count(s.sh_degree)), 3});
          }, "(N, K, 3) float32 SH coefficients, DC first, as gsplat takes them (a copy)")
      .def_property_readonly("kernel", [](const PyScene& s) { return s.scene->trained_kernel.kernel; },
                             "the kernel the scene was trained with (classic when its file names none)")
      .def_property_readonly("kernel_source", [](const PyScene& s) { return s.scene->trained_kernel.source; },
                             "what named the kernel (a PLY comment, an SPZ flag, ...); empty when nothing did")
      .def_property_readonly("load_report", &report_dict,
                             "what the loader read and dropped (a dict), or None for a scene made from arrays")
      .def("save", &save, py::arg("path"), "Writes the scene as INRIA PLY (.ply) or .splat, whole or not at all.");

  m.def("load_scene", &load, py::arg("path"), py::arg("lod") = py::none(),
        "Loads a scene: a file in any format flashgs reads (INRIA or compressed PLY, .splat, SPZ, SOG), a folder "
        "holding point_cloud.ply or a SOG set, or a 3DGS training output folder; `lod` picks a SOG LOD level.");
}

}  // namespace flashgs::python
