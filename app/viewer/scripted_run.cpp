// A scripted run's frame counting and report: frame 0 (setup) and path warm-up frames are not timed.
#include "scripted_run.h"

#include <algorithm>
#include <cstdio>

#include "stats_history.h"

namespace flashgs::viewer {

ScriptedRun::ScriptedRun(const ScriptedRunPlan& plan) : m_plan(plan) {
  if (m_plan.path && m_plan.frames <= 0) m_plan.frames = 120;
  if (!m_plan.keys.empty()) m_script = KeyScript::parse(m_plan.keys);
}

ScriptFrame ScriptedRun::next_input() { return m_script.done() ? ScriptFrame{} : m_script.next(kFrameSeconds); }

double ScriptedRun::path_time() const {
  const int timed = std::max(0, m_frame - m_plan.warmup);
  return double(timed) / std::max(1, m_plan.frames);
}

void ScriptedRun::frame_presented(const FrameTimes& t) {
  if (m_frame >= (m_plan.path ? std::max(1, m_plan.warmup) : 1)) {
    m_frame_ms.push_back(t.frame_ms);
    m_sum.before_render_ms += t.before_render_ms;
    m_sum.render_call_ms += t.render_call_ms;
    m_sum.draw_ms += t.draw_ms;
    m_sum.swap_ms += t.swap_ms;
  }
  ++m_frame;
}

bool ScriptedRun::done() const {
  const int needed = m_plan.path ? m_plan.frames + m_plan.warmup : std::max(1, m_plan.frames);
  return m_frame >= needed && m_script.done();
}

std::string ScriptedRun::frames_report(int width, int height, const std::string& path_name) const {
  if (m_frame_ms.empty()) return "";
  const FrameTimeSummary s = summarize_frame_times(m_frame_ms);
  char text[512];
  std::snprintf(text, sizeof text,
                "viewer frames: %zu at %dx%d on %s | mean %.3f ms, median %.3f ms, p95 %.3f ms, min %.3f ms, max %.3f ms | %.1f FPS",
                s.frames, width, height, path_name.c_str(), s.mean_ms, s.median_ms, s.p95_ms, s.min_ms, s.max_ms, s.fps);
  return text;
}

std::string ScriptedRun::split_report() const {
  if (m_frame_ms.empty()) return "";
  const double n = static_cast<double>(m_frame_ms.size());
  char text[256];
  std::snprintf(text, sizeof text, "viewer split (mean wall ms): events + panels %.3f, render call %.3f, draw %.3f, swap %.3f",
                m_sum.before_render_ms / n, m_sum.render_call_ms / n, m_sum.draw_ms / n, m_sum.swap_ms / n);
  return text;
}

}  // namespace flashgs::viewer
