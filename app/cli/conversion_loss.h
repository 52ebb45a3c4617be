// What a scene conversion loses: the Gaussians read back from the written file against those
// written (per attribute), and images of both against images of the input.
#pragma once

#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/scene.h"

namespace flashgs::cli {

struct AttributeLoss {
  std::string name;  // "position", "log-scale", ...
  std::string unit;  // "", "degrees"
  double max_error = 0;
  double mean_error = 0;
};

struct ViewLoss {
  std::string camera;
  double psnr_db = 0;  // infinity when the images are identical
};

struct ConversionLoss {
  std::size_t written = 0, read_back = 0;
  int sh_degree_written = 0, sh_degree_read_back = 0;
  std::vector<AttributeLoss> attributes;  // empty when the counts differ
  std::vector<ViewLoss> views;
};

// Compares `read_back` with `written` Gaussian by Gaussian (a writer keeps the order), and the
// CPU renderer's images of `read_back` with those of `input` at `views`, each drawn with its
// own trained kernel (a mark the output lost shows in the images).
ConversionLoss measure_conversion_loss(const Scene& input, const Scene& written, const Scene& read_back,
                                       const std::vector<Camera>& views);
// A few views of `scene` for the comparison: three of the cameras in `cameras_path` when that
// file exists, otherwise three orbit views around the bulk of the Gaussians; at most
// `width` pixels wide.
std::vector<Camera> loss_views(const Scene& scene, const std::string& cameras_path, int width);
// The report, several lines, each ending in a newline.
std::string format_conversion_loss(const ConversionLoss& loss);

}  // namespace flashgs::cli
