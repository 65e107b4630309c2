// Refinement 1 of label_refinements.h: per-pixel slopes (RefineByPixelSlope and its two steps).

#include "ssta/analysis/label_refinements.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {

// The column step takes __restrict pointers so that the compiler vectorises it; GCC drops
// __restrict when such a function is inlined, so it stays out of line.
#if defined(__GNUC__)
#define SSTA_ANALYSIS_NOINLINE __attribute__((noinline))
#else
#define SSTA_ANALYSIS_NOINLINE
#endif

/// Sliding-window sum along one line of `n` samples, restricted to runs of equal segment id:
/// out[i] = sum of in[j] with |i - j| <= r and ids[j] == ids[i] within the run holding i.
/// `in` holds x, y, z and a weight (1 for a finite normal, 0 otherwise) per sample.
void RunSum(const Eigen::Vector4f* in, const std::int32_t* ids, int n, int r, Eigen::Vector4f* out) {
  int start = 0;
  while (start < n) {
    int end = start + 1;
    while (end < n && ids[end] == ids[start]) ++end;
    Eigen::Vector4f acc = Eigen::Vector4f::Zero();
    int lo = start, hi = start;  // acc sums [lo, hi)
    for (int i = start; i < end; ++i) {
      const int want_hi = std::min(end, i + r + 1), want_lo = std::max(start, i - r);
      while (hi < want_hi) acc += in[hi++];
      while (lo < want_lo) acc -= in[lo++];
      out[i] = acc;
    }
    start = end;
  }
}

/// Steady-state column update of one row (see SegmentBoxSums): per column, add the row entering
/// the window when it lies in the pixel's run, subtract the row leaving it when that did. The
/// masks multiply by 1 or 0, which adds exactly what the branchy update added (or exactly 0),
/// so the sums stay the same to the bit; branch-free, the loop vectorises.
SSTA_ANALYSIS_NOINLINE void ColumnStep(int n, int v, int r, const std::int32_t* __restrict run_end,
                                       const std::int32_t* __restrict run_start, const float* __restrict add,
                                       const float* __restrict sub, float* __restrict sum, float* __restrict out) {
  for (int u = 0; u < n; ++u) {
    const float in = v + r < run_end[u] ? 1.0f : 0.0f;
    const float gone = v - r - 1 >= run_start[u] ? 1.0f : 0.0f;
    for (int k = 0; k < 4; ++k) {
      const int i = 4 * u + k;
      sum[i] = (sum[i] + in * add[i]) - gone * sub[i];
      out[i] = sum[i];
    }
  }
}

/// Sums of the finite unit normals (x, y, z and their count) in a window x window box around
/// each pixel, counting only pixels of the same segment along each row and then each column
/// (separable, so O(1) per pixel). Staying inside a segment keeps a ramp's edge from blurring
/// into the ground next to it. Calls on_row(v, sums) with the sums of each row v in turn.
///
/// The row sums (RunSum) are made just in time into a ring of the 2r + 2 rows the column pass
/// needs, and the column pass runs down all columns at once, streaming rows: per column the
/// same additions and subtractions in the same order as RunSum over that column, so the same
/// sums to the bit as summing whole transposed images, with cache-resident buffers instead of
/// several frame-sized ones. Where a vertical run starts its window is summed afresh; elsewhere
/// one branch-free step (ColumnStep) adds the row entering and subtracts the row leaving, from
/// each pixel's run end found beforehand. The buffers are kept per thread (no allocation per
/// frame).
template <typename OnRow>
void SegmentBoxSums(const Image3f& normals, const ImageI32& ids, int window, OnRow&& on_row) {
  const int w = normals.width(), h = normals.height(), r = window / 2;
  const std::size_t stride = static_cast<std::size_t>(w);
  const int slots = std::min(h, 2 * r + 2);
  thread_local std::vector<Eigen::Vector4f> row_in, ring, column_sum, out, zeros;
  thread_local std::vector<std::int32_t> run_start, run_end;
  thread_local std::vector<Eigen::Vector4f*> row_slot;  // row j's slot in the ring
  row_in.resize(stride);
  ring.resize(stride * slots);
  column_sum.resize(stride);
  out.resize(stride);
  zeros.assign(stride, Eigen::Vector4f::Zero());
  run_start.resize(stride);
  run_end.resize(stride * static_cast<std::size_t>(h));
  // run_end(v, u): the first row below v where column u's id changes (h at the bottom).
  for (int v = h - 1; v >= 0; --v) {
    std::int32_t* end = run_end.data() + stride * v;
    if (v == h - 1) {
      std::fill(end, end + w, h);
      continue;
    }
    const std::int32_t* id = ids.row(v);
    const std::int32_t* below = ids.row(v + 1);
    const std::int32_t* end_below = end + stride;
    for (int u = 0; u < w; ++u) end[u] = id[u] == below[u] ? end_below[u] : v + 1;
  }
  row_slot.resize(static_cast<std::size_t>(h));
  for (int j = 0; j < h; ++j) row_slot[j] = ring.data() + stride * static_cast<std::size_t>(j % slots);
  auto row_sums = [&](int j) { return row_slot[j]; };
  int next_row = 0;  // the next row whose row sums are not made yet
  float* sum = column_sum.data()->data();
  for (int v = 0; v < h; ++v) {
    for (const int need = std::min(h - 1, v + r); next_row <= need; ++next_row) {
      const Eigen::Vector3f* n = normals.row(next_row);
      const std::int32_t* id = ids.row(next_row);
      for (int u = 0; u < w; ++u) {
        const bool ok = id[u] >= 0 && std::isfinite(n[u].x()) && std::isfinite(n[u].y()) && std::isfinite(n[u].z());
        row_in[u] = ok ? Eigen::Vector4f(n[u].x(), n[u].y(), n[u].z(), 1.0f) : Eigen::Vector4f::Zero();
      }
      RunSum(row_in.data(), id, w, r, row_sums(next_row));
    }
    const std::int32_t* id = ids.row(v);
    const std::int32_t* end = run_end.data() + stride * v;
    const Eigen::Vector4f* add = v + r < h ? row_sums(v + r) : zeros.data();
    const Eigen::Vector4f* sub = v - r - 1 >= 0 ? row_sums(v - r - 1) : zeros.data();
    ColumnStep(w, v, r, end, run_start.data(), add->data(), sub->data(), sum, out.data()->data());
    const std::int32_t* above = v > 0 ? ids.row(v - 1) : nullptr;
    for (int u = 0; u < w; ++u) {
      if (v > 0 && id[u] == above[u]) continue;
      // A run starts: its window is rows [v, min(end, v + r + 1)), added in order.
      run_start[u] = v;
      Eigen::Vector4f acc = Eigen::Vector4f::Zero();
      for (int j = v; j < std::min(end[u], v + r + 1); ++j) acc += row_sums(j)[u];
      column_sum[u] = acc;
      out[u] = acc;
    }
    on_row(v, out.data());
  }
}

}  // namespace

