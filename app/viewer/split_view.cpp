// Difference image magnification and the divider's drag.
#include "split_view.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace flashgs::viewer {

Image difference_image(const Image& a, const Image& b, float* factor) {
  Image out;
  *factor = 1.0f;
  if (a.width != b.width || a.height != b.height || a.rgb.size() != b.rgb.size()) return out;
  out.resize(a.width, a.height);
  std::vector<float> nonzero;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    const float d = std::abs(a.rgb[i] - b.rgb[i]);
    out.rgb[i] = std::isfinite(d) ? d : 1.0f;
    if (out.rgb[i] > 0.0f) nonzero.push_back(out.rgb[i]);
  }
  // Scaled for the bulk of the errors, not the single worst one (which would leave the rest
  // black): the 99th percentile of the non-zero errors reaches half of white; larger ones clip.
  float typical = 0.0f;
  if (!nonzero.empty()) {
    const std::size_t k = std::min(nonzero.size() - 1, nonzero.size() * 99 / 100);
    std::nth_element(nonzero.begin(), nonzero.begin() + std::ptrdiff_t(k), nonzero.end());
    typical = nonzero[k];
  }
  float f = 1.0f;
  while (typical > 0.0f && typical * f < 0.5f && f < 1024.0f) f *= 2.0f;
  for (float& v : out.rgb) v = std::min(1.0f, v * f);
  *factor = f;
  return out;
}

void SplitDivider::set_fraction(float f) { m_fraction = std::isfinite(f) ? std::clamp(f, 0.02f, 0.98f) : 0.5f; }

bool SplitDivider::grabs(float x, float width) const {
  return width > 0.0f && std::abs(x - m_fraction * width) <= 8.0f;
}

void SplitDivider::press(float x, float width) {
  m_dragging = grabs(x, width);
  if (m_dragging) drag_to(x, width);
}

void SplitDivider::drag_to(float x, float width) {
  if (m_dragging && width > 0.0f) set_fraction(x / width);
}

}  // namespace flashgs::viewer
