// Refinement 4 of label_refinements.h: thin vertical faces from the disparity
// (RefineByDisparityFaces and its two steps).

#include "ssta/analysis/label_refinements.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {

constexpr float kMaxRowJumpPx = 0.5f;  // a larger step between rows is a depth edge, not a face

/// Per column of the disparity, sums over a window of rows slid down the image: s1 = sum of d
/// over the window, s2 = sum of j * d (j the row offset from the centre), and `bad`, how many
/// rows of the window are invalid or jump from the row above by more than kMaxRowJumpPx (a jump
/// into the window's first row does not count). Invalid disparities (NaN, <= 0) add 0 to the
/// sums and 1 to `bad`.
struct ColumnWindowSums {
  std::vector<double> s1, s2;
  std::vector<int> bad;

  /// All columns empty, for an image `width` px wide (the vectors keep their capacity).
  void Reset(int width) {
    s1.assign(width, 0.0);
    s2.assign(width, 0.0);
    bad.assign(width, 0);
  }

  /// Adds image row `row` at offset `j` from the window's centre; its jump from the row above
  /// counts (row 0, the first row of the first window, has none).
  void AddRow(const ImageF& disparity, int row, double j) {
    const int w = disparity.width();
    const float* d = disparity.row(row);
    const float* above = disparity.row(row > 0 ? row - 1 : row);
    for (int u = 0; u < w; ++u) {
      const bool ok = d[u] > 0.0f;
      const double x = ok ? static_cast<double>(d[u]) : 0.0;
      s1[u] += x;
      s2[u] += j * x;
      bad[u] += (!ok) + (std::abs(d[u] - above[u]) > kMaxRowJumpPx);
    }
  }

  /// Slides the window centred on row v (half height k) one row down: row v - k leaves, row
  /// v + k + 1 enters; every remaining row's offset j falls by one, so s2 loses the new s1 once.
  void SlideDown(const ImageF& disparity, int v, int k) {
    const int w = disparity.width();
    const float* leave = disparity.row(v - k);
    const float* leave_next = disparity.row(v - k + 1);
    const float* enter = disparity.row(v + k + 1);
    const float* enter_above = disparity.row(v + k);
    for (int u = 0; u < w; ++u) {
      const bool ok_out = leave[u] > 0.0f, ok_in = enter[u] > 0.0f;
      const double out_d = ok_out ? static_cast<double>(leave[u]) : 0.0;
      const double in_d = ok_in ? static_cast<double>(enter[u]) : 0.0;
      s1[u] += in_d - out_d;
      s2[u] += k * out_d + (k + 1) * in_d - s1[u];
      bad[u] += (!ok_in) + (std::abs(enter[u] - enter_above[u]) > kMaxRowJumpPx) - (!ok_out) -
                (std::abs(leave_next[u] - leave[u]) > kMaxRowJumpPx);
    }
  }
};

/// The face test of one frame. Per pixel, with q = (dd/dv) / d from the fit and y = v - cv, the
/// tangent along the column is t = (-(u - cu) q, 1 - y q, -f q): its rise along up is
/// up_y - q A(u) with A(u) = (u - cu) up_x + y up_y + f up_z, and
/// |t|^2 = q^2 ((u - cu)^2 + y^2 + f^2) - 2 y q + 1.
struct FaceTest {
  Eigen::Vector3d up;  // unit up vector, camera frame
  double f, cu, cv;    // pinhole [px]
  int k;               // the window spans rows v - k .. v + k
  int r;               // a pixel pools the fits of columns u - r .. u + r of its run
  double n;            // rows in the window
  double sum_jj;       // sum of j^2 over the window's row offsets j
  double jump_sum;     // kMaxRowJumpPx on s1 (= n * mean) [px]
  double sin2_min;     // sin^2 of face_min_slope_deg: steeper is a face
  double sin2_seed;    // sin^2 of the seed slope: steeper seeds the growth along the column
  bool grow;           // seeds are kept (face_grow_tolerance_px > 0)
};

/// The face test for pinhole f, cu, cv [px] and the up vector in the camera frame.
FaceTest MakeFaceTest(double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                      const LabelRefinementOptions& options) {
  // Pixels rising steeper than kGrowSeedSlopeDeg are surely on a face: their window's mean
  // disparity (the face's, constant along the column) is kept to grow the face along the column.
  constexpr double kGrowSeedSlopeDeg = 70.0;
  FaceTest test;
  test.up = up_camera.normalized();
  test.f = f;
  test.cu = cu;
  test.cv = cv;
  test.k = options.face_window_px / 2;
  test.r = options.face_columns_px / 2;
  test.n = 2 * test.k + 1;
  test.sum_jj = 0.0;
  for (int j = -test.k; j <= test.k; ++j) test.sum_jj += static_cast<double>(j) * j;
  test.jump_sum = kMaxRowJumpPx * (2 * test.k + 1);
  const double sin_min = std::sin(DegToRad(options.face_min_slope_deg));
  test.sin2_min = sin_min * sin_min;
  const double sin_seed = std::sin(DegToRad(kGrowSeedSlopeDeg));
  test.sin2_seed = sin_seed * sin_seed;
  test.grow = options.face_grow_tolerance_px > 0;
  return test;
}

