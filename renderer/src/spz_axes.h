// The axis change between SPZ's right-up-back axes and 3DGS PLY's right-down-forward ones, in
// one place for the SPZ reader and writer.
#pragma once

#include "flashgs/scene_formats.h"

namespace flashgs {

// y and z change sign: a 180-degree turn about x, so the quaternion's y and z change sign too,
// and each SH coefficient by the parity of its basis function in y and z (bands 1-3, m = -l..l).
inline constexpr float kSpzAxisFlip[3] = {1, -1, -1};
inline constexpr float kSpzShFlip[15] = {-1, -1, 1,                 // y, z, x
                                         -1, 1, 1, -1, 1,           // xy, yz, 3z2-1, xz, x2-y2
                                         -1, 1, -1, -1, 1, -1, 1};  // y(3x2-y2), xyz, y(5z2-1), z(5z2-3), x(5z2-1), z(x2-y2), x(x2-3y2)

// The sign position (or quaternion vector) component `k` takes between the two axes.
inline float spz_axis_sign(SpzAxes axes, int k) { return axes == SpzAxes::niantic ? kSpzAxisFlip[k] : 1.0f; }
// The sign SH coefficient `coefficient` (0 = the first of band 1) takes.
inline float spz_sh_sign(SpzAxes axes, int coefficient) {
  return axes == SpzAxes::niantic ? kSpzShFlip[coefficient] : 1.0f;
}

}  // namespace flashgs
