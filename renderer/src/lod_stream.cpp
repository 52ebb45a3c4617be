// The LOD streamer: cut per frame, chunk loads on background threads under a host cap (least
// recently used chunks go first), and the drawn scene assembled from what is in memory.
#include "flashgs/lod_stream.h"

#include <algorithm>
#include <map>

#include "flashgs/error.h"

namespace flashgs {

enum class ChunkState { absent, queued, loading, resident, failed };

struct LodStreamer::Chunk {
  ChunkState state = ChunkState::absent;
  std::shared_ptr<const Scene> scene;
  std::uint64_t bytes = 0;       // of the scene in memory
  std::uint64_t file_bytes = 0;  // on the disk
  std::uint64_t last_used = 0;   // the frame that last drew from it
};

namespace {

// Gaussian-tile pairs per drawn Gaussian that the frame costs are sized for (flash on the real
// scenes: 1.5-6 at 1080p).
constexpr std::uint64_t kPairsPerGaussian = 4;
// What a GPU renderer's pool of parts adds per drawn Gaussian (an id).
constexpr std::uint64_t kDeviceIdBytes = 4;
// Frames of the camera's last step to look ahead when prefetching.
constexpr float kPrefetchFrames = 8.0f;

std::uint64_t bytes_per_gaussian(int sh_degree) {
  return sizeof(float) * (14 + 3 * static_cast<std::uint64_t>(sh_coefficient_count(sh_degree) - 1));
}


}  // namespace

void lod_frame_costs(BackendKind backend, int width, int height, int cpu_threads, LodFrameCost* host,
                     LodFrameCost* device) {
  constexpr std::size_t kMillion = 1000000;
  const FrameMemory none = estimate_frame_memory(backend, 0, width, height, 0, cpu_threads);
  const FrameMemory many = estimate_frame_memory(backend, kMillion, width, height, kPairsPerGaussian * kMillion, cpu_threads);
  if (host) *host = LodFrameCost{none.host, (many.host - none.host) / kMillion};
  if (device) *device = LodFrameCost{none.device, (many.device - none.device) / kMillion};
}

LodStreamer::LodStreamer(LodSet set, LodStreamOptions options) : m_set(std::move(set)), m_options(options) {
  const int files = static_cast<int>(m_set.files.size());
  m_chunks.resize(static_cast<std::size_t>(files));
  m_file_gaussians.assign(static_cast<std::size_t>(files), 0);
  m_pinned.assign(static_cast<std::size_t>(files), false);
  for (const LodLeaf& leaf : m_set.leaves) {
    for (const LodRange& r : leaf.levels)
      if (r.file >= 0)
        m_file_gaussians[static_cast<std::size_t>(r.file)] =
            std::max(m_file_gaussians[static_cast<std::size_t>(r.file)], r.offset + r.count);
    for (auto r = leaf.levels.rbegin(); r != leaf.levels.rend(); ++r)
      if (r->file >= 0) {
        m_pinned[static_cast<std::size_t>(r->file)] = true;
        break;
      }
  }
  for (int f = 0; f < files; ++f) {
    try {  // a SOG chunk's bytes are its textures'
      m_chunks[static_cast<std::size_t>(f)].file_bytes = lod_chunk_bytes(m_set.file_path(f));
    } catch (const Error&) {
      // read when its turn comes, and then reported
    }
  }
  // The set's SH degree from the first chunk whose header reads (a broken one fails when loaded).
  for (int f = 0; f < files && m_bytes_per_gaussian == 0; ++f) {
    try {
      m_bytes_per_gaussian = bytes_per_gaussian(lod_chunk_sh_degree(m_set.file_path(f)));
    } catch (const Error&) {
    }
  }
  if (m_bytes_per_gaussian == 0) throw Error(m_set.meta_path + ": none of the set's chunk files can be read");
  if (options.host_bytes) {
    m_file_budget.always_held = m_pinned;
    for (int f = 0; f < files; ++f)
      m_file_budget.bytes.push_back(m_file_gaussians[static_cast<std::size_t>(f)] * m_bytes_per_gaussian);
  }
  apply_caps();
  for (int t = 0; t < std::max(1, options.threads); ++t) m_threads.emplace_back([this] { load_loop(); });
}

void LodStreamer::apply_caps() {
  const LodStreamOptions& options = m_options;
  // Two drawn scenes (the one drawn and the next), their copies (the level overlay's) and the
  // frame's working memory take at most half of the host cap; the chunks the rest. On the GPU,
  // the drawn scene and the frame.
  m_budget = options.cut.budget ? options.cut.budget : std::numeric_limits<std::uint64_t>::max();
  const std::uint64_t drawn_per_gaussian =
      (2 + static_cast<std::uint64_t>(m_drawn_copies)) * m_bytes_per_gaussian + options.host_frame.per_gaussian;
  if (options.host_bytes) {
    const std::uint64_t half = options.host_bytes / 2;
    m_budget = std::min(m_budget, half > options.host_frame.fixed ? (half - options.host_frame.fixed) / drawn_per_gaussian : 0);
  }
  if (options.device_bytes) {
    // A GPU renderer holds the drawn parts in pages of 256 (a leaf's last page partly empty),
    // each Gaussian with a 4-byte id, and stages uploads in up to a sixteenth of the cap.
    const std::uint64_t cap = options.device_bytes;
    const std::uint64_t per_gaussian = m_bytes_per_gaussian + kDeviceIdBytes;
    const std::uint64_t held = options.device_frame.fixed + cap / 16 + m_set.leaves.size() * kScenePartPageGaussians * per_gaussian;
    m_budget = std::min(m_budget, cap > held ? (cap - held) / (per_gaussian + options.device_frame.per_gaussian) : 0);
  }
  m_chunk_cap = std::numeric_limits<std::uint64_t>::max();
  if (options.host_bytes) {
    const std::uint64_t drawn = m_budget * drawn_per_gaussian + options.host_frame.fixed;
    m_chunk_cap = options.host_bytes - std::min(options.host_bytes, drawn);
    // The cut keeps to files that fit the chunks' share beside one load in flight, which holds
    // its file's bytes while it decodes: so every file the cut wants can be loaded, one at a
    // time where there is no room for more (a load without room waits for the next frame).
    std::uint64_t largest_file = 0;
    for (const Chunk& c : m_chunks) largest_file = std::max(largest_file, c.file_bytes);
    m_file_budget.limit = m_chunk_cap > largest_file ? m_chunk_cap - largest_file : 1;
  }
}

void LodStreamer::set_drawn_copies(int copies) {
  std::unique_lock<std::mutex> lock(m_mutex);
  if (copies == m_drawn_copies) return;
  m_drawn_copies = std::max(0, copies);
  apply_caps();
  make_room(0, lock);  // chunks beyond the smaller share that no frame draws now go at once
}

LodStreamer::~LodStreamer() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stop = true;
  }
  m_wake.notify_all();
  for (std::thread& t : m_threads) t.join();
}

