// The fp64 brute-force reference: every pixel blends every Gaussian in depth order.
#pragma once

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "flashgs/scene.h"

namespace flashgs {

// A window of pixels [x0, x0 + width) x [y0, y0 + height) of a camera's image.
struct PixelWindow {
  int x0 = 0, y0 = 0, width = -1, height = -1;  // width/height -1: the whole image
};

// Renders in double precision with no tiles, no boxes and no extent: each pixel composites
// all Gaussians sorted by (depth, index) under the 3DGS rules (near cull z <= 0.2, +0.3
// dilation, alpha = min(0.99, o e^power), skip alpha < 1/255, stop before T < 1e-4).
// Only options.background and options.sh_degree_cap are used. Cost is pixels x Gaussians, so
// meant for small scenes and crops (Gaussians that cannot reach alpha 1/255 anywhere in the
// window are skipped exactly, with the same minimum-over-a-rectangle test as the tile test).
Image render_reference(const Scene& scene, const Camera& camera, const RenderOptions& options,
                       PixelWindow window = {});

// Copies a window out of a full image (to compare with a reference crop).
Image crop_image(const Image& image, const PixelWindow& window);

}  // namespace flashgs
