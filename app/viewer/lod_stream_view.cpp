// Streaming a LOD set in the viewer: the streamer made from the set and the settings, its summary.
#include "lod_stream_view.h"

#include <cstdio>

#include "count_text.h"
#include "flashgs/lod_set.h"
#include "flashgs/lod_tint.h"

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
  return options;
}

}  // namespace

void LodStreamView::start(const std::string& meta_path, const StreamSettings& settings) {
  auto streamer = std::make_unique<LodStreamer>(read_lod_set(meta_path), stream_options(settings));
  m_streamer = std::move(streamer);
  m_meta_path = meta_path;
  m_settings = settings;
}

void LodStreamView::stop() {
  m_streamer.reset();
  m_tinted_from.reset();
  m_tinted.reset();
  m_read_rates.clear();
}

std::shared_ptr<const Scene> LodStreamView::update(const Camera& camera, bool settle, double now_s) {
  if (!m_streamer) return nullptr;
  if (settle) {
    m_streamer->update(camera);
    m_streamer->wait_until_idle();
  }
  std::shared_ptr<const Scene> scene = m_streamer->update(camera);
  m_read_rates.observe(now_s, m_streamer->stats().bytes_read);
  if (!m_overlay || !scene) {
    m_tinted_from.reset();
    m_tinted.reset();
    return scene;
  }
  if (scene != m_tinted_from) {  // a copy of what is drawn, the levels' colours in place of the scene's
    m_tinted = std::make_shared<const Scene>(tint_by_level(*scene, lod_level_runs(m_streamer->set(), m_streamer->drawn_ranges())));
    m_tinted_from = scene;
  }
  return m_tinted;
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
  char text[320];
  std::snprintf(text, sizeof text, "%s drawn (levels %s), %d chunks in memory, %d coming%s, %.0f MB (high %.0f MB)",
                human_count(double(s.drawn_gaussians)).c_str(), levels.empty() ? "none" : levels.c_str(), s.files_resident,
                s.files_queued, s.files_failed ? (", " + std::to_string(s.files_failed) + " unreadable").c_str() : "",
                static_cast<double>(s.host_bytes) / 1e6, static_cast<double>(s.host_high_water) / 1e6);
  return text;
}

std::vector<std::string> LodStreamView::take_errors() {
  return m_streamer ? m_streamer->take_errors() : std::vector<std::string>{};
}

}  // namespace flashgs::viewer
