// Scene and camera files: INRIA 3DGS PLY and the 3DGS training-output cameras.json.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs {

// Where a scene named by the user lives: the PLY to load and its cameras.json.
struct SceneLocation {
  std::string ply;
  std::string cameras;  // may not exist
};
// `path` is a scene file, a folder holding point_cloud.ply, a SOG folder (lod-meta.json of a
// LOD set, or meta.json of one chunk), or a 3DGS training output folder
// (point_cloud/iteration_<N>/point_cloud.ply, the highest N). Throws flashgs::Error with one
// line naming the path and the problem for an empty path, a missing path, a folder holding
// no scene, or a FIFO, device or link loop where the PLY should be; no file is opened.
SceneLocation locate_scene(const std::string& path);
// What a scene argument may name, as the command-line help of the CLI and the viewer says it.
inline constexpr const char kSceneArgumentHelp[] =
    "scene file (INRIA or PlayCanvas compressed PLY, .splat, SPZ, SOG meta.json or lod-meta.json), a folder holding "
    "point_cloud.ply or a SOG set, or a 3DGS training output folder (default: the bundled demo scene)";
inline constexpr const char kLodOptionHelp[] =
    "level of a SOG LOD set, 0 = finest (default: the finest that fits in memory)";
// cameras.json beside the PLY, or at the model root of a training output
// (<model>/point_cloud/iteration_<N>/point_cloud.ply -> <model>/cameras.json).
std::string default_cameras_path(const std::string& ply_path);

// Reads a 3DGS PLY, layout taken from its header. Throws flashgs::Error naming the file and
// the problem on anything it cannot read exactly. Gaussians with NaN/Inf attributes are
// dropped and counted in `report`. `progress` (see load_progress.h) follows the bytes read and
// the Gaussians decoded; its cancel request throws flashgs::LoadCancelled.
Scene load_ply(const std::string& path, LoadReport* report = nullptr, LoadProgress* progress = nullptr);
// Same, from bytes in memory (`name` is used in messages). The fuzz test drives this.
Scene parse_ply(const char* data, std::size_t size, const std::string& name,
                LoadReport* report = nullptr, LoadProgress* progress = nullptr);
// Writes the INRIA layout (binary little endian, logit opacity, log scales), whole or not at
// all (write_file_atomically). A negative scale has no log: its magnitude is written, which
// gives the same covariance (see count_negative_scales).
void save_ply(const Scene& scene, const std::string& path);
// Gaussians with a negative scale (as a .splat file may hold): PLY's log scales cannot
// represent the sign, so save_ply changes them, and a conversion says how many it touched.
std::size_t count_negative_scales(const Scene& scene);

// Reads cameras.json (at most 64 MB, a regular file). Throws flashgs::Error on a missing file,
// bad JSON, a missing field, a value that is not a finite float, an absurd focal length or
// size, or a rotation that is not orthonormal.
std::vector<Camera> load_cameras(const std::string& path);
// Parses the JSON text directly (`name` is used in messages).
std::vector<Camera> parse_cameras(const std::string& json_text, const std::string& name);
// Writes cameras.json, whole or not at all (write_file_atomically).
void save_cameras(const std::vector<Camera>& cameras, const std::string& path);

}  // namespace flashgs