void RefineByPixelSlope(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                        ImageU8* labels, const ImageI32* segment_ids, int window_px, bool gentler_too) {
  SSTA_CHECK(normals.width() == labels->width() && normals.height() == labels->height(),
             "normals and labels differ in size");
  thread_local ImageU8 slope_classes;
  PixelSlopeClasses(normals, up_camera, vehicle, segment_ids, window_px, &slope_classes);
  ApplyPixelSlopeClasses(slope_classes, labels, gentler_too);
}

void PixelSlopeClasses(const Image3f& normals, const Eigen::Vector3d& up_camera, const VehicleOptions& vehicle,
                       const ImageI32* segment_ids, int window_px, ImageU8* slope_classes) {
  SSTA_CHECK(window_px >= 1 && window_px % 2 == 1, "RefineByPixelSlope: window_px must be odd and positive");
  if (slope_classes->width() != normals.width() || slope_classes->height() != normals.height()) {
    *slope_classes = ImageU8(normals.width(), normals.height(), 0);
  }
  const Eigen::Vector3f up = up_camera.cast<float>();
  const float cos_semi = static_cast<float>(std::cos(DegToRad(vehicle.semi_slope_deg)));
  const float cos_max = static_cast<float>(std::cos(DegToRad(vehicle.max_slope_deg)));
  // c: |cos| of the slope at the pixel; NaN compares false: no class is forced.
  auto slope_class = [&](float c) -> std::uint8_t {
    if (c < cos_max) return static_cast<std::uint8_t>(TravClass::kNonTraversable);
    if (c < cos_semi) return static_cast<std::uint8_t>(TravClass::kSemiTraversable);
    if (c >= cos_semi) return static_cast<std::uint8_t>(TravClass::kTraversable);
    return 0;
  };
  if (window_px == 1) {
    for (std::size_t i = 0; i < normals.size(); ++i) {
      (*slope_classes)[i] = slope_class(std::abs(normals[i].dot(up)));
    }
    return;
  }
  SSTA_CHECK(segment_ids != nullptr && segment_ids->width() == normals.width() &&
                 segment_ids->height() == normals.height(),
             "RefineByPixelSlope: averaging needs segment ids of the normals' size");
  SegmentBoxSums(normals, *segment_ids, window_px, [&](int v, const Eigen::Vector4f* sums) {
    std::uint8_t* row = slope_classes->row(v);
    for (int u = 0; u < normals.width(); ++u) {
      float c = std::numeric_limits<float>::quiet_NaN();
      const Eigen::Vector3f sum = sums[u].head<3>();
      const float norm = sum.norm();
      if (sums[u][3] >= 0.5f && norm > 1e-6f) c = std::abs(sum.dot(up)) / norm;
      row[u] = slope_class(c);
    }
  });
}

void ApplyPixelSlopeClasses(const ImageU8& slope_classes, ImageU8* labels, bool gentler_too) {
  SSTA_CHECK(slope_classes.width() == labels->width() && slope_classes.height() == labels->height(),
             "ApplyPixelSlopeClasses: slope classes and labels differ in size");
  constexpr std::uint8_t kSemi = 2;
  for (std::size_t i = 0; i < labels->size(); ++i) {
    std::uint8_t& label = (*labels)[i];
    if (label != 1 && label != kSemi) continue;
    const std::uint8_t slope = slope_classes[i];
    if (gentler_too && label == kSemi && slope == 1) {
      label = 1;
    } else {
      label = std::max(label, slope);
    }
  }
}

}  // namespace ssta
