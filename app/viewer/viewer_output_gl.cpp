// What the viewer writes out: screenshots (the rendered image, or the window), the camera
// path's frames and video, and the scripted check of the displayed frame.
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "flashgs/file_access.h"
#include "flashgs/image_io.h"
#include "gl_headers_gl.h"
#include "image_presenter_gl.h"
#include "viewer_app_gl.h"
#include "window_gl.h"

namespace flashgs::viewer {

void ViewerApp::take_screenshot(const std::string& path) {
  // With the overlay: the framebuffer once this frame's image and heat map are drawn, before
  // the panels; else the rendered image itself.
  if (m_settings.screenshot_overlay && m_settings.heatmap) m_pending_overlay_shot = path;
  else save_screenshot(path);
}

void ViewerApp::save_screenshot(const std::string& path) {
  try {
    m_path->present_latest();
    m_presenter->show(m_path->shown_texture());
    check_output_file(path);  // before the frame may be rendered again for it
    Image image;
    const Image* host = m_path->last_image();
    const std::string ext = std::filesystem::path(path).extension().string();
    if (m_debug_shown != FrameView::colour) {
      image = m_debug_image;  // the debug view on screen, as shown
    } else if (host && host->width == m_presenter->width() && host->height == m_presenter->height()) {
      image = *host;
    } else if (ext == ".exr" || ext == ".EXR" || ext == ".pfm") {
      // Float formats get the float frame, rendered again for the same view.
      m_path->render_image(m_last_camera, m_last_options, image, nullptr, nullptr);
    } else {
      image = m_presenter->read_back();  // what the window shows, byte for byte
    }
    write_image(image, path);
    m_status = "saved " + path + " (" + std::to_string(image.width) + "x" + std::to_string(image.height) + ")";
    std::fprintf(stderr, "flashgs-viewer: %s\n", m_status.c_str());
  } catch (const std::exception& e) {
    m_status = std::string("screenshot failed: ") + e.what();
    std::fprintf(stderr, "flashgs-viewer: %s\n", m_status.c_str());
    if (m_scripted) m_exit_code = 2;
  }
}

void ViewerApp::save_window_screenshot(const std::string& path, int width, int height) {
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(width) * height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  Image image;
  image.resize(width, height);
  for (int y = 0; y < height; ++y)  // GL's row 0 is the bottom
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        image.pixel(x, y)[c] = rgba[(static_cast<std::size_t>(height - 1 - y) * width + x) * 4 + c] / 255.0f;
  try {
    write_image(image, path);
    std::fprintf(stderr, "flashgs-viewer: saved window %s (%dx%d)\n", path.c_str(), width, height);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flashgs-viewer: window screenshot failed: %s\n", e.what());
    m_exit_code = 2;
  }
  if (m_close_after_shot) m_window->request_close();
}

void ViewerApp::check_displayed_frame() {
  // What the window shows (the texture, written by interop or uploaded) against the same
  // backend's host-memory image of the same view, rounded to 8 bits as the texture is: catches
  // a flipped, shifted, channel-swapped or stale frame on any path.
  m_path->present_latest();
  m_presenter->show(m_path->shown_texture());
  const Image shown = m_presenter->read_back();
  Image expected;
  m_path->render_image(m_last_camera, m_last_options, expected, nullptr, nullptr);
  int worst = 0;
  std::size_t off = 0;
  if (shown.width != expected.width || shown.height != expected.height) {
    worst = 255;
  } else {
    for (std::size_t i = 0; i < shown.rgb.size(); ++i) {
      const float e = expected.rgb[i];
      const int want = !(e > 0.0f) ? 0 : static_cast<int>(std::lround(std::min(e, 1.0f) * 255.0f));
      const int got = static_cast<int>(std::lround(shown.rgb[i] * 255.0f));
      const int d = std::abs(want - got);
      worst = std::max(worst, d);
      off += d > 1;
    }
  }
  // One step of 8-bit rounding is allowed: the GPU's conversion may round a value that sits
  // on a half step the other way.
  const bool ok = worst <= 1;
  std::printf("viewer frame check: displayed %dx%d vs %s host image: max diff %d/255, %zu values off by > 1 -> %s\n",
              shown.width, shown.height, m_path->name().c_str(), worst, off, ok ? "ok" : "WRONG");
  if (!ok) m_exit_code = 4;
}

void ViewerApp::start_path_export(const std::string& folder, int frames) {
  if (!m_export_from_keys && (!m_camera_path || m_camera_path->empty())) {
    set_notice("path export: the scene has no cameras to make a path from");
    if (m_scripted) m_exit_code = 2;
    return;
  }
  if (m_export_job.busy()) {
    set_notice("path export: the last export is still finishing (" +
               std::string(m_encoding_video ? "ffmpeg" : "a frame") + "); try again when it is done");
    if (m_scripted) m_exit_code = 2;
    return;
  }
  const std::string problem = m_export.start(folder, frames);
  if (!problem.empty()) {
    set_notice(problem);
    if (m_scripted) m_exit_code = 2;
    return;
  }
  m_playing = false;
  std::fprintf(stderr, "flashgs-viewer: path export: %d frames into %s\n", frames, folder.c_str());
}

void ViewerApp::export_step() {
  const bool on_thread = m_path->renders_in_background() && !m_scripted;
  std::string error;
  if (m_encoding_video) {  // the last step: ffmpeg, beside the frame loop too
    if (!m_export_job.take(&error)) return;
    m_encoding_video = false;
    set_notice(exported_frames_line() + (error.empty() ? ", video " + m_export.video_file() : ", " + error));
    return;
  }
  // The frame in flight, finished: written, or the export stops with why.
  if (m_export_job.take(&error)) {
    if (!m_export.active()) return;  // the frame of an export stopped meanwhile: dropped
    if (!error.empty()) {
      set_notice("path export stopped: " + error);
      m_export.cancel();
      if (m_scripted) m_exit_code = 2;
      return;
    }
    m_export.advance();
    if (!m_export.active()) {
      const std::string video = m_export.video_command(m_export_from_keys ? m_export_keys.fps : 30);
      m_export_from_keys = false;
      if (video.empty()) {
        set_notice(exported_frames_line() + " (no ffmpeg on PATH: image sequence only)");
      } else {
        m_encoding_video = true;
        m_export_job.start(on_thread, [video](const std::atomic<bool>&) -> std::string {
          const int rc = std::system(video.c_str());
          return rc == 0 ? "" : "ffmpeg failed (exit " + std::to_string(rc) + ")";
        });
      }
      return;
    }
  }
  if (m_export_job.busy() || !m_export.active()) return;
  // The next frame renders and is written beside the frame loop where the path renders in the
  // background (the CPU), so the window keeps answering; scripted runs wait for each.
  // The keyed path at its own size and fps; the loop through the scene's cameras at the window's size.
  Camera camera;
  if (m_export_from_keys) {
    camera = m_export_keys.camera_at(m_export_keys.frame_time(m_export.done_frames()), m_export_keys.width,
                                     m_export_keys.height);
  } else {
    const int width = m_presenter->width() > 0 ? m_presenter->width() : 1280;
    const int height = m_presenter->height() > 0 ? m_presenter->height() : 720;
    CameraController at = m_controller;
    at.set_pose(m_camera_path->pose_at(m_export.next_t()));
    camera = at.render_camera(width, height, m_camera_path->fov_at(m_export.next_t()));
  }
  RenderOptions options = m_settings.options;
  options.collect_tile_counts = false;
  FramePath* path = m_path.get();
  const std::string file = m_export.next_file();
  m_export_job.start(on_thread,
                     [path, camera, options, file](const std::atomic<bool>& cancel) -> std::string {
                       Image image;
                       FrameStats stats;
                       path->render_image(camera, options, image, &stats, &cancel);
                       if (stats.cancelled) return "cancelled";
                       write_image(image, file);
                       return "";
                     });
}

void ViewerApp::stop_path_export(const std::string& verb, const std::string& why) {
  if (!m_export.active()) return;
  set_notice("path export " + verb + " after " + std::to_string(m_export.done_frames()) + " frames" + why);
  m_export.cancel();
  m_export_from_keys = false;
  // The frame in flight stops at its renderer's next check (the CPU's are between tiles);
  // export_step takes it and drops it, and a new export waits for that.
  m_export_job.cancel();
}

std::string ViewerApp::exported_frames_line() const {
  return "path export: " + std::to_string(m_export.done_frames()) + " frames in " + m_export.folder();
}

}  // namespace flashgs::viewer
