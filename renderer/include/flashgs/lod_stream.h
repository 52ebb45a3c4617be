// Streaming a LOD set by view: each frame's cut is drawn from the chunks in memory (a leaf whose
// chunk has not arrived is drawn at a coarser level that has), while background threads load
// what the cut asks for, under a host memory cap with least-recently-used eviction.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/frame_memory.h"
#include "flashgs/lod_cut.h"
#include "flashgs/lod_set.h"
#include "flashgs/scene.h"
#include "flashgs/scene_parts.h"

namespace flashgs {

// What the renderer needs beside the drawn scene to render it: fixed bytes (the image, the
// tiles) and bytes per drawn Gaussian (its records and pairs).
struct LodFrameCost {
  std::uint64_t fixed = 0, per_gaussian = 0;
};
// The host and GPU costs of a width x height frame on `backend` (estimate_frame_memory, with
// four pairs per Gaussian).
void lod_frame_costs(BackendKind backend, int width, int height, int cpu_threads, LodFrameCost* host,
                     LodFrameCost* device);

struct LodStreamOptions {
  LodCutOptions cut;
  // The caps: everything the stream and the renderer hold (chunks, loads in flight, the drawn
  // scene and the next, the frame's working memory); 0 = no cap. device_bytes: the drawn scene
  // uploaded and the frame's GPU memory (CUDA backend).
  std::uint64_t host_bytes = 0;
  std::uint64_t device_bytes = 0;
  LodFrameCost host_frame, device_frame;
  // Whether update_parts' renderer keeps the parts in GPU memory (the CUDA backend's pool);
  // otherwise it assembles them into one scene in host memory (Renderer::set_scene_parts by
  // default), which the host cap counts as it counts update()'s scene.
  bool parts_on_device = false;
  int threads = 2;                 // chunk loaders
  bool prefetch = true;            // also load what the view will need if the camera keeps moving
};

struct LodStreamStats {
  std::uint64_t budget = 0;          // the Gaussians a cut may take after the caps
  std::uint64_t drawn_gaussians = 0; // in the scene update() returned
  std::vector<std::uint64_t> drawn_per_level;
  int leaves_drawn = 0;
  int leaves_coarser = 0;  // drawn coarser than the cut wants: their chunk is on its way
  int leaves_missing = 0;  // in the cut but with no level in memory yet
  int files_resident = 0, files_queued = 0, files_failed = 0;
  std::uint64_t host_bytes = 0, host_high_water = 0;  // chunks, loads in flight, drawn scenes, the frame
  std::uint64_t bytes_read = 0;                        // chunk file bytes read so far
  float worst_error_px = 0;                            // of the cut wanted
};

class LodStreamer {
 public:
  LodStreamer(LodSet set, LodStreamOptions options);
  ~LodStreamer();
  LodStreamer(const LodStreamer&) = delete;
  LodStreamer& operator=(const LodStreamer&) = delete;

  // Chooses the cut for `camera`, asks for the chunks it lacks and returns the scene to draw:
  // the same pointer as before while nothing drawn changed. Never waits for a chunk.
  std::shared_ptr<const Scene> update(const Camera& camera);
  // The same cut as parts of the chunks in memory (ScenePart::key: the chunk file and offset)
  // for Renderer::set_scene_parts; the streamer then holds no drawn scene (the renderer does,
  // on the GPU or assembled: LodStreamOptions::parts_on_device). `changed`: whether they differ
  // from the last call's.
  const std::vector<ScenePart>& update_parts(const Camera& camera, bool* changed);
  // What Renderer::set_scene_parts may keep on the GPU under the device cap: the cap less the
  // frame's memory at the budget (0: no cap).
  std::uint64_t device_resident_bytes() const;
  LodStreamStats stats() const;
  // Blocks until no chunk is queued or loading (tests; a benchmark's warm start).
  void wait_until_idle();
  // One line per chunk that could not be read since the last call (the rest keeps rendering).
  std::vector<std::string> take_errors();
  const LodSet& set() const { return m_set; }
  // Copies of the drawn scene held on the host beside it (the level overlay's tinted parts,
  // LodCutFeed): the host cap makes room for them with a smaller budget, from the next cut on.
  // Called from the thread that calls update().
  void set_drawn_copies(int copies);
  // Whether update_parts' renderer keeps the parts on the GPU now (LodStreamOptions::
  // parts_on_device): a GPU path takes the cut assembled for a configuration its pool cannot
  // draw, and the host cap then counts that scene. From the thread that calls update_parts().
  void set_parts_on_device(bool on);
  // The ranges of the scene update() or the parts update_parts() last returned, in their order
  // (the level overlay's input).
  const std::vector<LodRange>& drawn_ranges() const { return m_drawn; }

 private:
  struct Chunk;
  // The ranges a cut draws and the chunk scenes they are in.
  struct Drawn {
    std::vector<LodRange> ranges;
    std::vector<std::shared_ptr<const Scene>> sources;
  };
  // Chooses the cut, asks for the chunks it lacks and fills m_stats but its drawn count.
  Drawn choose(const Camera& camera);
  bool same_as_drawn(const std::vector<LodRange>& drawn) const;
  static std::vector<ScenePart> as_parts(const Drawn& drawn);
  void load_loop();
  std::uint64_t chunk_estimate(int file) const;
  // The budget and the chunks' share of the caps, for m_drawn_copies (under the lock, or before
  // the loaders start).
  void apply_caps();
  // What update_parts' cut holds on the host: its assembled scene and copies (under the lock),
  // and with the frame's working memory.
  std::uint64_t parts_scene_bytes() const;
  std::uint64_t parts_drawn_bytes() const;
  bool make_room(std::uint64_t bytes, std::unique_lock<std::mutex>& lock);
  void request(const std::vector<int>& files);

  LodSet m_set;
  LodStreamOptions m_options;
  std::uint64_t m_bytes_per_gaussian = 0;
  std::uint64_t m_budget = 0, m_chunk_cap = 0;
  int m_drawn_copies = 0;
  std::vector<std::uint64_t> m_file_gaussians;  // the largest range end of each file
  std::vector<bool> m_pinned;                   // the coarsest level's files
  LodFileBudget m_file_budget;                  // what the cut's files may take: the chunk cap less loads in flight

  mutable std::mutex m_mutex;
  std::condition_variable m_wake, m_idle;
  std::vector<Chunk> m_chunks;
  std::vector<int> m_queue;  // files to load, most wanted first
  int m_loading = 0;
  bool m_stop = false;
  std::uint64_t m_frame = 0;
  std::uint64_t m_chunk_bytes = 0, m_reserved = 0, m_drawn_bytes = 0, m_high_water = 0, m_bytes_read = 0;
  std::vector<std::string> m_errors;

  LodCut m_cut;
  std::vector<LodRange> m_drawn;  // what m_scene holds, in leaf order
  std::shared_ptr<const Scene> m_scene;  // update()'s
  std::vector<ScenePart> m_parts;        // update_parts()'s
  LodStreamStats m_stats;
  bool m_have_last_position = false;
  float m_last_position[3] = {0, 0, 0};
  std::vector<std::thread> m_threads;
};

}  // namespace flashgs
