// The per-frame plain-data parameters shared by the CPU stages and the CUDA kernels.
#pragma once

#include "flashgs/camera.h"
#include "flashgs/gaussian_math.h"
#include "flashgs/options.h"

namespace flashgs {

gm::CameraParams make_camera_params(const Camera& camera);
gm::GeometryParams make_geometry_params(const RenderOptions& options);

}  // namespace flashgs
