#pragma once

#include <cmath>

#include <Eigen/Core>

namespace ssta {
namespace internal {

/// Eigenvector of the smallest eigenvalue of the symmetric positive semi-definite 3x3 matrix
/// [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]] (a covariance), NOT normalised (callers normalise
/// once, together with orienting it), sign arbitrary, length >= 1e-50.
///
/// Why not Eigen::SelfAdjointEigenSolver::computeDirect: it needs acos/cos/sin per call, which
/// at 300k pixels per frame costs more than the rest of the normal estimation. Instead: the
/// adjugate adj(C) = sum_k (product of the other two eigenvalues) e_k e_k^T has the same
/// eigenvectors, and its dominant one is the smallest of C, with ratio lambda1 / lambda2 to the
/// next. Start from adj(C)'s column with the largest diagonal (error ~ lambda1/lambda2) and
/// refine by power iteration (each step multiplies the error by lambda1 / lambda2): exact for
/// a plane (lambda1 = 0) and < 0.1 degree off for lambda1 / lambda2 <= 0.2 (tested).
/// Returns false, leaving *normal alone, when C has rank <= 1 (points on a line or one point).
inline bool SmallestEigenvector(double xx, double xy, double xz, double yy, double yz, double zz,
                                Eigen::Vector3d* normal) {
  const double trace = xx + yy + zz;
  if (!(trace > 0.0)) return false;
  const double s = 1.0 / trace;  // scale to trace 1 so the adjugate's entries stay near 1
  xx *= s; xy *= s; xz *= s; yy *= s; yz *= s; zz *= s;
  const double a00 = yy * zz - yz * yz;
  const double a11 = xx * zz - xz * xz;
  const double a22 = xx * yy - xy * xy;
  const double a01 = xz * yz - xy * zz;
  const double a02 = xy * yz - xz * yy;
  const double a12 = xy * xz - xx * yz;
  Eigen::Vector3d v;
  double best;
  if (a00 >= a11 && a00 >= a22) {
    v = {a00, a01, a02};
    best = a00;
  } else if (a11 >= a22) {
    v = {a01, a11, a12};
    best = a11;
  } else {
    v = {a02, a12, a22};
    best = a22;
  }
  // lambda2 * lambda3 relative to trace^2: below this the points are (nearly) collinear.
  constexpr double kMinRank2 = 1e-10;
  if (!(best > kMinRank2)) return false;
  // No normalisation inside the loop (sqrt and division dominate the cost otherwise): with
  // trace 1 and lambda2 * lambda3 > kMinRank2, the length shrinks by at most 1e-10 per step.
  constexpr int kPowerIterations = 4;
  for (int i = 0; i < kPowerIterations; ++i) {
    v = Eigen::Vector3d(a00 * v.x() + a01 * v.y() + a02 * v.z(),
                        a01 * v.x() + a11 * v.y() + a12 * v.z(),
                        a02 * v.x() + a12 * v.y() + a22 * v.z());
  }
  *normal = v;
  return true;
}

}  // namespace internal
}  // namespace ssta
