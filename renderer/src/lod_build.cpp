// The LOD set builder: a k-d tree over a sample of the centres, the Gaussians bucketed by leaf
// on the disk, then leaf by leaf the coarser levels merged and appended to per-level chunk files.
#include "flashgs/lod_build.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <system_error>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/io.h"
#include "flashgs/lod_set.h"
#include "format_writers.h"
#include "gaussian_batches.h"
#include "lod_merge.h"
#include "parallel_errors.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace flashgs {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxSamples = std::size_t{1} << 21;  // centres the tree is split on
constexpr std::size_t kBatch = std::size_t{1} << 18;       // Gaussians read at once
constexpr std::uint64_t kCoarsestPerLeaf = 256;
constexpr int kMaxLevels = 16;
constexpr int kMaxDepth = 60;

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw Error(printable_file_text(name, kMaxPrintedPathBytes) + ": " + problem);
}

// The k-d tree over the sampled centres: a node splits its cell at `split` on `axis`; the
// leaves are numbered in depth-first order, which is the set's tree (and so spatial) order.
struct KdNode {
  int axis = -1;  // -1: a leaf
  float split = 0;
  int child[2] = {-1, -1};
  int leaf = -1;
  std::size_t samples = 0;
};

class KdTree {
 public:
  KdTree(std::vector<float> centres, double gaussians_per_sample, std::uint64_t leaf_gaussians)
      : m_centres(std::move(centres)), m_per_sample(gaussians_per_sample), m_leaf_gaussians(leaf_gaussians) {
    std::vector<std::uint32_t> order(m_centres.size() / 3);
    std::iota(order.begin(), order.end(), 0u);
    build(order, 0, order.size(), 0);
    m_centres.clear();
    m_centres.shrink_to_fit();
  }
  int leaf_of(const float* p) const {
    int node = 0;
    while (m_nodes[node].axis >= 0) node = m_nodes[node].child[p[m_nodes[node].axis] < m_nodes[node].split ? 0 : 1];
    return m_nodes[node].leaf;
  }
  int leaf_count() const { return m_leaves; }
  const std::vector<KdNode>& nodes() const { return m_nodes; }
  // Gaussians the samples put in each leaf, about.
  std::vector<double> leaf_estimates() const {
    std::vector<double> out(static_cast<std::size_t>(m_leaves), 0.0);
    for (const KdNode& n : m_nodes)
      if (n.axis < 0) out[static_cast<std::size_t>(n.leaf)] = static_cast<double>(n.samples) * m_per_sample;
    return out;
  }

 private:
  int build(std::vector<std::uint32_t>& order, std::size_t a, std::size_t b, int depth) {
    const int index = static_cast<int>(m_nodes.size());
    m_nodes.emplace_back();
    m_nodes[index].samples = b - a;
    float length = 0;
    const int axis = longest_axis(m_centres, order.data() + a, b - a, &length);  // the cell's longest side
    const bool small = static_cast<double>(b - a) * m_per_sample <= static_cast<double>(m_leaf_gaussians);
    if (small || b - a < 2 || depth >= kMaxDepth || !(length > 0)) {
      m_nodes[index].leaf = m_leaves++;
      return index;
    }
    const std::size_t mid = a + (b - a) / 2;
    std::nth_element(order.begin() + a, order.begin() + mid, order.begin() + b,
                     [&](std::uint32_t x, std::uint32_t y) { return m_centres[x * 3 + axis] < m_centres[y * 3 + axis]; });
    const float split = m_centres[order[mid] * 3 + axis];
    // Samples equal to the split go right, as leaf_of sends them; the left part keeps those below.
    const std::size_t left_end = static_cast<std::size_t>(
        std::partition(order.begin() + a, order.begin() + b,
                       [&](std::uint32_t x) { return m_centres[x * 3 + axis] < split; }) - order.begin());
    if (left_end == a || left_end == b) {  // a run of equal coordinates: no split here
      m_nodes[index].leaf = m_leaves++;
      return index;
    }
    m_nodes[index].axis = axis;
    m_nodes[index].split = split;
    const int left = build(order, a, left_end, depth + 1);
    const int right = build(order, left_end, b, depth + 1);
    m_nodes[index].child[0] = left;
    m_nodes[index].child[1] = right;
    return index;
  }

  std::vector<float> m_centres;
  double m_per_sample;
  std::uint64_t m_leaf_gaussians;
  std::vector<KdNode> m_nodes;
  int m_leaves = 0;
};

