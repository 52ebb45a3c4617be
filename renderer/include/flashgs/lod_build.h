// `flashgs lod build`: a scene file turned into a streamed LOD set (lod-meta.json + chunk files),
// out of core: memory follows the options, not the scene's size.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "flashgs/scene.h"

namespace flashgs {

// How the chunk files are written: INRIA PLY at full precision (L_K.ply, any 3DGS tool reads
// it), or SOG folders (L_K/meta.json and WebP textures, quantised; PlayCanvas's viewers read it).
enum class LodChunkFormat { ply, sog };

struct LodBuildOptions {
  std::uint64_t leaf_gaussians = 16384;    // a leaf cell's Gaussians at level 0, about
  int levels = 0;                          // 0: enough for about 256 Gaussians per leaf at the coarsest
  std::uint64_t file_gaussians = 262144;   // Gaussians per chunk file and level, at most
  std::uint64_t memory_bytes = 2ull << 30; // what the builder may hold at once (buckets, chunk buffers)
  int threads = 0;                         // leaves merged at once; 0: every core (the output is the same)
  LodChunkFormat chunk_format = LodChunkFormat::ply;
  // Called as the build goes: a stage name ("sampling", "sorting", "building"), done and total.
  std::function<void(const char* stage, std::uint64_t done, std::uint64_t total)> progress;
};

struct LodBuildReport {
  std::uint64_t gaussians = 0;  // read (Gaussians with NaN or Inf dropped)
  int leaves = 0, levels = 0, files = 0;
  std::vector<std::uint64_t> level_gaussians;
  std::uint64_t bytes_written = 0;
  std::uint64_t bucket_bytes = 0;  // the largest bucket held at once
  bool streamed = false;           // the input was read from the disk batch by batch
};

// Builds the set in `out_folder` (created; it must be empty or absent) from the scene file
// `input`. Throws flashgs::Error with one line naming the file or folder and the problem.
// A chunk's file name in its set's folder: STEM.ply, or STEM/meta.json for a SOG chunk folder.
std::string lod_chunk_name(const std::string& stem, LodChunkFormat format);
// Writes `scene` as a chunk at `path` (named by lod_chunk_name; a SOG chunk's folder is
// created) and returns the bytes written.
std::uint64_t write_lod_chunk(const Scene& scene, const std::string& path, LodChunkFormat format);

// Makes `folder` ready for a new LOD set: created, or kept when it is an empty folder; throws
// flashgs::Error naming it otherwise.
void prepare_lod_folder(const std::string& folder);

LodBuildReport build_lod_set(const std::string& input, const std::string& out_folder, const LodBuildOptions& options);

}  // namespace flashgs
