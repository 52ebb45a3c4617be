// The one entry point for scene files in every format the project reads; the format is chosen by content.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs {

enum class SceneFormat { inria_ply, compressed_ply, splat, spz, sog, sog_bundle, ksplat };

// SPZ stores right-up-back axes (Niantic's spz library turns 3DGS's right-down-forward into them
// on writing); some writers stored the PLY axes unchanged. The file does not say which.
enum class SpzAxes { niantic, none };
// "niantic" or "none" to the value; false for anything else.
bool parse_spz_axes(const std::string& text, SpzAxes& out);

// How scene files are read: what the files cannot say themselves.
struct SceneReadOptions {
  SpzAxes spz_axes = SpzAxes::niantic;
};

// How scene files are written, where a format leaves a choice.
struct SceneWriteOptions {
  int spz_version = 3;  // 3 (gzip) or 4 (zstd streams, the spz library's current version)
  SpzAxes spz_axes = SpzAxes::niantic;
  int sog_iterations = 10;  // k-means passes for SOG's codebooks and SH palette
};

// "INRIA PLY", "PlayCanvas compressed PLY", ...
const char* format_name(SceneFormat format);
// How the format stores the Gaussians (its quantisation), one line for `flashgs info`.
const char* format_quantisation(SceneFormat format);

// Reads the scene file at `path`, its format recognised by its first bytes (the PLY header,
// a magic number) and, for formats without one (.splat), by the extension. Fills `report`
// (format, read and decode times, what was dropped) and `progress` (bytes, then Gaussians).
// Throws flashgs::Error naming the file and the problem (one line "<path>: not a scene file:
// ..." when no format matches), or flashgs::LoadCancelled when `progress->cancel_requested`
// was set. `report` and `progress` may be null; `options` says what the file cannot.
Scene load_scene_file(const std::string& path, LoadReport* report = nullptr, LoadProgress* progress = nullptr,
                      const SceneReadOptions& options = {});
// What a scene file declares, from its start, before it is read whole (its header; a .splat
// file's size): the Gaussians (0 when the format cannot say so cheaply, as SOG) and the memory
// reading and decoding it takes (the file's bytes, the scene's and the decoder's). Throws
// flashgs::Error naming the file when it is no scene file or its header contradicts its size;
// load_scene_file does this first and refuses a file whose load_bytes exceed the memory available.
struct SceneDeclaration {
  SceneFormat format = SceneFormat::inria_ply;
  std::uint64_t gaussians = 0;
  int sh_degree = 0;
  std::uint64_t file_bytes = 0;
  std::uint64_t load_bytes = 0;
};
SceneDeclaration declare_scene_file(const std::string& path);

// The same for a file's bytes already in memory (`name` is its path, used for messages and
// for the extension); the fuzz tests drive this.
Scene parse_scene_bytes(const char* data, std::size_t size, const std::string& name,
                        LoadReport* report = nullptr, LoadProgress* progress = nullptr,
                        const SceneReadOptions& options = {});

// Writes `scene` as .splat: 32-byte records of float position and scale, 8-bit RGBA (colour
// 0.5 + SH_C0 * dc, clamped to [0, 1]; opacity) and 8-bit quaternion (q * 128 + 128, w x y z),
// each byte rounded to the nearest. SH bands beyond degree 0 are not kept. Written whole or not
// at all (write_file_atomically).
void save_splat(const Scene& scene, const std::string& path);
// A format flashgs writes, picked by the output's name (see writable_format_for).
using SceneWriter = void (*)(const Scene& scene, const std::string& path, const SceneWriteOptions& options);
struct WritableFormat {
  SceneFormat format;
  const char* name_ending;  // ".compressed.ply", "meta.json", ...
  SceneWriter write;
  int max_sh_degree;       // bands beyond are not kept
  bool holds_kernel_mark;  // whether the file can say which kernel the scene was trained with
};
// The format `path`'s name picks: .ply (INRIA), .compressed.ply, .splat, .spz, .sog (zipped SOG
// v2), meta.json (SOG v2, textures beside it); null for any other name.
const WritableFormat* writable_format_for(const std::string& path);
// The names writable_format_for knows, for messages.
const char* writable_scene_extensions();
// Writes `scene` in the format `path`'s name picks; throws flashgs::Error for an unknown name.
void save_scene_file(const Scene& scene, const std::string& path, const SceneWriteOptions& options = {});

}  // namespace flashgs