std::uint64_t LodStreamer::chunk_estimate(int file) const {
  // The file's bytes while they are decoded, and the decoded Gaussians.
  const Chunk& c = m_chunks[static_cast<std::size_t>(file)];
  return c.file_bytes + m_file_gaussians[static_cast<std::size_t>(file)] * m_bytes_per_gaussian;
}

bool LodStreamer::make_room(std::uint64_t bytes, std::unique_lock<std::mutex>&) {
  while (m_chunk_bytes + m_reserved + bytes > m_chunk_cap) {
    // The least recently used chunk that this frame does not draw; unpinned ones first.
    int victim = -1;
    for (int pass = 0; pass < 2 && victim < 0; ++pass)
      for (std::size_t f = 0; f < m_chunks.size(); ++f) {
        const Chunk& c = m_chunks[f];
        if (c.state != ChunkState::resident || c.last_used >= m_frame || (pass == 0 && m_pinned[f])) continue;
        if (victim < 0 || c.last_used < m_chunks[static_cast<std::size_t>(victim)].last_used) victim = static_cast<int>(f);
      }
    if (victim < 0) return false;
    Chunk& c = m_chunks[static_cast<std::size_t>(victim)];
    m_chunk_bytes -= c.bytes;
    c.scene.reset();
    c.bytes = 0;
    c.state = ChunkState::absent;
  }
  return true;
}