/// Per row, prefix sums over the columns of s1 and s2, and the first and last column of each
/// run of clean columns whose window means step by at most kMaxRowJumpPx from one to the next
/// (one surface): each pixel pools the fits of up to face_columns_px columns of its run.
struct RowRuns {
  std::vector<double> p1, p2;  // p[u] = sum over columns < u
  std::vector<int> run_first, run_last;

  /// Sized for an image `width` px wide (the vectors keep their capacity).
  void Reset(int width) {
    p1.assign(width + 1, 0.0);
    p2.assign(width + 1, 0.0);
    run_first.assign(width, 0);
    run_last.assign(width, 0);
  }

  /// The prefix sums and runs of the current window sums; columns join when their s1 differ by
  /// at most `jump_sum`.
  void Build(const ColumnWindowSums& sums, double jump_sum) {
    const std::vector<double>& s1 = sums.s1;
    const std::vector<double>& s2 = sums.s2;
    const std::vector<int>& bad = sums.bad;
    const int w = static_cast<int>(s1.size());
    auto joins = [&](int a, int b) { return bad[a] == 0 && bad[b] == 0 && std::abs(s1[a] - s1[b]) <= jump_sum; };
    for (int u = 0; u < w; ++u) {
      p1[u + 1] = p1[u] + s1[u];
      p2[u + 1] = p2[u] + s2[u];
      run_first[u] = u > 0 && joins(u - 1, u) ? run_first[u - 1] : u;
    }
    for (int u = w - 1; u >= 0; --u) run_last[u] = u + 1 < w && joins(u, u + 1) ? run_last[u + 1] : u;
  }
};

/// Marks row v of faces->marks from the window centred on it: 1 where the pooled fit rises
/// steeper than face_min_slope_deg, 2 (and a seed with the window's mean disparity [px]) where
/// it also rises steeper than the seed slope.
void MarkFaceRow(const ColumnWindowSums& sums, const RowRuns& runs, const FaceTest& test, int v,
                 DisparityFaces* faces) {
  const std::vector<double>& s1 = sums.s1;
  const std::vector<int>& bad = sums.bad;
  const std::vector<double>& p1 = runs.p1;
  const std::vector<double>& p2 = runs.p2;
  const Eigen::Vector3d up = test.up;
  const double f = test.f, cu = test.cu, n = test.n, sum_jj = test.sum_jj;
  const double sin2_min = test.sin2_min, sin2_seed = test.sin2_seed;
  const int w = faces->marks.width(), r = test.r;
  const bool grow = test.grow;
  std::vector<std::pair<int, float>>& seeds = faces->seeds;
  std::uint8_t* out = faces->marks.row(v);
  const double y = v - test.cv;
  const double a0 = -cu * up.x() + y * up.y() + f * up.z(), b0 = y * y + f * f;
  for (int u = 0; u < w; ++u) {
    if (bad[u] != 0) continue;
    const int lo = std::max(u - r, runs.run_first[u]), hi = std::min(u + r, runs.run_last[u]) + 1;
    // The pooled slope over the mean disparity: q = mean(d') / mean(d) of those columns.
    const double q = (p2[hi] - p2[lo]) * n / (sum_jj * (p1[hi] - p1[lo]));
    const double du = u - cu;
    const double rise = up.y() - q * (a0 + u * up.x());
    const double norm2 = q * q * (du * du + b0) - 2.0 * y * q + 1.0;
    if (rise * rise > sin2_min * norm2) {
      out[u] = 1;
      if (grow && rise * rise > sin2_seed * norm2) {
        out[u] = 2;
        seeds.push_back({v * w + u, static_cast<float>(s1[u] / n)});
      }
    }
  }
}

}  // namespace

void RefineByDisparityFaces(const ImageF& disparity, double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                            const LabelRefinementOptions& options, ImageU8* labels) {
  if (options.face_window_px == 0) return;
  SSTA_CHECK(disparity.width() == labels->width() && disparity.height() == labels->height(),
             "RefineByDisparityFaces: disparity and labels differ in size");
  thread_local DisparityFaces faces;
  FindDisparityFaces(disparity, f, cu, cv, up_camera, options, &faces);
  ApplyDisparityFaces(faces, disparity, options, labels);
}

