// flashgs.Renderer: a backend (CPU or CUDA) that keeps the scene it last drew and renders frames
// with the GIL released, one at a time per renderer.
#include <cmath>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include <pybind11/stl.h>

#include "arrays.h"
#include "backend_factory.h"
#include "bindings.h"
#include "flashgs/error.h"
#include "flashgs/frame_memory.h"

namespace flashgs::python {

namespace {

class PyRenderer {
 public:
  PyRenderer(const std::string& backend, int threads) {
    if (backend != "auto" && backend != "cpu" && backend != "cuda")
      throw Error("backend: expected \"auto\", \"cpu\" or \"cuda\", got \"" + backend + "\"");
    if (threads < 0) throw Error("threads: " + std::to_string(threads) + " is negative (0 = every core)");
    m_renderer = cli::create_backend(backend, threads);
  }

  std::string name() const { return m_renderer->name(); }

  // One frame: the image (H, W, 3) float32 and its statistics.
  py::tuple render(const PyScene& scene, const Camera& camera, const RenderOptions& options) {
    check_fits(camera, scene.scene->size());
    Image image;
    FrameStats stats;
    on_scene(scene, [&] { m_renderer->render(camera, options, image, &stats); });
    const py::ssize_t h = image.height, w = image.width;
    return py::make_tuple(array_owning(std::move(image.rgb), {h, w, 3}), std::move(stats));
  }

  // One frame into `out`, a CUDA array of (H, W, 3) float32 (a torch tensor on the GPU): the
  // image never leaves the device. Returns the statistics.
  FrameStats render_into(const PyScene& scene, const Camera& camera, const RenderOptions& options,
                         const py::object& out) {
    const DeviceArray target = writable_cuda_array(out, "out", {camera.height, camera.width, 3});
    check_fits(camera, scene.scene->size());
    FrameStats stats;
    on_scene(scene, [&] { cli::render_to_device(*m_renderer, camera, options, target.data, target.stream, &stats, "out"); });
    return stats;
  }

 private:
  // Runs `frame` with the GIL released, one frame at a time, once the renderer holds `scene`
  // (uploaded only when it changed).
  template <typename Frame>
  void on_scene(const PyScene& scene, Frame frame) {
    py::gil_scoped_release unlocked;
    std::lock_guard<std::mutex> one_frame_at_a_time(m_mutex);
    if (m_scene != scene.scene) {
      m_renderer->set_scene(scene.scene);
      m_scene = scene.scene;
    }
    frame();
  }

  // Refuses a frame whose working memory this process cannot get, as `flashgs render` does.
  void check_fits(const Camera& camera, std::size_t gaussians) const {
    const bool cpu = m_renderer->name().rfind("cpu", 0) == 0;
    // The pairs are unknown before the frame: one per Gaussian is the floor of a scene in view.
    const FrameMemory need =
        estimate_frame_memory(cpu ? BackendKind::cpu : BackendKind::cuda, gaussians, camera.width, camera.height,
                              gaussians, static_cast<int>(std::thread::hardware_concurrency()));
    const std::string shortfall = frame_memory_shortfall(need, camera.width, camera.height, available_host_memory());
    if (!shortfall.empty()) throw Error("width, height: " + shortfall);
  }

  std::unique_ptr<Renderer> m_renderer;
  std::shared_ptr<const Scene> m_scene;  // the scene m_renderer holds
  std::mutex m_mutex;
};

// `camera` at width x height; a size left out follows the other at the camera's aspect ratio.
Camera sized(const Camera& camera, std::optional<int> width, std::optional<int> height) {
  if (!width && !height) return camera;
  const int w = width ? *width : static_cast<int>(std::lround(double(*height) * camera.width / camera.height));
  const int h = height ? *height : static_cast<int>(std::lround(double(*width) * camera.height / camera.width));
  if (w < 1 || h < 1 || w > 65536 || h > 65536)
    throw Error("width, height: " + std::to_string(w) + "x" + std::to_string(h) + " is not a size in 1..65536");
  return camera.resized(w, h);
}

}  // namespace

void bind_renderer(py::module_& m) {
  py::class_<PyRenderer>(m, "Renderer",
                         "A rendering backend. It keeps the scene it drew last (the CUDA backend uploads a scene "
                         "once); frames are rendered with the GIL released, one at a time per Renderer.")
      .def(py::init<const std::string&, int>(), py::arg("backend") = "auto", py::arg("threads") = 0,
           "backend: \"cpu\", \"cuda\" or \"auto\" (CUDA when a device works); threads: the CPU backend's "
           "threads, 0 = every core.")
      .def_property_readonly("name", &PyRenderer::name, "the backend and its device, e.g. \"cpu (2 threads)\"")
      .def(
          "render",
          [](PyRenderer& self, const PyScene& scene, py::object camera, std::optional<int> width,
             std::optional<int> height, std::optional<PyRenderOptions> options, const py::kwargs& switches) {
            const PyRenderOptions chosen = with_options(options.value_or(PyRenderOptions{}), switches);
            const RenderOptions resolved = chosen.resolved(*scene.scene);
            if (py::isinstance<Camera>(camera))
              return py::object(self.render(scene, sized(camera.cast<const Camera&>(), width, height), resolved));
            if (!py::isinstance<py::iterable>(camera))
              throw Error("camera: expected a Camera or a sequence of them, got " + py::repr(camera).cast<std::string>());
            py::list frames;  // a sequence of cameras: one (image, stats) each
            for (py::handle one : camera) {
              if (!py::isinstance<Camera>(one))
                throw Error("camera: expected a Camera or a sequence of them, got " +
                            py::repr(one).cast<std::string>());
              frames.append(self.render(scene, sized(one.cast<const Camera&>(), width, height), resolved));
            }
            return py::object(std::move(frames));
          },
          py::arg("scene"), py::arg("camera"), py::arg("width") = py::none(), py::arg("height") = py::none(),
          py::arg("options") = py::none(),
          "Renders `camera` (or each of a sequence of cameras) of `scene`: (image, stats) with the image an "
          "(H, W, 3) float32 numpy array, row 0 at the top. width/height resize the camera (field of view kept); "
          "keywords set RenderOptions on top of `options`.")
      .def(
          "render_into",
          [](PyRenderer& self, const PyScene& scene, const Camera& camera, py::object out, std::optional<int> width,
             std::optional<int> height, std::optional<PyRenderOptions> options, const py::kwargs& switches) {
            const PyRenderOptions chosen = with_options(options.value_or(PyRenderOptions{}), switches);
            return self.render_into(scene, sized(camera, width, height), chosen.resolved(*scene.scene), out);
          },
          py::arg("scene"), py::arg("camera"), py::arg("out"), py::arg("width") = py::none(),
          py::arg("height") = py::none(), py::arg("options") = py::none(),
          "Renders `camera` of `scene` into `out`, a CUDA array (__cuda_array_interface__, e.g. a torch tensor "
          "on the GPU) of shape (H, W, 3) float32, C-contiguous, on the CUDA backend: the image stays on the "
          "device. The frame waits for the work queued on the array's stream and is finished when this "
          "returns. Returns the FrameStats.")
      .def_static(
          "frame_size",
          [](const Camera& camera, std::optional<int> width, std::optional<int> height) {
            const Camera c = sized(camera, width, height);
            return py::make_tuple(c.width, c.height);
          },
          py::arg("camera"), py::arg("width") = py::none(), py::arg("height") = py::none(),
          "(width, height) of the frame render() makes of `camera` with these width/height arguments.");
}

}  // namespace flashgs::python
