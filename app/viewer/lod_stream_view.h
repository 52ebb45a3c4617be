// The viewer's streaming of a LOD set by view: the streamer and the feed that hands its cut to
// the frame path as parts, its live budget and error bound, and the one-line summary the panel
// shows and the log keeps.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "flashgs/camera.h"
#include "flashgs/lod_feed.h"
#include "flashgs/lod_stream.h"
#include "flashgs/options.h"
#include "flashgs/scene_parts.h"
#include "frame_path.h"
#include "read_rate_history.h"

namespace flashgs::viewer {

struct StreamSettings {
  std::uint64_t budget = 0;   // Gaussians drawn at most, 0: the caps' only
  float max_error_px = kDefaultLodMaxErrorPx;  // refine while a leaf's error is larger
  std::uint64_t host_bytes = 0, device_bytes = 0;  // 0: no cap
  LodFrameCost host_frame, device_frame;           // what the renderer needs beside the scene
  bool parts_on_device = false;                    // the renderer keeps the parts on the GPU (LodStreamOptions)
};

// What LodStreamView::update did.
struct StreamUpdate {
  bool handed = false;             // a cut went to the path: a new frame is needed
  bool assembled_changed = false;  // the cut goes to the path assembled now, or as parts again
  std::string path_error;          // the path refused the cut (out of GPU memory): tried again next time
  std::string overlay_error;       // the overlay's copies could not be made: the overlay is off now
};

class LodStreamView {
 public:
  // Starts streaming the set at `meta_path` (lod-meta.json). Throws flashgs::Error naming the
  // file when it cannot be read; the previous stream, if any, then stays.
  void start(const std::string& meta_path, const StreamSettings& settings);
  void stop();
  bool active() const { return m_streamer != nullptr; }
  // Chooses the cut for `camera` and hands it to `path` when what is drawn changed, the level
  // overlay was turned on or off or hand_over_again() was called (LodCutFeed::update): as parts
  // (FramePath::set_scene_parts, under the streamer's GPU cap), or assembled into one scene
  // (set_scene) where the path cannot draw parts with `options` (the GPU's pool and the
  // baseline: FramePath::scene_parts_refusal). `settle`: wait for the view's chunks first
  // (scripted runs, whose frames must not depend on how fast the disk was). `now_s`: a steady
  // clock's seconds, for the read rate.
  StreamUpdate update(const Camera& camera, const RenderOptions& options, bool settle, double now_s, FramePath& path);
  // Gives `path` the last cut assembled now where it went as parts and the path cannot draw them
  // with one of `options` (a comparison's sides); the next update() hands it over again. Returns
  // why (empty: nothing was done). Throws what the path's set_scene throws.
  std::string assemble_for(const std::vector<RenderOptions>& options, FramePath& path);
  // Why the cut goes to the path assembled (empty: as parts).
  const std::string& assembled_because() const { return m_assembled_because; }
  // The next update() hands the cut over again (the frame path was replaced).
  void hand_over_again();
  // The level overlay: each Gaussian drawn in its level's colour (lod_level_colour).
  void set_level_overlay(bool on);
  bool level_overlay() const { return m_overlay; }
  // What the frame path was last handed (empty before the first cut): tinted while the overlay is on.
  const std::vector<ScenePart>& drawn_parts() const;
  const ReadRateHistory& read_rates() const { return m_read_rates; }
  // Budget and error bound changed live (the streamer is made again; its chunks are read again).
  void change(const StreamSettings& settings);
  const StreamSettings& settings() const { return m_settings; }
  LodStreamStats stats() const;
  // Chunks are on their way: the window keeps drawing so that they show as they arrive.
  bool loading() const;
  // "1.2M drawn (levels 0:.. 1:..), 14 chunks in memory, 3 coming, 512 MB (high 600 MB), 14 parts
  // handed over (hand-over 3: 2 new)"
  std::string summary() const;
  std::vector<std::string> take_errors();

 private:
  std::string m_meta_path;
  StreamSettings m_settings;
  std::unique_ptr<LodStreamer> m_streamer;
  std::unique_ptr<LodCutFeed> m_feed;  // of m_streamer
  bool m_overlay = false;
  std::string m_assembled_because;
  ReadRateHistory m_read_rates;
};

}  // namespace flashgs::viewer