void FindDisparityFaces(const ImageF& disparity, double f, double cu, double cv, const Eigen::Vector3d& up_camera,
                        const LabelRefinementOptions& options, DisparityFaces* faces) {
  faces->seeds.clear();
  if (faces->marks.width() != disparity.width() || faces->marks.height() != disparity.height()) {
    faces->marks = ImageU8(disparity.width(), disparity.height(), 0);
  } else {
    faces->marks.Fill(0);
  }
  if (options.face_window_px == 0) return;
  SSTA_CHECK(options.face_window_px >= 3 && options.face_window_px % 2 == 1,
             "RefineByDisparityFaces: face_window_px must be odd and at least 3");
  SSTA_CHECK(options.face_columns_px >= 1 && options.face_columns_px % 2 == 1,
             "RefineByDisparityFaces: face_columns_px must be odd and at least 1");
  SSTA_CHECK(f > 0, "RefineByDisparityFaces: focal length must be positive");
  const int h = disparity.height(), k = options.face_window_px / 2;
  if (h < 2 * k + 1) return;
  const FaceTest test = MakeFaceTest(f, cu, cv, up_camera, options);
  // Kept per thread between frames.
  thread_local ColumnWindowSums sums;
  thread_local RowRuns runs;
  sums.Reset(disparity.width());
  runs.Reset(disparity.width());
  for (int j = -k; j <= k; ++j) sums.AddRow(disparity, k + j, j);
  for (int v = k;; ++v) {
    runs.Build(sums, test.jump_sum);
    MarkFaceRow(sums, runs, test, v, faces);
    if (v + k + 1 >= h) break;
    sums.SlideDown(disparity, v, k);
  }
}

void ApplyDisparityFaces(const DisparityFaces& faces, const ImageF& disparity, const LabelRefinementOptions& options,
                         ImageU8* labels) {
  if (options.face_window_px == 0) return;
  SSTA_CHECK(faces.marks.width() == labels->width() && faces.marks.height() == labels->height() &&
                 disparity.width() == labels->width() && disparity.height() == labels->height(),
             "ApplyDisparityFaces: faces, disparity and labels differ in size");
  const int w = labels->width(), h = labels->height(), k = options.face_window_px / 2;
  // Traversable, semi-traversable and undecided pixels on a face become non-traversable; those
  // steep enough seed the growth, in raster order (the order of faces.seeds).
  thread_local std::vector<std::pair<int, float>> seeds;
  seeds.clear();
  std::size_t next_seed = 0;
  for (std::size_t i = 0; i < labels->size(); ++i) {
    const std::uint8_t mark = faces.marks[i];
    if (mark == 0) continue;
    std::uint8_t& c = (*labels)[i];
    const bool drivable = c == 1 || c == 2 || c == 4;
    if (drivable) c = static_cast<std::uint8_t>(TravClass::kNonTraversable);
    if (mark == 2) {
      if (drivable) seeds.push_back(faces.seeds[next_seed]);
      ++next_seed;
    }
  }
  // A face a few rows tall is flagged only where the window is centred on it (its rows near the
  // ground and the top straddle them): the rows within the window's reach whose disparity is
  // the face's, within face_grow_tolerance_px, join it.
  for (const auto& [index, face_d] : seeds) {
    const int v = index / w, u = index % w;
    for (int vv = std::max(0, v - k); vv <= std::min(h - 1, v + k); ++vv) {
      std::uint8_t& c = (*labels)(vv, u);
      if (c != 1 && c != 2 && c != 4) continue;
      const float d = disparity(vv, u);
      if (d > 0.0f && std::abs(d - face_d) <= options.face_grow_tolerance_px) {
        c = static_cast<std::uint8_t>(TravClass::kNonTraversable);
      }
    }
  }
}

void JudgeFacesByHeight(const Image3f& cloud, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                        const ImageU8& before, ImageU8* labels) {
  SSTA_CHECK(labels != nullptr && before.width() == labels->width() && before.height() == labels->height() &&
                 cloud.width() == labels->width() && cloud.height() == labels->height(),
             "JudgeFacesByHeight: cloud, labels before and labels after differ in size");
  constexpr auto kNon = static_cast<std::uint8_t>(TravClass::kNonTraversable);
  constexpr auto kSemi = static_cast<std::uint8_t>(TravClass::kSemiTraversable);
  const Eigen::Vector3f up = up_camera.normalized().cast<float>();
  const int w = labels->width(), h = labels->height();
  // A run is the column's consecutive non-traversable pixels, whichever rule made them: a face
  // continues the obstacle another rule found above or below it.
  for (int u = 0; u < w; ++u) {
    for (int v = 0; v < h;) {
      if ((*labels)(v, u) != kNon) {
        ++v;
        continue;
      }
      const int first = v;
      float lo = std::numeric_limits<float>::infinity(), hi = -lo;
      int points = 0;
      bool made = false;
      for (; v < h && (*labels)(v, u) == kNon; ++v) {
        made = made || before(v, u) != kNon;
        const Eigen::Vector3f& p = cloud(v, u);
        if (!p.allFinite()) continue;
        const float z = up.dot(p);
        lo = std::min(lo, z);
        hi = std::max(hi, z);
        ++points;
      }
      const double height = points >= 2 ? static_cast<double>(hi - lo) : 0.0;
      if (!made || height >= vehicle.max_step_m) continue;
      for (int r = first; r < v; ++r) {
        const std::uint8_t was = before(r, u);
        if (was == kNon) continue;
        (*labels)(r, u) = height >= vehicle.semi_step_m ? kSemi : was;
      }
    }
  }
}

}  // namespace ssta
