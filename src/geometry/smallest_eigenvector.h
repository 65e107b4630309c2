#pragma once

namespace ssta {
namespace internal {

/// Eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3x3 matrix
/// [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]] (a covariance) scaled to trace 1. Writes it NOT
/// normalised (length in [~min_rank2^5, 1]; callers normalise once, together with orienting
/// it), sign arbitrary; or (0, 0, 0) when lambda2 * lambda3 <= min_rank2 (rank <= 1: the points
/// lie on a line or are one point).
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
/// min_rank2 = 1e-6 keeps the adjugate's cancellation error small and the result far above the
/// smallest normal float.
template <typename T>
inline void SmallestEigenvectorOfUnitTrace(T xx, T xy, T xz, T yy, T yz, T zz, T min_rank2, T* nx,
                                           T* ny, T* nz) {
  const T a00 = yy * zz - yz * yz;
  const T a11 = xx * zz - xz * xz;
  const T a22 = xx * yy - xy * xy;
  const T a01 = xz * yz - xy * zz;
  const T a02 = xy * yz - xz * yy;
  const T a12 = xy * xz - xx * yz;
  // Column of the largest diagonal entry. |a_ij| <= sqrt(a_ii a_jj) <= best for the PSD
  // adjugate, so scaling by 1/best keeps |v| <= 1; adj's eigenvalues are <= 1/4 at trace 1.
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
    const T x1 = a00 * x + a01 * y + a02 * z;
    const T y1 = a01 * x + a11 * y + a12 * z;
    const T z1 = a02 * x + a12 * y + a22 * z;
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
