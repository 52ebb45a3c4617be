// Parsing and playback of scripted navigation input.
#include "key_script.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "flashgs/error.h"

namespace flashgs::viewer {
namespace {

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, sep)) parts.push_back(part);
  return parts;
}

bool parse_float(const std::string& text, float* out) {
  char* end = nullptr;
  const float v = std::strtof(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

}  // namespace

KeyScript KeyScript::parse(const std::string& text) {
  KeyScript script;
  for (std::string token : split(text, ',')) {
    token.erase(std::remove_if(token.begin(), token.end(), [](unsigned char c) { return std::isspace(c); }),
                token.end());
    if (token.empty()) continue;
    std::transform(token.begin(), token.end(), token.begin(), [](unsigned char c) { return std::toupper(c); });
    const auto fields = split(token, ':');
    const std::string bad = "--keys step \"" + token + "\": ";
    Step step;
    if (fields[0] == "RESIZE") {
      float w = 0, h = 0;
      if (fields.size() != 3 || !parse_float(fields[1], &w) || !parse_float(fields[2], &h) || w < 1 || h < 1 ||
          w > 16384 || h > 16384)
        throw Error(bad + "expected RESIZE:width:height (window points, 1..16384)");
      step.resize_width = static_cast<int>(w);
      step.resize_height = static_cast<int>(h);
      step.is_drag = true;  // applied in one frame, like a drag
    } else if (fields[0] == "MOUSE") {
      if (fields.size() != 3 || !parse_float(fields[1], &step.held.look_dx) ||
          !parse_float(fields[2], &step.held.look_dy))
        throw Error(bad + "expected MOUSE:dx:dy (window points of a right-button drag)");
      step.is_drag = true;
    } else {
      if (fields.size() != 2 || !parse_float(fields[1], &step.seconds) || step.seconds < 0)
        throw Error(bad + "expected KEYS:seconds, e.g. W:0.5 or W+SHIFT:0.2");
      if (fields[0] != "WAIT")
        for (const std::string& key : split(fields[0], '+')) {
          if (key == "W") step.held.forward = true;
          else if (key == "S") step.held.back = true;
          else if (key == "A") step.held.left = true;
          else if (key == "D") step.held.right = true;
          else if (key == "Q") step.held.down = true;
          else if (key == "E") step.held.up = true;
          else if (key == "SHIFT") step.held.fast = true;
          else throw Error(bad + "unknown key \"" + key + "\" (W A S D Q E SHIFT, WAIT, MOUSE, RESIZE)");
        }
    }
    script.m_steps.push_back(step);
  }
  return script;
}

ScriptFrame KeyScript::next(float dt) {
  ScriptFrame frame;
  if (done()) return frame;
  Step& step = m_steps[m_step];
  frame.nav = step.held;
  if (step.is_drag) {
    frame.resize_width = step.resize_width;
    frame.resize_height = step.resize_height;
    ++m_step;
    return frame;
  }
  m_elapsed += dt;
  // The last frame of a step is shortened by the caller's dt only through the step boundary:
  // total simulated key time equals the requested seconds to within one frame.
  if (m_elapsed + 1e-6f >= step.seconds) {
    ++m_step;
    m_elapsed = 0;
  }
  return frame;
}

}  // namespace flashgs::viewer