// One Gaussian on the disk between the passes: its leaf, then its floats as Scene holds them.
std::size_t record_floats(int sh_degree) { return 14 + static_cast<std::size_t>((sh_coefficient_count(sh_degree) - 1) * 3); }

void pack(const Scene& s, std::size_t i, std::uint32_t leaf, std::vector<char>& out) {
  const std::size_t rest = static_cast<std::size_t>(s.sh_rest_per_gaussian());
  const std::size_t at = out.size();
  out.resize(at + 4 + 4 * (14 + rest));
  char* p = &out[at];
  auto put = [&p](const float* v, std::size_t n) {
    std::memcpy(p, v, n * 4);
    p += n * 4;
  };
  std::memcpy(p, &leaf, 4);
  p += 4;
  put(&s.positions[i * 3], 3);
  put(&s.scales[i * 3], 3);
  put(&s.rotations[i * 4], 4);
  put(&s.opacities[i], 1);
  put(&s.sh_dc[i * 3], 3);
  if (rest) put(&s.sh_rest[i * rest], rest);
}

void unpack(const char* p, Scene& s) {
  const std::size_t rest = static_cast<std::size_t>(s.sh_rest_per_gaussian());
  auto take = [&p](std::vector<float>& to, std::size_t n) {
    const std::size_t at = to.size();
    to.resize(at + n);
    std::memcpy(&to[at], p, n * 4);
    p += n * 4;
  };
  p += 4;
  take(s.positions, 3);
  take(s.scales, 3);
  take(s.rotations, 4);
  take(s.opacities, 1);
  take(s.sh_dc, 3);
  if (rest) take(s.sh_rest, rest);
}

// Consecutive leaves whose Gaussians are held together in pass 3, each in its own file.
class Buckets {
 public:
  Buckets(const fs::path& folder, const std::vector<double>& leaf_estimates, double record_bytes, double cap_bytes)
      : m_folder(folder) {
    double bytes = 0;
    for (std::size_t leaf = 0; leaf < leaf_estimates.size(); ++leaf) {
      const double leaf_bytes = leaf_estimates[leaf] * record_bytes;
      if (!m_first_leaf.empty() && bytes + leaf_bytes > cap_bytes && bytes > 0) {
        m_first_leaf.push_back(static_cast<int>(leaf));
        bytes = 0;
      }
      if (m_first_leaf.empty()) m_first_leaf.push_back(0);
      m_bucket_of.push_back(static_cast<int>(m_first_leaf.size()) - 1);
      bytes += leaf_bytes;
    }
    m_buffers.resize(m_first_leaf.size());
    m_files.resize(m_first_leaf.size(), nullptr);
  }
  ~Buckets() {
    for (std::FILE* f : m_files)
      if (f) std::fclose(f);
  }
  int count() const { return static_cast<int>(m_first_leaf.size()); }
  int first_leaf(int bucket) const { return m_first_leaf[static_cast<std::size_t>(bucket)]; }
  std::vector<char>& buffer_of_leaf(int leaf) { return m_buffers[static_cast<std::size_t>(m_bucket_of[static_cast<std::size_t>(leaf)])]; }
  fs::path path(int bucket) const { return m_folder / ("bucket_" + std::to_string(bucket)); }
  // Writes the buffers that grew past `threshold` bytes to their files.
  void spill(std::size_t threshold) {
    for (std::size_t b = 0; b < m_buffers.size(); ++b) {
      if (m_buffers[b].size() <= threshold || m_buffers[b].empty()) continue;
      if (!m_files[b] && !(m_files[b] = std::fopen(path(static_cast<int>(b)).c_str(), "wb")))
        fail(path(static_cast<int>(b)).string(), "cannot create a temporary file: " + std::string(std::strerror(errno)));
      if (std::fwrite(m_buffers[b].data(), 1, m_buffers[b].size(), m_files[b]) != m_buffers[b].size())
        fail(path(static_cast<int>(b)).string(), "write error: " + std::string(std::strerror(errno)));
      m_buffers[b].clear();
    }
  }
  void close_all() {
    spill(0);
    for (std::FILE*& f : m_files) {
      if (f && std::fclose(f) != 0) fail(m_folder.string(), "write error: " + std::string(std::strerror(errno)));
      f = nullptr;
    }
  }

