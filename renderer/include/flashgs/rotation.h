// Rotations as row-major 3x3 matrices and unit quaternions (w, x, y, z), in double.
#pragma once

namespace flashgs {

// The unit quaternion of a rotation matrix (determinant +1).
void quaternion_from_matrix(const double m[9], double q[4]);
// The rotation matrix of a quaternion (normalised first; a zero quaternion is the identity).
void matrix_from_quaternion(const double q[4], double m[9]);
// a * b: the rotation b, then a.
void multiply_quaternions(const double a[4], const double b[4], double out[4]);

}  // namespace flashgs
