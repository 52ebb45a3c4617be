// The CPU backend's stages up to the tile lists, for the tests that look at one stage's output.
#pragma once

#include "cpu_frame.h"
#include "flashgs/camera.h"
#include "flashgs/options.h"
#include "flashgs/scene.h"
#include "flashgs/stats.h"

namespace flashgs {
namespace test {

// project, order_by_depth, emit and sort_by_tile on `threads` threads, as the CPU renderer runs
// them: frame's tile lists (tile_start, tile_ids) and stats' pair count are then the frame's.
void build_tile_lists(const Scene& scene, const Camera& camera, const RenderOptions& options, int threads,
                      cpu::Frame& frame, FrameStats& stats);

}  // namespace test
}  // namespace flashgs
