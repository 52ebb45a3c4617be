// flashgs.Camera and load_cameras: cameras from cameras.json, from gsplat's viewmat + K, or
// looking at a point; pinhole, OpenCV axes (x right, y down, z forward).
#include <cmath>
#include <string>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "flashgs/camera.h"
#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"

namespace flashgs::python {

namespace {

// The largest image side cameras.json accepts, for cameras made here too.
constexpr int kMaxSide = 65536;

void check_size(int width, int height) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw Error("width and height must be whole numbers in 1.." + std::to_string(kMaxSide) + " (got " +
                std::to_string(width) + "x" + std::to_string(height) + ")");
}

std::vector<double> finite_values(py::handle object, const std::string& name, const std::vector<py::ssize_t>& shape) {
  const std::vector<float> values = checked_floats(host_float_array(object, name), name, shape);
  for (float v : values)
    if (!std::isfinite(v)) throw Error(name + ": every value must be finite");
  return std::vector<double>(values.begin(), values.end());
}

// gsplat's camera: world-to-camera `viewmat` (4, 4) and intrinsics `K` (3, 3), whose principal
// point counts pixel centres at +0.5 (ours are at whole numbers).
Camera from_viewmat(py::handle viewmat_in, py::handle k_in, int width, int height, const std::string& name) {
  check_size(width, height);
  const std::vector<double> v = finite_values(viewmat_in, "viewmat", {4, 4});
  const std::vector<double> k = finite_values(k_in, "K", {3, 3});
  const double rows[9] = {v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]};
  check_rotation(rows, "viewmat");
  if (v[12] != 0 || v[13] != 0 || v[14] != 0 || v[15] != 1) throw Error("viewmat: the last row must be 0 0 0 1");
  if (!(k[0] > 0) || !(k[4] > 0)) throw Error("K: fx and fy (K[0, 0], K[1, 1]) must be positive");
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = static_cast<float>(k[0]);
  camera.fy = static_cast<float>(k[4]);
  camera.cx = static_cast<float>(k[2] - 0.5);
  camera.cy = static_cast<float>(k[5] - 0.5);
  const double t[3] = {v[3], v[7], v[11]};
  for (int r = 0; r < 9; ++r) camera.rotation[r] = static_cast<float>(rows[r]);
  for (int c = 0; c < 3; ++c)  // centre = -R^T t
    camera.position[c] = static_cast<float>(-(rows[c] * t[0] + rows[3 + c] * t[1] + rows[6 + c] * t[2]));
  camera.name = name;
  return camera;
}

Camera look_at(py::handle eye_in, py::handle target_in, py::handle up_in, int width, int height, float fov) {
  check_size(width, height);
  if (!(fov >= 1.0f && fov <= 179.0f)) throw Error("fov: " + std::to_string(fov) + " is not in [1, 179] degrees");
  const std::vector<double> e = finite_values(eye_in, "eye", {3});
  const std::vector<double> t = finite_values(target_in, "target", {3});
  const std::vector<double> u = finite_values(up_in, "up", {3});
  const float eye[3] = {float(e[0]), float(e[1]), float(e[2])};
  const float target[3] = {float(t[0]), float(t[1]), float(t[2])};
  const float up[3] = {float(u[0]), float(u[1]), float(u[2])};
  Camera camera = look_at_camera(eye, target, up, width, height, fov);
  camera.name = "look_at";
  return camera;
}

py::array_t<float> matrix(std::vector<float>&& values, py::ssize_t rows) {
  const py::ssize_t columns = static_cast<py::ssize_t>(values.size()) / rows;
  return array_owning(std::move(values), {rows, columns});
}

}  // namespace

void bind_camera(py::module_& m) {
  py::class_<Camera>(m, "Camera", "A pinhole camera, OpenCV axes (x right, y down, z forward).")
      .def_static("from_viewmat", &from_viewmat, py::arg("viewmat"), py::arg("K"), py::arg("width"),
                  py::arg("height"), py::arg("name") = "",
                  "A camera from gsplat's world-to-camera `viewmat` (4, 4) and intrinsics `K` (3, 3).")
      .def_static("look_at", &look_at, py::arg("eye"), py::arg("target"), py::arg("up") = std::vector<float>{0, -1, 0},
                  py::arg("width") = 1920, py::arg("height") = 1080, py::arg("fov") = 60.0f,
                  "A camera at `eye` looking at `target`, `up` up in the image, horizontal field of view `fov` "
                  "degrees (as `flashgs render --eye --look-at --up --fov`).")
      .def_readonly("width", &Camera::width)
      .def_readonly("height", &Camera::height)
      .def_readonly("fx", &Camera::fx)
      .def_readonly("fy", &Camera::fy)
      .def_readonly("cx", &Camera::cx, "principal point x, pixel centres at whole numbers")
      .def_readonly("cy", &Camera::cy, "principal point y, pixel centres at whole numbers")
      .def_readonly("name", &Camera::name)
      .def_property_readonly(
          "position", [](const Camera& c) { return matrix({c.position[0], c.position[1], c.position[2]}, 1).reshape({3}); },
          "(3,) camera centre in world space")
      .def_property_readonly(
          "rotation", [](const Camera& c) { return matrix(std::vector<float>(c.rotation, c.rotation + 9), 3); },
          "(3, 3) world-to-camera rotation")
      .def_property_readonly(
          "viewmat",
          [](const Camera& c) {
            std::vector<float> v(16, 0.0f);
            for (int r = 0; r < 3; ++r) {
              double t = 0;
              for (int k = 0; k < 3; ++k) {
                v[r * 4 + k] = c.rotation[r * 3 + k];
                t -= double(c.rotation[r * 3 + k]) * c.position[k];
              }
              v[r * 4 + 3] = static_cast<float>(t);
            }
            v[15] = 1.0f;
            return matrix(std::move(v), 4);
          },
          "(4, 4) world-to-camera matrix, as gsplat takes it")
      .def_property_readonly(
          "K", [](const Camera& c) { return matrix({c.fx, 0, c.cx + 0.5f, 0, c.fy, c.cy + 0.5f, 0, 0, 1}, 3); },
          "(3, 3) intrinsics, as gsplat takes them (principal point with pixel centres at +0.5)")
      .def(
          "resized",
          [](const Camera& c, int width, int height) {
            check_size(width, height);
            return c.resized(width, height);
          },
          py::arg("width"), py::arg("height"),
           "The same pose and field of view at another resolution.")
      .def("__repr__", [](const Camera& c) {
        return "<flashgs.Camera \"" + c.name + "\" " + std::to_string(c.width) + "x" + std::to_string(c.height) + ">";
      });

  m.def(
      "load_cameras",
      [](const std::string& path) {
        py::gil_scoped_release unlocked;
        return load_cameras(path);
      },
      py::arg("path"), "The cameras of a 3DGS cameras.json, in file order.");
}

}  // namespace flashgs::python
