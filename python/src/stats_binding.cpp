// flashgs.FrameStats and flashgs.StageTimes: what a frame cost and did, as the CLI prints it.
#include <utility>

#include <pybind11/numpy.h>

#include "bindings.h"
#include "flashgs/stats.h"

namespace flashgs::python {

void bind_stats(py::module_& m) {
  py::class_<StageTimes>(m, "StageTimes", "Milliseconds per stage, named the same on every backend.")
      .def_readonly("project_ms", &StageTimes::project_ms, "cull, 2D covariance, extent, box, SH to colour")
      .def_readonly("emit_ms", &StageTimes::emit_ms, "Gaussian-tile keys")
      .def_readonly("sort_ms", &StageTimes::sort_ms, "by tile, then depth")
      .def_readonly("ranges_ms", &StageTimes::ranges_ms, "per-tile start and end in the sorted list")
      .def_readonly("blend_ms", &StageTimes::blend_ms, "front-to-back compositing")
      .def_readonly("total_ms", &StageTimes::total_ms)
      .def_readonly("sort_in_blend", &StageTimes::sort_in_blend,
                    "CUDA bin sort: its per-bin blocks ran beside the blend and are in blend_ms")
      .def("as_dict", [](const StageTimes& t) {
        py::dict d;
        d["project"] = t.project_ms;
        d["emit"] = t.emit_ms;
        d["sort"] = t.sort_ms;
        d["ranges"] = t.ranges_ms;
        d["blend"] = t.blend_ms;
        d["total"] = t.total_ms;
        return d;
      }, "stage name -> milliseconds");

  py::class_<FrameStats>(m, "FrameStats", "What one frame did and cost.")
      .def_readonly("kv_pairs", &FrameStats::kv_pairs, "Gaussian-tile pairs emitted")
      .def_readonly("sorted_pairs", &FrameStats::sorted_pairs, "pairs the sort ordered (fewer with CUDA macro bins)")
      .def_readonly("tiles_x", &FrameStats::tiles_x)
      .def_readonly("tiles_y", &FrameStats::tiles_y)
      .def_property_readonly(
          "tile_pair_counts",
          [](const FrameStats& s) -> py::object {
            if (s.tile_pair_counts.empty()) return py::none();
            py::array_t<std::uint32_t> counts({py::ssize_t(s.tiles_y), py::ssize_t(s.tiles_x)});
            std::copy(s.tile_pair_counts.begin(), s.tile_pair_counts.end(), counts.mutable_data());
            return std::move(counts);
          },
          "(tiles_y, tiles_x) uint32 pairs per 16x16 tile; None unless collect_tile_counts was set")
      .def_readonly("max_tile_pairs", &FrameStats::max_tile_pairs)
      .def_readonly("gaussians", &FrameStats::gaussians)
      .def_readonly("visible", &FrameStats::visible, "Gaussians that emitted at least one pair")
      .def_readonly("culled_near", &FrameStats::culled_near)
      .def_readonly("culled_offscreen", &FrameStats::culled_offscreen)
      .def_readonly("culled_low_opacity", &FrameStats::culled_low_opacity)
      .def_readonly("culled_degenerate", &FrameStats::culled_degenerate)
      .def_readonly("culled_by_chunk", &FrameStats::culled_by_chunk)
      .def_readonly("times", &FrameStats::times, "StageTimes of this frame")
      .def_readonly("device_memory_bytes", &FrameStats::device_memory_bytes)
      .def_readonly("device_peak_bytes", &FrameStats::device_peak_bytes)
      .def_readonly("scene_device_bytes", &FrameStats::scene_device_bytes)
      .def("__repr__", [](const FrameStats& s) {
        return "<flashgs.FrameStats " + std::to_string(s.kv_pairs) + " pairs, " + std::to_string(s.visible) +
               " visible, " + std::to_string(s.times.total_ms) + " ms>";
      });
}

}  // namespace flashgs::python
