// The debug views in the window: the shown frame's depth or blended-count planes coloured and uploaded in place of its colour.
#include <cstdio>

#include "image_presenter_gl.h"
#include "viewer_app_gl.h"

namespace flashgs::viewer {

void ViewerApp::show_debug_view() {
  const FrameView want = m_settings.view;
  const std::size_t pixels = static_cast<std::size_t>(m_last_camera.width) * m_last_camera.height;
  const bool planes = m_have_frame && m_last_options.collect_pixel_planes && m_stats.pixel_depth.size() == pixels &&
                      m_stats.pixel_blended.size() == pixels;
  if (want == FrameView::colour || !planes) {
    // Back to colour: the next frame (asked for without planes) replaces the debug image.
    if (want == FrameView::colour) m_debug_shown = FrameView::colour;
    return;
  }
  // Depth and count come from the same planes: switching between them needs no render.
  if (!m_delivered && want == m_debug_shown) return;
  try {
    m_debug_scale = debug_scale(m_stats);
    m_debug_image = debug_view_image(want, m_stats, m_last_camera.width, m_last_camera.height, m_debug_scale,
                                     m_last_options.background);
    m_path->present_latest();
    m_presenter->upload(m_debug_image);
    m_debug_shown = want;
  } catch (const std::exception& e) {  // the texture refused: keep running with the colour
    m_status = std::string("debug view failed: ") + e.what();
    std::fprintf(stderr, "flashgs-viewer: %s\n", m_status.c_str());
    m_debug_shown = FrameView::colour;
    return;
  }
  const std::string line = debug_legend_line(want, m_debug_scale);
  if (line == m_logged_debug_legend) return;
  m_logged_debug_legend = line;
  std::fprintf(stderr, "flashgs-viewer: %s\n", line.c_str());
}

}  // namespace flashgs::viewer