void LodStreamer::load_loop() {
  std::unique_lock<std::mutex> lock(m_mutex);
  for (;;) {
    m_wake.wait(lock, [this] { return m_stop || !m_queue.empty(); });
    if (m_stop) return;
    const int file = m_queue.front();
    m_queue.erase(m_queue.begin());
    Chunk& chunk = m_chunks[static_cast<std::size_t>(file)];
    if (chunk.state != ChunkState::queued) continue;
    const std::uint64_t estimate = chunk_estimate(file);
    if (!make_room(estimate, lock)) {
      chunk.state = ChunkState::absent;  // asked for again by a later frame, when room may be made
      if (m_loading == 0) m_idle.notify_all();
      continue;
    }
    chunk.state = ChunkState::loading;
    m_reserved += estimate;
    m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes);
    ++m_loading;
    lock.unlock();
    std::shared_ptr<Scene> scene;
    std::string problem;
    const std::string path = m_set.file_path(file);
    try {
      scene = std::make_shared<Scene>(read_lod_set_chunk(m_set, file));
      if (scene->size() < m_file_gaussians[static_cast<std::size_t>(file)])
        problem = printable_file_text(path, kMaxPrintedPathBytes) + ": holds " + std::to_string(scene->size()) +
                  " Gaussians but the set's tree takes " + std::to_string(m_file_gaussians[static_cast<std::size_t>(file)]) +
                  " from it";
      else if (scene->byte_size() / std::max<std::size_t>(1, scene->size()) != m_bytes_per_gaussian)
        problem = printable_file_text(path, kMaxPrintedPathBytes) + ": its SH degree differs from the set's first chunk";
    } catch (const Error& e) {
      problem = e.what();
    } catch (const std::bad_alloc&) {
      problem = printable_file_text(path, kMaxPrintedPathBytes) + ": out of memory while reading the chunk";
    }
    lock.lock();
    --m_loading;
    m_reserved -= estimate;
    m_bytes_read += chunk.file_bytes;
    if (!problem.empty()) {
      chunk.state = ChunkState::failed;
      m_errors.push_back(problem + " (the set draws that part coarser or not at all)");
    } else if (make_room(scene->byte_size(), lock)) {
      chunk.bytes = scene->byte_size();
      chunk.scene = std::move(scene);
      chunk.state = ChunkState::resident;
      chunk.last_used = m_frame;
      m_chunk_bytes += chunk.bytes;
      m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes);
    } else {
      chunk.state = ChunkState::absent;
    }
    if (m_queue.empty() && m_loading == 0) m_idle.notify_all();
  }
}

void LodStreamer::request(const std::vector<int>& files) {
  // Called with the lock held: the queue becomes `files` (most wanted first); chunks no longer
  // wanted leave it.
  for (int f : m_queue)
    if (m_chunks[static_cast<std::size_t>(f)].state == ChunkState::queued) m_chunks[static_cast<std::size_t>(f)].state = ChunkState::absent;
  m_queue.clear();
  for (int f : files) {
    Chunk& c = m_chunks[static_cast<std::size_t>(f)];
    if (c.state != ChunkState::absent) continue;
    c.state = ChunkState::queued;
    m_queue.push_back(f);
  }
}

