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

// Which pixels a Gaussian may reach in the reference.
enum class ReferenceFootprint {
  unbounded,  // every pixel where alpha >= 1/255: the image the rules define
  box_3dgs,   // only the tiles of 3DGS's box (radius ceil(3 sqrt(mid + sqrt(max(0.1, mid^2 -
              // det)))), getRect's 16x16 tiles): the original rasterizer's image, in double
};

// Renders in double precision with no tiles and no extent (unless `footprint` asks for 3DGS's
// box): each pixel composites all Gaussians sorted by (depth, index) under the 3DGS rules
// (near cull z <= 0.2, the kernel's dilation and, anti-aliased, its opacity compensation, alpha =
// min(0.99, o e^power), skip alpha < 1/255, stop before T < 1e-4). Only options.background,
// options.sh_degree_cap and options.kernel are used. Cost is
// pixels x Gaussians, so meant for small scenes and crops (Gaussians that cannot reach alpha
// 1/255 anywhere in the window are skipped exactly, with the same minimum-over-a-rectangle
// test as the tile test).
Image render_reference(const Scene& scene, const Camera& camera, const RenderOptions& options,
                       PixelWindow window = {}, ReferenceFootprint footprint = ReferenceFootprint::unbounded);

// Copies a window out of a full image (to compare with a reference crop).
Image crop_image(const Image& image, const PixelWindow& window);

}  // namespace flashgs
