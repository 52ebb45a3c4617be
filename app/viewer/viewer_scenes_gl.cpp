// Opening scenes in the viewer: the first one (generated, named or the demo file, tiled), one
// the user opens (beside the frame loop, or at once in scripted runs), another LOD level, and
// installing a loaded scene into the frame path and the navigation.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>

#include "count_text.h"
#include "flashgs/demo_scene.h"
#include "flashgs/error.h"
#include "flashgs/scene_summary.h"
#include "flashgs/frame_memory.h"
#include "lod_cache.h"
#include "memory_budget.h"
#include "scene_state.h"
#include "viewer_app_gl.h"
#include "window_gl.h"

namespace flashgs::viewer {
namespace {

LodBuildOptions lod_cache_options(const ViewerArgs& args) {
  LodBuildOptions options;
  options.leaf_gaussians = args.lod_leaf_size;
  options.file_gaussians = args.lod_file_size;
  return options;
}

}  // namespace

void ViewerApp::install_scene(LoadedScene scene) {
  m_path->set_scene(scene.scene);  // throws on failure: the old scene stays
  m_stream.stop();  // a new scene, or a level chosen by hand
  // Another level of the same LOD set: the same place, seen from where the user stands.
  const bool same_place = !scene.lod_gaussians.empty() && scene.path == m_scene.path && m_scene.scene;
  m_scene = std::move(scene);
  m_compare_task.cancel();  // a comparison of the old scene: dropped when it ends...
  m_arrived = {};           // ...or while its textures are going up
  m_arrived_textures = 0;
  if (same_place) {
    m_compare = {};
    m_have_request = false;
    std::fprintf(stderr, "flashgs-viewer: %s: LOD level %d, %zu Gaussians\n", m_scene.path.c_str(), m_scene.lod_level,
                 m_scene.scene->size());
    return;
  }
  stop_path_export("stopped", ": another scene was opened");  // its frames follow the old scene's cameras
  m_camera_path = std::make_unique<CameraPath>(m_scene.cameras);
  m_coarse_next_frame = true;  // something on screen soon: the full frame of a large scene takes seconds
  m_playing = false;
  m_camera_index = -1;
  m_compare = {};
  m_settings.flip_up = m_args.flip_up;
  apply_up_choice();
  if (!m_scene.cameras.empty()) snap_to_camera(0);
  if (!m_args.orbit && !m_args.fly) {
    // Seen from around (the cameras stand outside it): orbit, as object viewers do; else fly.
    const bool object = is_object_sized(m_scene.centre, m_scene.extent, m_scene.cameras);
    m_settings.mode = object ? NavigationMode::orbit : NavigationMode::fly;
    std::fprintf(stderr, "flashgs-viewer: navigation: %s (%s)\n", object ? "orbit" : "fly",
                 object ? "the cameras look at the scene from around it" : "the cameras stand inside the scene");
  }
  // The kernel the scene was trained with, unless --kernel chose one for every scene.
  m_settings.options.kernel = m_args.kernel.resolve(*m_scene.scene);
  m_have_frame = false;
  m_have_request = false;
  std::string note;
  if (m_scene.report.dropped_non_finite)
    note += std::to_string(m_scene.report.dropped_non_finite) + " Gaussians with NaN/Inf dropped. ";
  if (!m_scene.cameras_note.empty()) note += m_scene.cameras_note;
  const std::string level = m_scene.lod_gaussians.empty()
                                ? ""
                                : "LOD level " + std::to_string(m_scene.lod_level) + " of 0.." +
                                      std::to_string(m_scene.lod_gaussians.size() - 1) + ", ";
  std::fprintf(stderr, "flashgs-viewer: %s: %s%zu Gaussians, SH degree %d, %zu cameras, %s kernel (%s)%s%s\n",
               m_scene.path.c_str(), level.c_str(), m_scene.scene->size(), m_scene.scene->sh_degree,
               m_scene.cameras.size(), m_settings.options.kernel.description().c_str(),
               m_args.kernel.chosen() ? "--kernel" : kernel_summary(m_scene.scene->trained_kernel).c_str(),
               note.empty() ? "" : "; ", note.c_str());
  if (m_args.stream) start_stream();
}

void ViewerApp::start_stream() {
  if (m_scene.lod_gaussians.empty()) {
    set_notice("--stream: " + m_scene.path + " is not a LOD set: drawn whole (`flashgs lod build` makes one)");
    return;
  }
  StreamSettings settings;
  settings.budget = m_args.stream_budget;
  settings.max_error_px = m_args.stream_max_error_px;
  settings.host_bytes = m_args.host_memory_mb << 20;
  settings.device_bytes = m_path_is_cpu ? 0 : m_args.gpu_memory_mb << 20;
  settings.parts_on_device = !m_path_is_cpu;
  int width = 0, height = 0;  // the frames' cost beside the scene, at the window's size
  m_window->framebuffer_size(&width, &height);
  lod_frame_costs(m_path_is_cpu ? BackendKind::cpu : BackendKind::cuda, std::max(width, 1), std::max(height, 1),
                  m_args.cpu_threads > 0 ? m_args.cpu_threads : static_cast<int>(std::thread::hardware_concurrency()),
                  &settings.host_frame, &settings.device_frame);
  m_settings.stream_max_error_px = settings.max_error_px;
  m_settings.stream_budget_millions = static_cast<float>(static_cast<double>(settings.budget) / 1e6);
  try {
    m_stream.start(m_scene.path, settings);
  } catch (const std::exception& e) {
    set_notice("--stream refused, level " + std::to_string(m_scene.lod_level) + " drawn whole: " + error_text(e));
    return;
  }
  m_stream_was_loading = true;
  std::fprintf(stderr, "flashgs-viewer: streaming %s by view (max error %.1f px, budget %s, host cap %s)\n",
               m_scene.path.c_str(), settings.max_error_px,
               settings.budget ? human_count(double(settings.budget)).c_str() : "the caps'",
               settings.host_bytes ? (std::to_string(m_args.host_memory_mb) + " MiB").c_str() : "none");
}

bool ViewerApp::update_stream(const Camera& camera, const RenderOptions& options) {
  StreamSettings wanted = m_stream.settings();
  wanted.max_error_px = m_settings.stream_max_error_px;
  wanted.budget = static_cast<std::uint64_t>(double(m_settings.stream_budget_millions) * 1e6);
  try {
    m_stream.change(wanted);
  } catch (const std::exception& e) {  // the set's files went away: the stream stops, the last cut stays
    set_notice("streaming stopped: " + error_text(e));
    try {  // as the scene: what the panel counts and a new frame path is given
      if (!m_stream.drawn_parts().empty()) m_scene.scene = assemble_scene_parts(m_stream.drawn_parts());
    } catch (const std::exception&) {  // no memory for it: the level loaded first
    }
    m_stream.stop();
    return false;
  }
  if (m_stream.level_overlay() != m_settings.lod_overlay) {
    m_stream.set_level_overlay(m_settings.lod_overlay);
    std::fprintf(stderr, "flashgs-viewer: level overlay %s\n", m_settings.lod_overlay ? "on" : "off");
  }
  // The cut goes to the frame path as parts: the GPU keeps them and uploads only new ones. Its
  // pool draws fewer configurations than a whole scene: for the others, the cut assembled.
  const StreamUpdate u = m_stream.update(camera, options, m_scripted, ms_since_start() / 1000.0, *m_path);
  if (u.assembled_changed)
    std::fprintf(stderr, "flashgs-viewer: the streamed cut goes to the renderer %s%s\n",
                 m_stream.assembled_because().empty() ? "as parts" : "assembled: ", m_stream.assembled_because().c_str());
  if (!u.overlay_error.empty()) {  // no memory for the overlay's copies: the scene's own colours
    set_notice("level overlay off: " + u.overlay_error);
    m_settings.lod_overlay = false;
  }
  if (!u.path_error.empty()) set_notice("streamed scene refused: " + u.path_error);  // out of GPU memory: again next frame
  for (const std::string& line : m_stream.take_errors()) set_notice(line);
  const bool loading = m_stream.loading();
  if (m_stream_was_loading && !loading)  // tests and users see when the view's chunks are all in
    std::fprintf(stderr, "flashgs-viewer: stream settled: %s\n", m_stream.summary().c_str());
  m_stream_was_loading = loading;
  return u.handed;
}

std::vector<ScenePart> ViewerApp::drawn_parts() const {
  if (!m_stream.drawn_parts().empty()) return m_stream.drawn_parts();
  if (!m_scene.scene) return {};
  return {ScenePart{0, m_scene.scene, 0, m_scene.scene->size()}};
}

void ViewerApp::report_failed_load(const std::string& error) {
  // Says what the window shows now: the scene from before, or (first load) nothing yet.
  m_load_error = m_scene.scene ? "load failed, scene kept: " + error : "load failed (no scene loaded yet): " + error;
  std::fprintf(stderr, "flashgs-viewer: %s\n", m_load_error.c_str());
}

bool ViewerApp::open_scene(const std::string& path) {
  m_path_buffer = path;  // kept in the box when it fails, to be corrected
  try {
    const std::string cameras = path == m_args.scene ? m_args.cameras : "";
    install_scene(m_args.stream ? load_streamed_scene(path, cameras, nullptr, lod_cache_options(m_args)) : load_scene(path, cameras));
    m_load_error.clear();
    return true;
  } catch (const std::exception& e) {
    report_failed_load(error_text(e));
    return false;
  }
}

void ViewerApp::request_open(const std::string& path) {
  m_path_buffer = path;  // the box shows what was asked for, and keeps it when it fails
  if (m_scripted) {  // scripted runs stay deterministic: load in the frame that asks
    open_scene(path);
    return;
  }
  // Parsing a large PLY takes seconds: it runs beside the frame loop, which keeps drawing the
  // current scene; the new one is installed (uploaded) on this thread once it is ready.
  SceneLoader::LoadFunction load;  // the constructor's: the file whole
  if (m_args.stream)
    load = [options = lod_cache_options(m_args)](const std::string& p, LoadProgress& progress) {
      return load_streamed_scene(p, "", &progress, options);
    };
  if (!m_loader.start(path, load)) set_notice("still loading " + m_loader.path() + "; " + path + " ignored");
  m_logged_load_progress = false;
}

void ViewerApp::request_lod_level(int level) {
  const std::string path = m_scene.path, cameras = path == m_args.scene ? m_args.cameras : "";
  std::fprintf(stderr, "flashgs-viewer: loading LOD level %d of %s\n", level, path.c_str());
  if (m_scripted) {
    try {
      install_scene(load_scene(path, cameras, nullptr, level));
    } catch (const std::exception& e) {
      report_failed_load(e.what());
    }
    return;
  }
  const bool started = m_loader.start(path, [cameras, level](const std::string& p, LoadProgress& progress) {
    return load_scene(p, cameras, &progress, level);
  });
  if (!started) set_notice("still loading " + m_loader.path() + "; LOD level " + std::to_string(level) + " ignored");
  m_logged_load_progress = false;
}

void ViewerApp::finish_pending_load() {
  const std::string path = m_loader.path();
  LoadedScene scene;
  std::string error;
  if (!m_loader.take(&scene, &error)) return;
  const bool first = m_first_load_pending;
  m_first_load_pending = false;
  std::fprintf(stderr, "flashgs-viewer: load of %s finished after %.0f ms since start\n", path.c_str(), ms_since_start());
  if (!error.empty()) {
    report_failed_load(error);
    if (first && !m_scene.scene) {  // nothing to show: the generated demo scene instead
      install_scene(generate_demo_scene(30000));
      m_load_error += "; showing a generated demo scene";
      std::fprintf(stderr, "flashgs-viewer: showing a generated demo scene instead\n");
    }
    return;
  }
  try {
    install_scene(std::move(scene));
    m_load_error.clear();
    m_path_buffer = first ? m_args.scene : path;
    if (first) apply_start_options();
    if (!first || !m_args.scene.empty()) remember_recent(first ? m_args.scene : path);
  } catch (const std::exception& e) {
    report_failed_load(path + ": " + error_text(e));
  }
}

namespace {

// The first scene: generated, the argument or the demo file, tiled when --tile asks (on the
// loader thread for interactive runs: it only reads `args`, a copy). Throws flashgs::Error
// naming the option or file; a refused --tile leaves the scene untiled with `refused_option` set.
LoadedScene load_start_scene(const ViewerArgs& args, LoadProgress* progress) {
  LoadedScene scene;
  if (args.generate_demo > 0) {
    const std::string option = "--generate-demo " + std::to_string(args.generate_demo);
    const int demo_sh_degree = 1;  // what make_demo_scene builds
    const std::string problem =
        scene_size_problem(scene_bytes(std::uint64_t(args.generate_demo), scene_bytes_per_gaussian(demo_sh_degree)),
                           system_available_memory());
    try {
      if (!problem.empty()) throw Error(problem);
      scene = generate_demo_scene(static_cast<std::size_t>(args.generate_demo));
    } catch (const std::exception& e) {
      throw Error(option + ": " + error_text(e));
    }
  } else {
    const std::string path = args.scene.empty() ? demo_scene_path() : args.scene;
    try {
      // lod -1: the finest that fits. A streamed set starts from its coarsest level; a named
      // scene file is streamed through the LOD set cached for it (the bundled demo is drawn whole).
      if (args.stream && !args.scene.empty()) scene = load_streamed_scene(path, args.cameras, progress, lod_cache_options(args));
      else scene = load_scene(path, args.cameras, progress, args.stream ? kCoarsestLodLevel : args.lod);
    } catch (const LoadCancelled&) {
      throw;
    } catch (const std::exception& e) {
      if (args.lod < 0) throw;
      throw Error("--lod " + std::to_string(args.lod) + ": " + error_text(e));  // the option that chose it
    }
  }
  if (args.tile > 1) {
    const std::string option = "--tile " + std::to_string(args.tile);
    const std::uint64_t gaussians = std::uint64_t(scene.scene->size()) * std::uint64_t(args.tile);
    const std::string problem =
        scene_size_problem(scene_bytes(gaussians, scene_bytes_per_gaussian(scene.scene->sh_degree)),
                           system_available_memory());
    try {
      if (!problem.empty()) throw Error(problem + " for " + std::to_string(gaussians) + " Gaussians");
      scene = tile_loaded_scene(scene, args.tile);
    } catch (const std::exception& e) {
      scene.refused_option = option + " refused: " + error_text(e);
    }
  }
  return scene;
}

}  // namespace

bool ViewerApp::start_first_scene() {
  if (!m_args.load_gate.empty()) {
    m_loader.set_gate(m_args.load_gate);
    std::fprintf(stderr, "flashgs-viewer: each scene load beside the window waits for %s (--load-gate)\n",
                 m_args.load_gate.c_str());
  }
  if (!m_scripted) {
    // The window and panels come up at once; the scene loads beside them with its progress shown.
    m_first_load_pending = true;
    const std::string shown = m_args.generate_demo > 0 ? "generated demo scene"
                              : m_args.scene.empty()   ? demo_scene_path()
                                                       : m_args.scene;
    m_loader.start(shown, [args = m_args](const std::string&, LoadProgress& progress) {
      return load_start_scene(args, &progress);
    });
    m_path_buffer = m_args.scene;
    return true;
  }
  // Scripted runs load before their first frame: what they time and save does not depend on
  // when a thread finishes.
  try {
    LoadedScene scene = load_start_scene(m_args, nullptr);
    const std::string refused = scene.refused_option;
    install_scene(std::move(scene));
    m_path_buffer = m_args.scene;
    if (!refused.empty()) {  // its numbers would be for another scene
      set_notice(refused);
      return false;
    }
  } catch (const std::exception& e) {
    report_failed_load(error_text(e));
    std::fprintf(stderr, "flashgs-viewer: no scene to run the script on\n");
    return false;
  }
  return apply_start_options();
}

bool ViewerApp::apply_start_options() {
  // Each refusal is one line naming the option; a scripted run stops (its numbers would be
  // for something else), an interactive one goes on without the option.
  if (!m_scene.refused_option.empty()) set_notice(m_scene.refused_option + "; the scene is shown once");
  if (m_settings.forced_width > 0) {
    const std::string problem = frame_size_problem(m_settings.forced_width, m_settings.forced_height,
                                                   m_path->texture_count(), m_max_texture_size, system_available_memory());
    if (!problem.empty()) {
      set_notice("--render-size " + size_text(m_settings.forced_width, m_settings.forced_height) + " refused: " +
                 problem + (m_scripted ? "" : "; rendering at the window size"));
      if (m_scripted) return false;
      m_settings.forced_width = m_settings.forced_height = 0;
    }
  }
  if (m_args.camera >= 0) {
    const int count = static_cast<int>(m_scene.cameras.size());
    if (m_args.camera >= count) {
      set_notice("--camera " + std::to_string(m_args.camera) + ": " +
                 (count == 0 ? std::string("the scene has no cameras")
                             : "the scene has " + std::to_string(count) + " cameras (0.." + std::to_string(count - 1) + ")"));
      if (m_scripted) return false;
    } else {
      snap_to_camera(m_args.camera);
    }
  }
  if (m_args.fov > 0) m_settings.fov_x_degrees = m_args.fov;
  return true;
}

}  // namespace flashgs::viewer
