// ScriptedRun: the unattended run frame by frame (the key script's input, the camera path's time, which frames are timed, when --then-open happens, when the run is done) and the report it prints.
#pragma once

#include <string>
#include <vector>

#include "key_script.h"

namespace flashgs::viewer {

struct ScriptedRunPlan {
  std::string keys;        // --keys; empty: none
  bool path = false;       // --path: the camera path over the timed frames
  int frames = 0;          // --frames (a path run without it: 120)
  int warmup = 3;          // --warmup: path frames before timing starts
  bool then_open = false;  // --then-open: a scene to open after the first frame
};

// Where one frame's wall time went (milliseconds).
struct FrameTimes {
  double frame_ms = 0;        // swap to swap
  double before_render_ms = 0;  // events and panels
  double render_call_ms = 0;  // the render (queued on a GPU, or rendered and waited for)
  double draw_ms = 0;         // image and panels drawn
  double swap_ms = 0;
};

class ScriptedRun {
 public:
  static constexpr float kFrameSeconds = 1.0f / 60.0f;  // simulated time per frame: runs are repeatable

  // Throws flashgs::Error on a malformed key script, naming the bad step.
  explicit ScriptedRun(const ScriptedRunPlan& plan);

  // Whether the key script still has input (after it, the window's own input counts).
  bool has_input() const { return !m_script.done(); }
  // The scripted input of the next frame (none once the key script is done); advances it.
  ScriptFrame next_input();
  // Path runs: where on the camera path (0..1) the current frame's view is.
  double path_time() const;

  // Records a presented frame.
  void frame_presented(const FrameTimes& times);
  int frames_presented() const { return m_frame; }
  // After the frame just recorded: open the --then-open scene now (after the first frame).
  bool open_then_now() const { return m_plan.then_open && m_frame == 1; }
  // After the frame just recorded: every frame is done and the key script too.
  bool done() const;

  // The report lines (empty when no frame was timed): frame-time summary, wall-time split.
  bool timed_any() const { return !m_frame_ms.empty(); }
  std::string frames_report(int width, int height, const std::string& path_name) const;
  std::string split_report() const;

 private:
  ScriptedRunPlan m_plan;
  KeyScript m_script;
  int m_frame = 0;
  std::vector<double> m_frame_ms;
  FrameTimes m_sum;  // over the timed frames
};

}  // namespace flashgs::viewer