LodStreamer::Drawn LodStreamer::choose(const Camera& camera) {
  LodCutOptions cut_options = m_options.cut;
  cut_options.budget = m_budget == std::numeric_limits<std::uint64_t>::max() ? 0 : m_budget;
  LodCut cut = choose_lod_cut(m_set, camera, cut_options, &m_cut, &m_file_budget);
  // Where the camera will be if it keeps moving: its chunks are asked for after the cut's.
  LodCut ahead;
  if (m_options.prefetch && m_have_last_position) {
    Camera next = camera;
    for (int k = 0; k < 3; ++k) next.position[k] += kPrefetchFrames * (camera.position[k] - m_last_position[k]);
    if (next.position[0] != camera.position[0] || next.position[1] != camera.position[1] || next.position[2] != camera.position[2])
      ahead = choose_lod_cut(m_set, next, cut_options, &cut, &m_file_budget);
  }
  for (int k = 0; k < 3; ++k) m_last_position[k] = camera.position[k];
  m_have_last_position = true;

  const int levels = m_set.level_count;
  Drawn result;
  std::vector<LodRange>& drawn = result.ranges;
  std::vector<std::shared_ptr<const Scene>>& sources = result.sources;
  LodStreamStats& stats = m_stats;
  stats = LodStreamStats{};
  stats.budget = cut_options.budget;
  stats.drawn_per_level.assign(static_cast<std::size_t>(levels), 0);
  stats.worst_error_px = cut.worst_error_px;
  {
    std::unique_lock<std::mutex> lock(m_mutex);
    ++m_frame;
    auto resident = [&](int file) { return file >= 0 && m_chunks[static_cast<std::size_t>(file)].state == ChunkState::resident; };
    std::vector<std::pair<float, int>> wanted;  // (priority, file)
    for (std::size_t f = 0; f < m_chunks.size(); ++f)
      if (m_pinned[f]) wanted.emplace_back(std::numeric_limits<float>::infinity(), static_cast<int>(f));
    // Each leaf of the cut at its level if in memory, else the nearest coarser one in memory.
    // Where only a finer one is, that one while the budget still holds it (the cut's own
    // Gaussians are within the budget; finer stand-ins must not push the drawn scene over it).
    std::vector<int> draw_level(cut.level.size(), -1);
    std::vector<std::pair<std::size_t, int>> finer_only;  // (leaf, the nearest finer level in memory)
    std::uint64_t drawn_total = 0;
    for (std::size_t leaf = 0; leaf < cut.level.size(); ++leaf) {
      const int want = cut.level[leaf];
      if (want < 0) continue;
      const LodLeaf& l = m_set.leaves[leaf];
      for (int c = want; draw_level[leaf] < 0 && c < levels; ++c)
        if (resident(l.levels[static_cast<std::size_t>(c)].file)) draw_level[leaf] = c;
      if (draw_level[leaf] >= 0) {
        drawn_total += l.levels[static_cast<std::size_t>(draw_level[leaf])].count;
        continue;
      }
      for (int c = want - 1; c >= 0; --c)
        if (resident(l.levels[static_cast<std::size_t>(c)].file)) {
          finer_only.emplace_back(leaf, c);
          break;
        }
    }
    for (const auto& [leaf, level] : finer_only) {
      const std::uint64_t count = m_set.leaves[leaf].levels[static_cast<std::size_t>(level)].count;
      if (drawn_total + count > cut_options.budget && cut_options.budget != 0) continue;
      draw_level[leaf] = level;
      drawn_total += count;
    }
    for (std::size_t leaf = 0; leaf < cut.level.size(); ++leaf) {
      const int want = cut.level[leaf], draw = draw_level[leaf];
      if (want < 0) continue;
      const LodLeaf& l = m_set.leaves[leaf];
      if (draw != want) {
        const float error = lod_leaf_error_px(m_set, static_cast<int>(leaf), draw < 0 ? levels - 1 : draw, camera);
        wanted.emplace_back(draw < 0 ? std::numeric_limits<float>::max() : error, l.levels[static_cast<std::size_t>(want)].file);
      }
      if (draw < 0) {
        ++stats.leaves_missing;
        continue;
      }
      stats.leaves_coarser += draw > want;
      ++stats.leaves_drawn;
      const LodRange& range = l.levels[static_cast<std::size_t>(draw)];
      Chunk& chunk = m_chunks[static_cast<std::size_t>(range.file)];
      chunk.last_used = m_frame;
      drawn.push_back(range);
      sources.push_back(chunk.scene);
      stats.drawn_per_level[static_cast<std::size_t>(draw)] += range.count;
    }
    std::stable_sort(wanted.begin(), wanted.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<int> files;
    for (const auto& w : wanted) files.push_back(w.second);
    for (std::size_t leaf = 0; leaf < ahead.level.size(); ++leaf)
      if (ahead.level[leaf] >= 0) files.push_back(m_set.leaves[leaf].levels[static_cast<std::size_t>(ahead.level[leaf])].file);
    request(files);
    if (!m_queue.empty()) m_wake.notify_all();
  }
  m_cut = std::move(cut);
  return result;
}

bool LodStreamer::same_as_drawn(const std::vector<LodRange>& drawn) const {
  return drawn.size() == m_drawn.size() &&
         std::equal(drawn.begin(), drawn.end(), m_drawn.begin(), [](const LodRange& a, const LodRange& b) {
           return a.file == b.file && a.offset == b.offset && a.count == b.count;
         });
}

std::shared_ptr<const Scene> LodStreamer::update(const Camera& camera) {
  Drawn drawn = choose(camera);
  if (!same_as_drawn(drawn.ranges) || !m_scene) {
    const std::vector<ScenePart> parts = as_parts(drawn);
    const std::uint64_t total = scene_parts_size(parts);
    {
      std::lock_guard<std::mutex> lock(m_mutex);  // the next scene is held beside the one drawn now
      m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes + total * m_bytes_per_gaussian);
    }
    m_scene = assemble_scene_parts(parts);
    m_drawn = std::move(drawn.ranges);
    std::lock_guard<std::mutex> lock(m_mutex);
    // The scene drawn now and the frame that renders it.
    m_drawn_bytes = m_scene->size() * ((1 + static_cast<std::uint64_t>(m_drawn_copies)) * m_bytes_per_gaussian +
                                       m_options.host_frame.per_gaussian) +
                    m_options.host_frame.fixed;
    m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes);
  }
  m_stats.drawn_gaussians = m_scene->size();
  return m_scene;
}

