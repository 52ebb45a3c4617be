// The visual comparison's layout: split view (left | right with a draggable divider) or the magnified difference image, without GL.
#pragma once

#include "flashgs/image.h"

namespace flashgs::viewer {

// |a - b| per channel times a power of two chosen so that the 99th percentile of the non-zero
// errors is at least half as bright as white (x1 when already that large; up to x1024; larger
// errors clip to white). `factor` gets the magnification; identical images give black with
// factor 1. Sizes must match (else empty).
Image difference_image(const Image& a, const Image& b, float* factor);

// The divider's place, a fraction of the window width from the left, kept in [0.02, 0.98].
class SplitDivider {
 public:
  float fraction() const { return m_fraction; }
  void set_fraction(float f);
  // Whether a press at window x (points) of a window `width` points wide grabs the divider
  // (within 8 points of it).
  bool grabs(float x, float width) const;
  // Starts / continues / ends a drag: the divider follows the pointer while dragging.
  void press(float x, float width);
  void drag_to(float x, float width);
  void release() { m_dragging = false; }
  bool dragging() const { return m_dragging; }

 private:
  float m_fraction = 0.5f;
  bool m_dragging = false;
};

}  // namespace flashgs::viewer