 private:
  fs::path m_folder;
  std::vector<int> m_first_leaf, m_bucket_of;
  std::vector<std::vector<char>> m_buffers;
  std::vector<std::FILE*> m_files;
};

// The chunk files of one level: a leaf's Gaussians are appended to the open file, which is
// written out once it holds `file_gaussians`.
class LevelWriter {
 public:
  LevelWriter(int level, std::uint64_t file_gaussians, LodChunkFormat format, const fs::path& folder, LodSet& set,
              LodBuildReport& report)
      : m_level(level), m_file_gaussians(file_gaussians), m_format(format), m_folder(folder), m_set(set), m_report(report) {}
  LodRange append(const Scene& leaf_level) {
    if (m_file < 0 || (m_pending.size() > 0 && m_pending.size() + leaf_level.size() > m_file_gaussians)) start_file();
    LodRange range{m_file, m_pending.size(), leaf_level.size()};
    if (m_pending.size() == 0) {
      m_pending.sh_degree = leaf_level.sh_degree;
      m_pending.trained_kernel = leaf_level.trained_kernel;
    }
    m_pending.append(leaf_level);
    return range;
  }
  void finish() {
    if (m_file >= 0 && m_pending.size() > 0) write_file();
  }

 private:
  void start_file() {
    if (m_file >= 0) write_file();
    m_file = static_cast<int>(m_set.files.size());
    const std::string name = std::to_string(m_level) + "_" + std::to_string(m_next_name++);
    m_set.files.push_back(lod_chunk_name(name, m_format));
    m_pending = Scene{};
  }
  void write_file() {
    const fs::path path = m_folder / m_set.files[static_cast<std::size_t>(m_file)];
    m_report.bytes_written += write_lod_chunk(m_pending, path.string(), m_format);
    ++m_report.files;
    m_pending = Scene{};
  }

  int m_level;
  std::uint64_t m_file_gaussians;
  LodChunkFormat m_format;
  fs::path m_folder;
  LodSet& m_set;
  LodBuildReport& m_report;
  Scene m_pending;
  int m_file = -1, m_next_name = 0;
};

// The temporary folder goes however the build ends.
struct TemporaryFolder {
  fs::path path;
  ~TemporaryFolder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

LodBox bound_of(const Scene& scene) {
  LodBox box;
  box.min.fill(std::numeric_limits<float>::max());
  box.max.fill(std::numeric_limits<float>::lowest());
  for (std::size_t i = 0; i < scene.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], scene.positions[i * 3 + k]);
      box.max[k] = std::max(box.max[k], scene.positions[i * 3 + k]);
    }
  return box;
}

// One leaf's levels, finest first, and its cell (its level 0's bounding box).
struct LeafLevels {
  LodBox bound;
  std::vector<Scene> levels;  // empty: the leaf holds no Gaussians
};

LeafLevels leaf_levels(Scene level0, int levels) {
  LeafLevels out;
  if (level0.size() == 0) return out;
  out.bound = bound_of(level0);
  out.levels.reserve(static_cast<std::size_t>(levels));
  out.levels.push_back(std::move(level0));
  for (int l = 1; l < levels; ++l) {
    const Scene& finer = out.levels.back();
    out.levels.push_back(finer.size() > 1 ? coarser_level(finer) : finer);
  }
  return out;
}

int build_threads(int asked) {
  if (asked > 0) return asked;
#ifdef _OPENMP
  return std::max(1, omp_get_max_threads());
#else
  return 1;
#endif
}

// The written tree: the k-d tree without its empty leaves, nodes in post order (the root last).
int emit_tree(const std::vector<KdNode>& kd, int node, const std::vector<int>& new_leaf,
              std::vector<LodTreeNode>& out) {
  const KdNode& n = kd[static_cast<std::size_t>(node)];
  if (n.axis < 0) {
    const int leaf = new_leaf[static_cast<std::size_t>(n.leaf)];
    if (leaf < 0) return -1;
    out.push_back(LodTreeNode{leaf, 1, {-1, -1}});
    return static_cast<int>(out.size()) - 1;
  }
  const int left = emit_tree(kd, n.child[0], new_leaf, out);
  const int right = emit_tree(kd, n.child[1], new_leaf, out);
  if (left < 0 || right < 0) return left < 0 ? right : left;
  const LodTreeNode& l = out[static_cast<std::size_t>(left)];
  const LodTreeNode& r = out[static_cast<std::size_t>(right)];
  out.push_back(LodTreeNode{l.first_leaf, l.leaf_count + r.leaf_count, {left, right}});
  return static_cast<int>(out.size()) - 1;
}

}  // namespace

