// A streamed level-of-detail set as a tree of spatial cells (PlayCanvas's lod-meta.json layout):
// each leaf names, per level, a range of Gaussians in one chunk file; level 0 is the finest.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/load_progress.h"
#include "flashgs/lod_instance.h"
#include "flashgs/scene.h"

namespace flashgs {

struct LodBox {
  std::array<float, 3> min{}, max{};
};

// A leaf's Gaussians at one level: [offset, offset + count) of chunk file `file`.
struct LodRange {
  int file = -1;  // -1: the leaf has nothing at this level
  std::uint64_t offset = 0, count = 0;
};

struct LodLeaf {
  LodBox bound;                  // of the leaf's Gaussian centres, as drawn (after its instance)
  std::vector<LodRange> levels;  // one per level of the set
  int instance = -1;             // the set's instance that moves its Gaussians; -1: none
};

struct LodSet {
  std::string meta_path;           // the lod-meta.json
  std::string folder;              // chunk file names are relative to it
  int level_count = 0;
  // Chunk files (SOG meta.json or PLY), relative to `folder`. In an instanced set, one entry per
  // (file, instance) that the leaves name: each instance's copy of a chunk is loaded, cached
  // and keyed (ScenePart::key) apart, as if it were a file of its own.
  std::vector<std::string> files;
  std::vector<LodLeaf> leaves;     // in tree order, which is spatial order
  LodBox bound;                    // of every leaf
  // Ours, not PlayCanvas's (its reader ignores them): rigid placements of leaves, and per entry
  // of `files` the instance its Gaussians are moved by (-1: none). Both empty in a plain set.
  std::vector<LodInstance> instances;
  std::vector<int> file_instance;

  std::uint64_t gaussians(int level) const;
  std::string file_path(int file) const;  // folder / files[file]
};

// Reads lod-meta.json (a path to it, or a folder holding it) with every leaf's bound and ranges,
// and the instances if it has them. Throws flashgs::Error with one line naming the file and the
// problem for malformed JSON, a missing field, a level, file or instance index out of range, a
// path leaving the set's folder, or an instance that is not finite or not a unit rotation.
LodSet read_lod_set(const std::string& path);

// A chunk file: SOG (meta.json, as PlayCanvas writes sets) or a scene file of any format we read
// (PLY, as `flashgs lod build` writes them). Its bytes to read (the textures, for SOG), its SH
// degree from its header alone, and its Gaussians.
std::uint64_t lod_chunk_bytes(const std::string& path);
int lod_chunk_sh_degree(const std::string& path);
// A chunk's Gaussians by its header alone (SOG meta.json's count, a PLY's vertex count).
std::uint64_t lod_chunk_gaussians(const std::string& path);

// Throws flashgs::Error naming the set unless level `level`'s leaves split each chunk file they
// name between them, as LOD writers make them: every range inside its file (by the chunk's
// header: lod_chunk_gaussians, read once per file), no Gaussian in two leaves, none in no leaf.
// So a tree that claims more Gaussians than its files hold costs no decoding.
void check_lod_ranges(const LodSet& set, int level);
Scene read_lod_chunk(const std::string& path, LoadReport* report = nullptr, LoadProgress* progress = nullptr);
// Entry `file` of set.files read and moved by its instance (read_lod_chunk for a plain set).
Scene read_lod_set_chunk(const LodSet& set, int file, LoadReport* report = nullptr, LoadProgress* progress = nullptr);

// The tree written into lod-meta.json: internal nodes split the leaves in two, as the builder's
// k-d tree did; each node's bound is the union of its leaves'.
struct LodTreeNode {
  int first_leaf = 0, leaf_count = 0;  // the leaves below it, consecutive in tree order
  int children[2] = {-1, -1};          // node indices; -1 for a leaf node
};
// Writes `set` as lod-meta.json at `path` (whole or not at all). The last node is the root. An
// instanced set's leaves are written with their instance and the file names once each.
void write_lod_meta(const LodSet& set, const std::vector<LodTreeNode>& nodes, const std::string& path);

}  // namespace flashgs
