// Streaming a LOD set in the viewer: the streamer made from the set and the settings, its cut
// handed to the frame path, its summary.
#include "lod_stream_view.h"

#include <cstdio>

#include "count_text.h"
#include "flashgs/error.h"
#include "flashgs/lod_set.h"

namespace flashgs::viewer {
namespace {

LodStreamOptions stream_options(const StreamSettings& s) {
  LodStreamOptions options;
  options.cut.budget = s.budget;
  options.cut.max_error_px = s.max_error_px;
  options.host_bytes = s.host_bytes;
  options.device_bytes = s.device_bytes;
  options.host_frame = s.host_frame;
  options.device_frame = s.device_frame;
  options.parts_on_device = s.parts_on_device;
  return options;
}

}  // namespace

void LodStreamView::start(const std::string& meta_path, const StreamSettings& settings) {
  auto streamer = std::make_unique<LodStreamer>(read_lod_set(meta_path), stream_options(settings));
  auto feed = std::make_unique<LodCutFeed>(*streamer);
  feed->set_level_overlay(m_overlay);
  m_feed = std::move(feed);  // before the streamer it refers to goes
  m_streamer = std::move(streamer);
  m_meta_path = meta_path;
  m_settings = settings;
}

void LodStreamView::stop() {
  m_feed.reset();
  m_streamer.reset();
  m_assembled_because.clear();
  m_read_rates.clear();
}

StreamUpdate LodStreamView::update(const Camera& camera, const RenderOptions& options, bool settle, double now_s,
                                   FramePath& path) {
  StreamUpdate out;
  if (!m_streamer) return out;
  const std::string refusal = path.scene_parts_refusal(options);
  if (refusal.empty() != m_assembled_because.empty()) {
    m_feed->hand_over_again();
    out.assembled_changed = true;
  }
  m_assembled_because = refusal;
  m_streamer->set_parts_on_device(m_settings.parts_on_device && refusal.empty());  // an assembled cut is the host's
  if (settle) {
    m_streamer->update_parts(camera, nullptr);
    m_streamer->wait_until_idle();
  }
  bool path_failed = false;
  const auto hand_over = [&](const std::vector<ScenePart>& parts, std::uint64_t resident_bytes) {
    try {
      if (m_assembled_because.empty()) path.set_scene_parts(parts, resident_bytes);
      else path.set_scene(assemble_scene_parts(parts));
    } catch (...) {
      path_failed = true;
      throw;
    }
  };
  try {
    out.handed = m_feed->update(camera, hand_over);
  } catch (const std::exception& e) {
    if (path_failed || !m_overlay) {
      out.path_error = error_text(e);
    } else {  // the overlay's copies: the scene's own colours instead
      out.overlay_error = error_text(e);
      set_level_overlay(false);
      try {
        out.handed = m_feed->update(camera, hand_over);
      } catch (const std::exception& again) {
        out.path_error = error_text(again);
      }
    }
  }
  m_read_rates.observe(now_s, m_streamer->stats().bytes_read);
  return out;
}

std::string LodStreamView::assemble_for(const std::vector<RenderOptions>& options, FramePath& path) {
  if (!m_feed || m_feed->handed_parts().empty() || !m_assembled_because.empty()) return "";
  std::string refusal;
  for (const RenderOptions& o : options)
    if (refusal.empty()) refusal = path.scene_parts_refusal(o);
  if (refusal.empty()) return "";
  m_streamer->set_parts_on_device(false);  // until the next update hands parts over again
  path.set_scene(assemble_scene_parts(m_feed->handed_parts()));
  m_feed->hand_over_again();
  return refusal;
}

void LodStreamView::hand_over_again() {
  if (m_feed) m_feed->hand_over_again();
}

void LodStreamView::set_level_overlay(bool on) {
  m_overlay = on;
  if (m_feed) m_feed->set_level_overlay(on);
}

const std::vector<ScenePart>& LodStreamView::drawn_parts() const {
  static const std::vector<ScenePart> kNone;
  return m_feed ? m_feed->handed_parts() : kNone;
}

void LodStreamView::change(const StreamSettings& settings) {
  if (!m_streamer || (settings.budget == m_settings.budget && settings.max_error_px == m_settings.max_error_px)) return;
  start(m_meta_path, settings);
}

LodStreamStats LodStreamView::stats() const { return m_streamer ? m_streamer->stats() : LodStreamStats{}; }

bool LodStreamView::loading() const { return m_streamer && m_streamer->stats().files_queued > 0; }

std::string LodStreamView::summary() const {
  if (!m_streamer) return "";
  const LodStreamStats s = m_streamer->stats();
  std::string levels;
  for (std::size_t l = 0; l < s.drawn_per_level.size(); ++l)
    if (s.drawn_per_level[l]) levels += (levels.empty() ? "" : " ") + std::to_string(l) + ":" + human_count(double(s.drawn_per_level[l]));
  const LodFeedStats& f = m_feed->stats();
  char text[400];
  std::snprintf(text, sizeof text,
                "%s drawn (levels %s), %d chunks in memory, %d coming%s, %.0f MB (high %.0f MB), %zu parts handed over "
                "(hand-over %llu: %zu new)",
                human_count(double(s.drawn_gaussians)).c_str(), levels.empty() ? "none" : levels.c_str(), s.files_resident,
                s.files_queued, s.files_failed ? (", " + std::to_string(s.files_failed) + " unreadable").c_str() : "",
                static_cast<double>(s.host_bytes) / 1e6, static_cast<double>(s.host_high_water) / 1e6, f.parts,
                static_cast<unsigned long long>(f.hand_overs), f.new_parts);
  return text;
}

std::vector<std::string> LodStreamView::take_errors() {
  return m_streamer ? m_streamer->take_errors() : std::vector<std::string>{};
}

}  // namespace flashgs::viewer