const std::vector<ScenePart>& LodStreamer::update_parts(const Camera& camera, bool* changed) {
  Drawn drawn = choose(camera);
  const bool differ = !same_as_drawn(drawn.ranges) || m_parts.empty();
  if (differ) {
    m_parts = as_parts(drawn);
    m_drawn = std::move(drawn.ranges);
    m_scene.reset();  // the renderer holds the parts
    std::lock_guard<std::mutex> lock(m_mutex);
    // The next scene is made beside the one drawn now.
    m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes + parts_scene_bytes());
    m_drawn_bytes = parts_drawn_bytes();
    m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes);
  }
  m_stats.drawn_gaussians = scene_parts_size(m_parts);
  if (changed) *changed = differ;
  return m_parts;
}

std::uint64_t LodStreamer::parts_scene_bytes() const {
  // The scene a host renderer assembles from the parts (none where the GPU keeps them), and the
  // overlay's copies.
  const std::uint64_t total = scene_parts_size(m_parts);
  const std::uint64_t scenes = (m_options.parts_on_device ? 0 : 1) + static_cast<std::uint64_t>(m_drawn_copies);
  return scenes * total * m_bytes_per_gaussian;
}

std::uint64_t LodStreamer::parts_drawn_bytes() const {
  return parts_scene_bytes() + scene_parts_size(m_parts) * m_options.host_frame.per_gaussian + m_options.host_frame.fixed;
}

void LodStreamer::set_parts_on_device(bool on) {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (on == m_options.parts_on_device) return;
  m_options.parts_on_device = on;
  if (m_parts.empty()) return;
  m_drawn_bytes = parts_drawn_bytes();
  m_high_water = std::max(m_high_water, m_chunk_bytes + m_reserved + m_drawn_bytes);
}

std::vector<ScenePart> LodStreamer::as_parts(const Drawn& drawn) {
  std::vector<ScenePart> parts;
  parts.reserve(drawn.ranges.size());
  for (std::size_t i = 0; i < drawn.ranges.size(); ++i) {
    const LodRange& r = drawn.ranges[i];
    // A range of a chunk file never changes: the file and offset name it.
    parts.push_back(ScenePart{static_cast<std::uint64_t>(r.file) << 40 | r.offset, drawn.sources[i], r.offset, r.count});
  }
  return parts;
}

std::uint64_t LodStreamer::device_resident_bytes() const {
  if (!m_options.device_bytes) return 0;
  const std::uint64_t drawn_budget = m_budget == std::numeric_limits<std::uint64_t>::max() ? 0 : m_budget;
  const std::uint64_t frame = m_options.device_frame.fixed + drawn_budget * m_options.device_frame.per_gaussian;
  return m_options.device_bytes > frame ? m_options.device_bytes - frame : 1;
}

LodStreamStats LodStreamer::stats() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  LodStreamStats s = m_stats;
  for (const Chunk& c : m_chunks) {
    s.files_resident += c.state == ChunkState::resident;
    s.files_queued += c.state == ChunkState::queued || c.state == ChunkState::loading;
    s.files_failed += c.state == ChunkState::failed;
  }
  s.host_bytes = m_chunk_bytes + m_reserved + m_drawn_bytes;
  s.host_high_water = m_high_water;
  s.bytes_read = m_bytes_read;
  return s;
}

void LodStreamer::wait_until_idle() {
  std::unique_lock<std::mutex> lock(m_mutex);
  m_idle.wait(lock, [this] { return m_queue.empty() && m_loading == 0; });
}

std::vector<std::string> LodStreamer::take_errors() {
  std::lock_guard<std::mutex> lock(m_mutex);
  std::vector<std::string> out;
  out.swap(m_errors);
  return out;
}

}  // namespace flashgs
