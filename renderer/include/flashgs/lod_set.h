// A streamed level-of-detail set as a tree of spatial cells (PlayCanvas's lod-meta.json layout):
// each leaf names, per level, a range of Gaussians in one chunk file; level 0 is the finest.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/load_progress.h"
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
  LodBox bound;                  // of the leaf's Gaussian centres
  std::vector<LodRange> levels;  // one per level of the set
};

struct LodSet {
  std::string meta_path;           // the lod-meta.json
  std::string folder;              // chunk file names are relative to it
  int level_count = 0;
  std::vector<std::string> files;  // chunk files (SOG meta.json or PLY), relative to `folder`
  std::vector<LodLeaf> leaves;     // in tree order, which is spatial order
  LodBox bound;                    // of every leaf

  std::uint64_t gaussians(int level) const;
  std::string file_path(int file) const;  // folder / files[file]
};

// Reads lod-meta.json (a path to it, or a folder holding it) with every leaf's bound and ranges.
// Throws flashgs::Error with one line naming the file and the problem for malformed JSON,
// a missing field, a level or file index out of range, or a path leaving the set's folder.
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

// The tree written into lod-meta.json: internal nodes split the leaves in two, as the builder's
// k-d tree did; each node's bound is the union of its leaves'.
struct LodTreeNode {
  int first_leaf = 0, leaf_count = 0;  // the leaves below it, consecutive in tree order
  int children[2] = {-1, -1};          // node indices; -1 for a leaf node
};
// Writes `set` as lod-meta.json at `path` (whole or not at all). The last node is the root.
void write_lod_meta(const LodSet& set, const std::vector<LodTreeNode>& nodes, const std::string& path);

}  // namespace flashgs
