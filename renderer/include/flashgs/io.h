// Scene and camera files: INRIA 3DGS PLY and the 3DGS training-output cameras.json.
#pragma once

#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/scene.h"

namespace flashgs {

// Reads a 3DGS PLY, layout taken from its header. Throws flashgs::Error naming the file and
// the problem on anything it cannot read exactly. Gaussians with NaN/Inf attributes are
// dropped and counted in `report`.
Scene load_ply(const std::string& path, LoadReport* report = nullptr);
// Same, from bytes in memory (`name` is used in messages). The fuzz test drives this.
Scene parse_ply(const char* data, std::size_t size, const std::string& name,
                LoadReport* report = nullptr);
// Writes the INRIA layout (binary little endian, logit opacity, log scales).
void save_ply(const Scene& scene, const std::string& path);

// Reads cameras.json. Throws flashgs::Error on a missing file, bad JSON, a missing field, a
// non-finite value or a rotation that is not orthonormal.
std::vector<Camera> load_cameras(const std::string& path);
// Parses the JSON text directly (`name` is used in messages).
std::vector<Camera> parse_cameras(const std::string& json_text, const std::string& name);
void save_cameras(const std::vector<Camera>& cameras, const std::string& path);

}  // namespace flashgs
