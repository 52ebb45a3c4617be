// The constants of the 3DGS image model, written once in double: gaussian_math.h rounds them
// to float for the backends (each rounds to the float literal it replaced), the fp64
// reference uses them as they are.
#pragma once

namespace flashgs {
namespace model {

// Real spherical harmonics basis, degree 0..3, of the 3DGS colour model (index = basis
// function, signs included).
constexpr double kShC0 = 0.28209479177387814;
constexpr double kShC1 = 0.4886025119029199;
constexpr double kShC2_0 = 1.0925484305920792;
constexpr double kShC2_1 = -1.0925484305920792;
constexpr double kShC2_2 = 0.31539156525252005;
constexpr double kShC2_3 = -1.0925484305920792;
constexpr double kShC2_4 = 0.5462742152960396;
constexpr double kShC3_0 = -0.5900435899266435;
constexpr double kShC3_1 = 2.890611442640554;
constexpr double kShC3_2 = -0.4570457994644658;
constexpr double kShC3_3 = 0.3731763325901154;
constexpr double kShC3_4 = -0.4570457994644658;
constexpr double kShC3_5 = 1.445305721320277;
constexpr double kShC3_6 = -0.5900435899266435;

// The projection's Jacobian is taken at the view direction clamped to the frustum widened by
// this fraction of the image size on each side: 3DGS's limit 1.3 tan(fov / 2) = (1 + 2 * 0.15)
// tan(fov / 2).
constexpr double kFrustumMargin = 0.15;

}  // namespace model
}  // namespace flashgs
