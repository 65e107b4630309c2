#pragma once

#include <cmath>

namespace ssta {
namespace internal {

/// Eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3x3 matrix
/// [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]] (a covariance) scaled to trace 1. Writes it NOT
/// normalised (length about 1 to 150; callers normalise once, together with orienting it), sign
/// arbitrary; or (0, 0, 0) when lambda2 * lambda3 <= min_rank2 (rank <= 1: the points lie on a
/// line or are one point).
///
/// Why not Eigen::SelfAdjointEigenSolver::computeDirect: it needs acos/cos/sin and branches per
/// call, which at 300k pixels per frame costs more than the rest of the normal estimation.
/// Instead: the adjugate adj(C) = sum_k (product of the other two eigenvalues) e_k e_k^T has the
/// same eigenvectors, and its dominant one is C's smallest, with ratio lambda1 / lambda2 to the
/// next. Start from adj(C)'s column with the largest diagonal (error ~ lambda1 / lambda2) and
/// refine by 4 power iterations (each multiplies the error by lambda1 / lambda2): exact for a
/// plane (lambda1 = 0) and < 0.1 degree off for lambda1 / lambda2 <= 0.2 (tested against Eigen).
///
/// Branch-free (selects only), so a loop over a row vectorises (float: 4 pixels per SSE
/// instruction; GCC needs -fno-trapping-math to turn the selects into blends). In float,
/// min_rank2 = 1e-6 keeps the adjugate's cancellation error small.
template <typename T>
inline void SmallestEigenvectorOfUnitTrace(T xx, T xy, T xz, T yy, T yz, T zz, T min_rank2, T* nx,
                                           T* ny, T* nz) {
  // Entries below 1e-12 (relative to trace^2 = 1) are rounding noise; flushing them, and
  // rescaling by 1/best in every iteration, keeps the vanishing components of exact planes
  // (lambda1 = 0) above denormal floats, which cost ~10% of the frame time on such data.
  auto flush = [](T value, T tiny) { return std::abs(value) < tiny ? T(0) : value; };
  constexpr T kTinyEntry = T(1e-12);
  const T a00 = flush(yy * zz - yz * yz, kTinyEntry);
  const T a11 = flush(xx * zz - xz * xz, kTinyEntry);
  const T a22 = flush(xx * yy - xy * xy, kTinyEntry);
  const T a01 = flush(xz * yz - xy * zz, kTinyEntry);
  const T a02 = flush(xy * yz - xz * yy, kTinyEntry);
  const T a12 = flush(xy * xz - xx * yz, kTinyEntry);
  // Column of the largest diagonal entry. |a_ij| <= sqrt(a_ii a_jj) <= best for the PSD
  // adjugate, so scaling by 1/best keeps |v| <= 1; each iteration rescales by 1/best too, which
  // keeps the dominant component within [1, 81] (best >= lambda2 lambda3 / 3).
  const T m12 = a11 >= a22 ? a11 : a22;
  const T best = a00 >= m12 ? a00 : m12;
  T x = a00 >= m12 ? a00 : (a11 >= a22 ? a01 : a02);
  T y = a00 >= m12 ? a01 : (a11 >= a22 ? a11 : a12);
  T z = a00 >= m12 ? a02 : (a11 >= a22 ? a12 : a22);
  const T keep = best > min_rank2 ? T(1) : T(0);
  const T scale = keep / (best > min_rank2 ? best : T(1));
  x *= scale;
  y *= scale;
  z *= scale;
  for (int i = 0; i < 4; ++i) {
    const T x1 = (a00 * x + a01 * y + a02 * z) * scale;
    const T y1 = (a01 * x + a11 * y + a12 * z) * scale;
    const T z1 = (a02 * x + a12 * y + a22 * z) * scale;
    x = x1;
    y = y1;
    z = z1;
  }
  *nx = x;
  *ny = y;
  *nz = z;
}

}  // namespace internal
}  // namespace ssta