std::string lod_chunk_name(const std::string& stem, LodChunkFormat format) {
  return format == LodChunkFormat::sog ? stem + "/meta.json" : stem + ".ply";
}

std::uint64_t write_lod_chunk(const Scene& scene, const std::string& path_name, LodChunkFormat format) {
  const fs::path path(path_name);
  std::error_code error;
  std::uint64_t bytes = 0;
  if (format == LodChunkFormat::sog) {
    if (!fs::create_directory(path.parent_path(), error) && error)
      fail(path.parent_path().string(), "cannot create the chunk folder: " + error.message());
    save_sog_folder(scene, path.string(), SceneWriteOptions{});
    for (const auto& e : fs::directory_iterator(path.parent_path(), error)) bytes += e.file_size(error);
  } else {
    save_ply(scene, path.string());
    bytes = fs::file_size(path, error);
  }
  return bytes;
}

void prepare_lod_folder(const std::string& folder_name) {
  const fs::path folder(folder_name);
  std::error_code error;
  const fs::file_status status = fs::status(folder, error);
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) fail(folder.string(), "exists and is not a folder");
    if (!fs::is_empty(folder, error)) fail(folder.string(), "is not empty: name a new or empty folder for the LOD set");
    return;
  }
  if (!fs::create_directories(folder, error) || error)
    fail(folder.string(), "cannot create the folder: " + error.message());
}

