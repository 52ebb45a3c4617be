// The one entry point for scene files in every format the project reads; the format is chosen by content.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs {

enum class SceneFormat { inria_ply, compressed_ply, splat, spz, sog };

// "INRIA PLY", "PlayCanvas compressed PLY", ...
const char* format_name(SceneFormat format);
// How the format stores the Gaussians (its quantisation), one line for `flashgs info`.
const char* format_quantisation(SceneFormat format);

// Reads the scene file at `path`, its format recognised by its first bytes (the PLY header,
// a magic number) and, for formats without one (.splat), by the extension. Fills `report`
// (format, read and decode times, what was dropped) and `progress` (bytes, then Gaussians).
// Throws flashgs::Error naming the file and the problem (one line "<path>: not a scene file:
// ..." when no format matches), or flashgs::LoadCancelled when `progress->cancel_requested`
// was set. `report` and `progress` may be null.
Scene load_scene_file(const std::string& path, LoadReport* report = nullptr,
                      LoadProgress* progress = nullptr);
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
                        LoadReport* report = nullptr, LoadProgress* progress = nullptr);

// Writes `scene` as .splat: 32-byte records of float position and scale, 8-bit RGBA (colour
// 0.5 + SH_C0 * dc, clamped to [0, 1]; opacity) and 8-bit quaternion (q * 128 + 128, w x y z),
// each byte rounded to the nearest. SH bands beyond degree 0 are not kept. Written whole or not
// at all (write_file_atomically).
void save_splat(const Scene& scene, const std::string& path);
// The writer of the format `path`'s extension names: save_ply for .ply (INRIA PLY),
// save_splat for .splat; null for any other extension.
using SceneWriter = void (*)(const Scene& scene, const std::string& path);
SceneWriter scene_writer_for(const std::string& path);
// The extensions scene_writer_for knows, for messages: ".ply (INRIA PLY) or .splat".
const char* writable_scene_extensions();

}  // namespace flashgs
