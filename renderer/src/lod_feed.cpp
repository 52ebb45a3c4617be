// The LOD cut feed: the streamer's parts handed to a renderer when they change, tinted by level on request.
#include "flashgs/lod_feed.h"

#include <algorithm>
#include <unordered_set>

namespace flashgs {

bool LodCutFeed::same_as_handed(const std::vector<ScenePart>& cut) const {
  return cut.size() == m_handed.size() &&
         std::equal(cut.begin(), cut.end(), m_handed.begin(), [](const ScenePart& a, const ScenePart& handed) {
           return a.key == (handed.key & ~kTintedPartKeyBit) && a.count == handed.count;
         });
}

void LodCutFeed::set_level_overlay(bool on) {
  if (on == m_overlay) return;
  m_overlay = on;
  m_stale = true;
  if (!on) m_tinted.clear();
  m_streamer.set_drawn_copies(on ? 1 : 0);  // the tinted copies count against the host cap
}

bool LodCutFeed::update(const Camera& camera, const HandOver& hand_over) {
  // The streamer's own `changed` is not used: anyone may have asked it for the cut since (a
  // scripted run settling its view).
  const std::vector<ScenePart>& cut = m_streamer.update_parts(camera, nullptr);
  m_cut_gaussians = scene_parts_size(cut);
  if (cut.empty() || (!m_stale && same_as_handed(cut))) return false;
  m_stale = true;  // until the renderer has it
  std::vector<ScenePart> parts =
      m_overlay ? tint_parts_by_level(cut, lod_level_runs(m_streamer.set(), m_streamer.drawn_ranges()), m_tinted) : cut;
  hand_over(parts, m_streamer.device_resident_bytes());
  std::unordered_set<std::uint64_t> before;
  for (const ScenePart& p : m_handed) before.insert(p.key);
  m_stats.new_parts = static_cast<std::size_t>(
      std::count_if(parts.begin(), parts.end(), [&](const ScenePart& p) { return before.count(p.key) == 0; }));
  m_stats.parts = parts.size();
  ++m_stats.hand_overs;
  m_handed = std::move(parts);
  m_stale = false;
  return true;
}

bool LodCutFeed::update(const Camera& camera, Renderer& renderer) {
  return update(camera, [&renderer](const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) {
    renderer.set_scene_parts(parts, resident_bytes);
  });
}

}  // namespace flashgs
