#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ssta/core/option_fields.h"
#include "ssta/core/image.h"

namespace ssta {

/// Options of the normal-based segmentation (YAML section `segmentation`).
struct SegmenterOptions {
  /// Maximum angle between the normals of two 4-neighbours that join one segment [deg]
  /// (paper eq. 1, read as n1 . n2 >= cos(roughness)). The test is local, and the window spreads
  /// a crease over about its width, so a crease splits two surfaces only where the normal turns
  /// by more than roughness_deg per pixel. Measured with 13 x 13 covariance windows (floor to
  /// ramp at 6 m): 10 / 15 / 20 / 30 degree creases turn by 1.4 / 2.3 / 3.4 / 6.0 degrees per
  /// pixel at their steepest. Default 2: splits creases from ~14 degrees (about the vehicle's
  /// semi-traversable slope) while noisy stereo ground, whose neighbouring normals share most of
  /// their window, stays one segment (97% of the ground within 10 m at 0.15 px disparity
  /// noise). Gentler creases merge into one segment; their slopes lie below the default
  /// semi-traversable slope (15 degrees) anyway.
  double roughness_deg = 9.0;

  /// Maximum disparity difference between two 4-neighbours that join one segment [px]; 0
  /// disables the test, restoring the paper's pure normal criterion. Why: a box top and the
  /// ground seen behind its silhouette have parallel normals and would merge although they lie
  /// apart in depth. Default 1.0: a plane's disparity changes by b |n_xy| / dist px per pixel
  /// (ground seen from a camera h above it: b / h per row, 0.12 px at b = 0.12 m, h = 1 m), and
  /// stereo matchers' sub-pixel noise between neighbours stays well below 1 px, while a 0.3 m
  /// box at 5 m jumps by ~3 px to the ground behind it (f = 450 px, b = 0.12 m, h = 1 m).
  double max_disparity_jump_px = 1.0;

  /// Maximum angle between the mean normals of two segments that join [deg]; 0 disables the
  /// test, restoring the paper's pure neighbour criterion. Why: eq. 1 compares neighbours only,
  /// so a crease smoothed over the normal window (ground into a 20-degree ramp) is crossed in
  /// steps each below roughness_deg and the ramp joins the ground. Comparing whole segments
  /// stops that chaining, and lets roughness_deg be loose enough for stereo noise.
  double max_segment_angle_deg = 10.0;

  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<SegmenterOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Connected components of a normal image. Segment ids are 0 .. num_segments() - 1, numbered in
/// raster order of each segment's first (top-left-most) pixel.
struct Segmentation {
  ImageI32 labels;         ///< segment id per pixel, -1 = no segment (no normal)
  std::vector<int> sizes;  ///< pixels per segment id
  /// The pixels of segment k, as linear indices v * width + u in raster order, are
  /// pixel_indices[offsets[k]] .. pixel_indices[offsets[k + 1] - 1] (CSR layout: one flat
  /// array, so a per-segment pass such as PCA touches memory once and allocates nothing).
  std::vector<int> offsets;
  std::vector<int> pixel_indices;

  int num_segments() const { return static_cast<int>(sizes.size()); }
  /// Id of the segment with the most pixels (the smallest id among equals); -1 when there is none.
  int LargestSegment() const;
};

/// 4-connected connected-components segmentation of per-pixel normals (paper section
/// "Image segmentation", after Trevor et al. 2012): two 4-neighbours with finite normals join
/// while n1 . n2 >= cos(roughness_deg) and, when the disparity test is on and `disparity` is
/// given, |d1 - d2| <= max_disparity_jump_px (an invalid disparity, <= 0 or NaN, fails it),
/// and, when max_segment_angle_deg > 0, the mean normals of their two segments so far differ
/// by less than it (pixels are visited in raster order).
/// Union-find over a reused parent array; no per-pixel allocation.
///
/// Inputs: unit normals (any frame, all-NaN where invalid) and optionally the matching
/// disparity image [px, 0 = invalid] of the same size. Keeps its buffers between calls.
/// Not thread-safe: use one segmenter per thread.
class Segmenter {
 public:
  /// Throws ssta::Error (message from SegmenterOptions::IsValid) on invalid options.
  explicit Segmenter(const SegmenterOptions& options);

  /// Segments `normals`; the reference stays valid until the next Compute call. Throws
  /// ssta::InternalError when `disparity` is given with another size than `normals`.
  const Segmentation& Compute(const Image3f& normals, const ImageF* disparity);

  const SegmenterOptions& options() const { return options_; }

 private:
  struct JoinTest;  // the join test of one Compute call
  void JoinNeighbours(const Image3f& normals, const ImageF* disparity);  // pass 1: union-find
  void TestRowJoins(const JoinTest& test, int v, int width);
  void JoinRow(const Image3f& normals, const JoinTest& test, int v);
  int NumberSegments(std::int32_t num_pixels);  // pass 2: ids and sizes
  void ListPixels(int num_segments);            // offsets and pixel_indices

  SegmenterOptions options_;
  Segmentation result_;
  std::vector<std::int32_t> parent_;
  std::vector<Eigen::Vector3f> normal_sum_;  // per root: sum of its pixels' normals
  std::vector<int> cursor_;
  std::vector<std::uint8_t> join_left_, join_up_;  // per-row join tests
};

/// One-shot convenience: Segmenter(options).Compute(normals, disparity), returned by value.
/// `disparity` may be null. Throws ssta::Error on invalid options. Thread-safe.
Segmentation SegmentNormals(const Image3f& normals, const ImageF* disparity,
                            const SegmenterOptions& options);

}  // namespace ssta
