// The marks trainers and converters leave in scene files to say which kernel a scene was trained
// with, read and written in one place (README "Which kernel a scene is drawn with" lists them).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/splat_kernel.h"

namespace flashgs {

// PLY header comments: Brush's "SplatRenderMode: default|mip" and Postshot's "antialiased 0|1"
// (the last mark wins, as in splat-transform), and ours, "antialias_epsilon E", beside either
// when the epsilon is not gsplat's 0.3. Other comments are ignored.
TrainedKernel kernel_from_ply_comments(const std::vector<std::string>& comments);
// The comments that carry `kernel` into a PLY file (none for an unmarked classic scene).
std::vector<std::string> ply_comments_for(const TrainedKernel& kernel);

// A PLY with Mip-Splatting's per-Gaussian `filter_3D` property: its 2D mip filter (eps 0.1).
TrainedKernel mip_splatting_kernel();
// The "antialiased" bit (0x1) of an SPZ header's flags byte (Niantic's spz library).
TrainedKernel kernel_from_spz_flags(std::uint8_t flags);
// The flags byte that carries `kernel` into an SPZ header (the bit says anti-aliased, not its
// epsilon: the spz library's kernel is gsplat's 0.3).
std::uint8_t spz_flags_for(const TrainedKernel& kernel);
// SOG meta.json's optional "model" entry ("antialiased" or "mip"; "default" or "classic").
// Returns false for a value it does not know (the caller names the file).
bool kernel_from_sog_model(const std::string& model, TrainedKernel& out);
// The "model" entry that carries `kernel` into a SOG meta.json ("antialiased" or "classic";
// empty for an unmarked classic scene).
std::string sog_model_for(const TrainedKernel& kernel);
// Whether a format that stores only "anti-aliased or not" keeps `kernel` whole.
bool kernel_fits_a_flag(const TrainedKernel& kernel);

}  // namespace flashgs