LodBuildReport build_lod_set(const std::string& input, const std::string& out_folder, const LodBuildOptions& options) {
  if (options.leaf_gaussians < 1) fail(out_folder, "the leaf size must be at least 1 Gaussian");
  if (options.file_gaussians < 1) fail(out_folder, "the chunk file size must be at least 1 Gaussian");
  auto progress = [&](const char* stage, std::uint64_t done, std::uint64_t total) {
    if (options.progress) options.progress(stage, done, total);
  };
  GaussianBatches source(input);
  const fs::path folder(out_folder);
  prepare_lod_folder(folder.string());
  TemporaryFolder temporary{folder / ".lod-build-tmp"};
  std::error_code error;
  if (!fs::create_directory(temporary.path, error)) fail(temporary.path.string(), "cannot create: " + error.message());

  LodBuildReport report;
  report.streamed = source.streamed();
  int levels = options.levels;
  if (levels <= 0) {
    levels = 1;
    while (levels < kMaxLevels && (options.leaf_gaussians >> (levels - 1)) > kCoarsestPerLeaf) ++levels;
  }
  levels = std::min(levels, kMaxLevels);
  report.levels = levels;

  // Pass 1: a sample of the centres, every stride-th Gaussian, splits the space.
  const std::uint64_t declared = source.declared_count();
  const std::uint64_t stride = std::max<std::uint64_t>(1, (declared + kMaxSamples - 1) / kMaxSamples);
  std::vector<float> samples;
  Scene batch;
  std::uint64_t seen = 0;
  while (source.next(batch, kBatch)) {
    for (std::size_t i = 0; i < batch.size(); ++i, ++seen)
      if (seen % stride == 0) samples.insert(samples.end(), &batch.positions[i * 3], &batch.positions[i * 3] + 3);
    progress("sampling", seen, declared);
  }
  if (samples.empty()) fail(input, "no Gaussians to build a LOD set from");
  const KdTree tree(std::move(samples), static_cast<double>(stride), options.leaf_gaussians);

  // Pass 2: every Gaussian to its leaf's bucket on the disk.
  const int sh_degree = source.sh_degree();
  const double record_bytes = 4.0 + 4.0 * static_cast<double>(record_floats(sh_degree));
  Buckets buckets(temporary.path, tree.leaf_estimates(), record_bytes, static_cast<double>(options.memory_bytes) / 4);
  const std::size_t spill_bytes = std::max<std::size_t>(1 << 16, options.memory_bytes / 8 / static_cast<std::size_t>(buckets.count()));
  std::vector<std::uint64_t> leaf_counts(static_cast<std::size_t>(tree.leaf_count()), 0);
  source.rewind();
  std::uint64_t sorted = 0;
  while (source.next(batch, kBatch)) {
    if (batch.sh_degree != sh_degree) fail(input, "the SH degree changes inside the file");
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const int leaf = tree.leaf_of(&batch.positions[i * 3]);
      ++leaf_counts[static_cast<std::size_t>(leaf)];
      pack(batch, i, static_cast<std::uint32_t>(leaf), buckets.buffer_of_leaf(leaf));
    }
    sorted += batch.size();
    buckets.spill(spill_bytes);
    progress("sorting", sorted, declared);
  }
  buckets.close_all();
  report.gaussians = sorted;

  // Pass 3: leaf by leaf, the levels, appended to each level's chunk files.
  LodSet set;
  set.level_count = levels;
  const std::uint64_t gaussian_bytes = static_cast<std::uint64_t>(record_bytes);
  const std::uint64_t file_gaussians = std::max<std::uint64_t>(
      1, std::min(options.file_gaussians, options.memory_bytes / 4 / (gaussian_bytes * static_cast<std::uint64_t>(levels))));
  std::vector<LevelWriter> writers;
  for (int level = 0; level < levels; ++level) writers.emplace_back(level, file_gaussians, options.chunk_format, folder, set, report);
  std::vector<int> new_leaf(static_cast<std::size_t>(tree.leaf_count()), -1);
  report.level_gaussians.assign(static_cast<std::size_t>(levels), 0);
  const int threads = build_threads(options.threads);
  const int group_leaves = 4 * threads;
  std::uint64_t built = 0;
  for (int b = 0; b < buckets.count(); ++b) {
    const int first = buckets.first_leaf(b);
    const int end = b + 1 < buckets.count() ? buckets.first_leaf(b + 1) : tree.leaf_count();
    std::vector<Scene> leaves(static_cast<std::size_t>(end - first));
    for (Scene& s : leaves) {
      s.sh_degree = sh_degree;
      s.trained_kernel = source.trained_kernel();
    }
    const fs::path bucket_path = buckets.path(b);
    if (fs::exists(bucket_path)) {
      const std::vector<char> bytes = read_regular_file(bucket_path.string());
      report.bucket_bytes = std::max<std::uint64_t>(report.bucket_bytes, bytes.size());
      for (std::size_t at = 0; at + static_cast<std::size_t>(record_bytes) <= bytes.size(); at += static_cast<std::size_t>(record_bytes)) {
        std::uint32_t leaf;
        std::memcpy(&leaf, &bytes[at], 4);
        unpack(&bytes[at], leaves[leaf - static_cast<std::uint32_t>(first)]);
      }
      fs::remove(bucket_path, error);
    }
    // A group of leaves at a time: their levels merged in parallel (each leaf's alone, so the
    // result does not depend on the threads), then written in leaf order. A group holds its
    // leaves' levels beside the bucket: about twice their level 0.
    for (int group = first; group < end; group += group_leaves) {
      const int group_end = std::min(end, group + group_leaves);
      std::vector<LeafLevels> merged(static_cast<std::size_t>(group_end - group));
      ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
      for (int leaf = group; leaf < group_end; ++leaf)
        errors.capture([&] {
          merged[static_cast<std::size_t>(leaf - group)] =
              leaf_levels(std::move(leaves[static_cast<std::size_t>(leaf - first)]), levels);
        });
      errors.rethrow();
      for (int leaf = group; leaf < group_end; ++leaf) {
        LeafLevels& m = merged[static_cast<std::size_t>(leaf - group)];
        if (m.levels.empty()) continue;
        new_leaf[static_cast<std::size_t>(leaf)] = static_cast<int>(set.leaves.size());
        LodLeaf out;
        out.bound = m.bound;
        for (int l = 0; l < levels; ++l) {
          const Scene& level = m.levels[static_cast<std::size_t>(l)];
          out.levels.push_back(writers[static_cast<std::size_t>(l)].append(level));
          report.level_gaussians[static_cast<std::size_t>(l)] += level.size();
        }
        m = LeafLevels{};
        built += leaf_counts[static_cast<std::size_t>(leaf)];
        set.leaves.push_back(std::move(out));
      }
      progress("building", built, sorted);
    }
  }
  for (LevelWriter& w : writers) w.finish();
  report.leaves = static_cast<int>(set.leaves.size());

  std::vector<LodTreeNode> nodes;
  emit_tree(tree.nodes(), 0, new_leaf, nodes);
  const std::string meta_path = (folder / "lod-meta.json").string();
  write_lod_meta(set, nodes, meta_path);
  report.bytes_written += fs::file_size(meta_path, error);
  return report;
}

}  // namespace flashgs
