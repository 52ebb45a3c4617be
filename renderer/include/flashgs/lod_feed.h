// Handing a streamed LOD set's cut to a renderer frame by frame, as parts under the GPU cap the
// streamer reports, optionally coloured by level: what `flashgs lod fly` and the viewer share.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "flashgs/camera.h"
#include "flashgs/lod_stream.h"
#include "flashgs/lod_tint.h"
#include "flashgs/renderer.h"
#include "flashgs/scene_parts.h"

namespace flashgs {

// What a feed has handed over since it was made.
struct LodFeedStats {
  std::uint64_t hand_overs = 0;  // cuts handed to the renderer
  std::size_t parts = 0;         // of the last one
  std::size_t new_parts = 0;     // of the last one, not in the one before (what a GPU pool uploads at most)
};

class LodCutFeed {
 public:
  // Renderer::set_scene_parts, or what passes the parts on to it (the viewer's frame path).
  using HandOver = std::function<void(const std::vector<ScenePart>& parts, std::uint64_t resident_bytes)>;

  explicit LodCutFeed(LodStreamer& streamer) : m_streamer(streamer) {}

  // Chooses the cut for `camera` (LodStreamer::update_parts) and hands it over when it differs
  // from the last one handed over, the overlay changed or hand_over_again() was called; an empty
  // cut (no chunk in memory yet) is never handed over: the renderer keeps what it has. Returns
  // whether it handed one over. Exceptions propagate (from the overlay's copies or `hand_over`);
  // the cut is then handed over again at the next call.
  bool update(const Camera& camera, const HandOver& hand_over);
  bool update(const Camera& camera, Renderer& renderer);

  // The level overlay: the parts handed over are copies coloured by level (tint_parts_by_level).
  void set_level_overlay(bool on);
  bool level_overlay() const { return m_overlay; }
  // The next update() hands the cut over even if unchanged (the renderer was replaced).
  void hand_over_again() { m_stale = true; }

  // The Gaussians of the last update()'s cut (0: nothing in memory to draw yet).
  std::uint64_t cut_gaussians() const { return m_cut_gaussians; }
  // What was last handed over: tinted copies while the overlay is on.
  const std::vector<ScenePart>& handed_parts() const { return m_handed; }
  const LodFeedStats& stats() const { return m_stats; }

 private:
  bool same_as_handed(const std::vector<ScenePart>& cut) const;

  LodStreamer& m_streamer;
  bool m_overlay = false;
  bool m_stale = true;                // hand over at the next update whatever the cut
  std::vector<ScenePart> m_handed;    // what the renderer got
  TintedParts m_tinted;               // the overlay's copies of the parts handed over
  std::uint64_t m_cut_gaussians = 0;
  LodFeedStats m_stats;
};

}  // namespace flashgs
