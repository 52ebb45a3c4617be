#include "cpu_stages.h"

#include "flashgs/frame_params.h"

namespace flashgs {
namespace test {

void build_tile_lists(const Scene& scene, const Camera& camera, const RenderOptions& options, int threads,
                      cpu::Frame& frame, FrameStats& stats) {
  frame.threads = threads;
  frame.camera = make_camera_params(camera);
  frame.geometry = make_geometry_params(options);
  cpu::project(scene, options, frame, stats);
  cpu::order_by_depth(frame, static_cast<std::int64_t>(scene.size()));
  cpu::emit(options, frame, stats);
  double ranges_ms = 0;
  cpu::sort_by_tile(frame, stats, &ranges_ms);
}

}  // namespace test
}  // namespace flashgs
