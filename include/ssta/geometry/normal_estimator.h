#pragma once

#include <memory>
#include <string>

#include "ssta/core/option_fields.h"
#include "ssta/core/image.h"

namespace ssta {

/// How per-pixel normals are computed from integral images (paper, section "Feature
/// extraction"). All three cost O(1) per pixel whatever the window size, and all three are
/// exact (< 0.01 degree) on noise-free planes, also next to holes, depth edges and the border.
/// On stereo ground with 0.15 px disparity noise and 13 x 13 windows the mean error is ~1.6
/// degrees beyond 5 m for all three; closer than 2.5 m the covariance fit is tilted most by
/// the noise along the viewing rays (4.3 degrees against 2.6 for the two gradient methods).
enum class NormalMethod {
  /// Smallest eigenvector of the 3x3 covariance of the window's points (9 sums + a count):
  /// the paper's choice, and the only method that keeps a normal where a window half is empty
  /// (e.g. at the far end of the ground). Also the fastest here (its eigen solve vectorises).
  kCovarianceMatrix,
  /// Cross product of the smoothed horizontal and vertical 3D gradients, each the difference of
  /// the mean points of two window halves (3 sums + a count).
  kAverage3dGradient,
  /// Normals from the average change of inverse depth across window halves (a sum of 1/Z, a
  /// count and the valid pixels' u, v sums, which locate each half's centre), turned into 3D
  /// with the pixel's own viewing ray and the focal length recovered from the cloud (X/Z of
  /// the extreme valid columns and rows: needs valid points in two columns and two rows).
  kAverageDepthChange,
};

/// Parses the YAML / command-line name: "covariance", "average_3d_gradient" or
/// "average_depth_change". Throws ssta::Error naming the value and the accepted names.
NormalMethod ParseNormalMethod(const std::string& name);

/// The name ParseNormalMethod accepts for `method`.
const char* NormalMethodName(NormalMethod method);

/// Options of the normal estimator (YAML section `normals`).
struct NormalOptions {
  NormalMethod method = NormalMethod::kCovarianceMatrix;

  /// Side of the square averaging window [px]; the window spans +-smoothing_size_px / 2
  /// (integer division) around the pixel, so 12 and 13 both give a 13 x 13 window. Default 13:
  /// at 640 x 480 and f ~ 450 px it covers 0.06 m x 0.06 m at 2 m and 0.3 m across at 10 m,
  /// enough points to average stereo depth noise while staying smaller than the obstacles that
  /// matter (a 0.2 m step at 5 m spans ~18 rows).
  int smoothing_size_px = 31;

  /// Depth-edge threshold in inverse depth [1/m]. Two neighbouring points (4-neighbours, or the
  /// valid points at both ends of a gap of invalid pixels shorter than the window) are a depth
  /// edge when |1/Z_a - 1/Z_b| > max_depth_change_factor * sqrt(1 + gap_px). Inverse depth is
  /// disparity divided by f * b, so the threshold is a disparity jump of factor * f * b pixels:
  /// the default 0.02 is ~1.1 px for f = 450 px, b = 0.12 m. Why inverse depth: stereo noise
  /// is constant in disparity (grows with Z^2 in depth), and 1/Z is linear in (u, v) on any
  /// plane, so a plane is cut only where it passes closer than |n_xy| / (f * factor) to the
  /// camera centre (0.11 m here) - never far ground at a grazing angle, which a relative
  /// |dZ| > factor * Z test cuts. The sqrt(1 + gap) term lets occlusion bands (a gap as wide
  /// as the disparity jump) still separate foreground from background.
  /// A pixel's window never reaches past the nearest edge pixel, nor past the image border.
  double max_depth_change_factor = 0.02;

  /// When true, the window side scales with depth as smoothing_size_px * sqrt(Z / 5 m),
  /// clamped to [0.5, 2] x smoothing_size_px (so up to 2x the buffers and time). Why sqrt: on a
  /// surface facing the camera, disparity noise gives a normal error ~ Z / s^2 for an s x s
  /// window, so s ~ sqrt(Z) keeps it constant. Off by default: on ground seen at a grazing
  /// angle the error of a fixed pixel window hardly depends on Z, and shrinking the near
  /// windows costs more there than the far ones gain (measured, 0.15 px disparity noise: mean
  /// error 1.6 -> 0.8 degrees beyond 10 m, but 4.3 -> 7.0 degrees closer than 2.5 m).
  bool depth_dependent_smoothing = true;

  /// 1: a normal per pixel. 2: normals on every 2nd pixel in each direction only - the
  /// estimator runs on the cloud's (even row, even column) points with half the smoothing size
  /// (the same metric window, a quarter of the points), and each pixel with a valid point takes
  /// the normal of its 2 x 2 block's even pixel (NaN when that one has none). About 3x faster;
  /// planes stay exact (< 0.05 degree, tested), depth-edge gaps widen to whole blocks. The
  /// default: it answers fewer truly blocked footprints drivable than 1 on the tuning scenes
  /// (docs/accuracy.md) and takes about two thirds off the normals' time.
  int subsample = 2;

  /// Threads the sweep over the image runs on, in bands of rows (OpenCV's parallel_for_): 0 =
  /// OpenCV's thread count (cv::getNumThreads(), all cores unless the application set it), 1 =
  /// the calling thread only. The normals are bit for bit the same for any value: each band
  /// starts its integral rows at the band, and box sums are exact integer differences.
  int threads = 0;

  /// Every field: its key, unit, range and meaning (reading, writing and IsValid come from it).
  static const OptionFields<NormalOptions>& Fields();
  /// The first field out of its range, as "key: requirement" in `*error`.
  bool IsValid(std::string* error) const;
};

/// Estimates per-pixel unit normals of an organized point cloud with integral images.
///
/// Input: an organized cloud in the rectified left camera frame (x right, y down, z forward,
/// metres), from a pinhole camera (X/Z linear in u, Y/Z linear in v - true for triangulated
/// rectified stereo), all-NaN where there is no point. Points with Z <= 0 are treated as invalid.
/// Output: unit normals in the same frame, oriented towards the camera (n . p < 0), all-NaN
/// where the point is invalid, the window holds fewer than a quarter valid points (each half,
/// for the gradient methods), or the window is cut by a depth edge or the image border to less
/// than 3 x 3 pixels. The window is the largest square around the pixel, up to the smoothing
/// size, that holds no depth-edge pixel (the chessboard distance to the nearest edge pixel,
/// found with a summed-area table of the edge map); depth-edge pixels themselves get none.
///
/// Precision hardly depends on the rest of the frame: window sums are exact 64-bit integers in
/// a per-frame fixed-point unit (scaled to the largest coordinate), not running float totals,
/// so a few stereo outliers at 500 m cost a plane 1.5 m away at most 0.04 degrees (tested).
///
/// Cost: O(1) per pixel; memory ~ (smoothing_size_px + 2) integral rows per band of rows, not
/// whole tables. The bands run on NormalOptions::threads threads.
/// Keeps its buffers between calls, so a sequence of equally sized frames does not reallocate.
/// Not thread-safe: use one estimator per thread (each call runs its own bands in parallel).
class NormalEstimator {
 public:
  /// Throws ssta::Error (message from NormalOptions::IsValid) on invalid options.
  explicit NormalEstimator(const NormalOptions& options);
  ~NormalEstimator();
  NormalEstimator(NormalEstimator&&) noexcept;
  NormalEstimator& operator=(NormalEstimator&&) noexcept;

  /// Normals of `cloud_camera`; the reference stays valid until the next Compute call.
  const Image3f& Compute(const Image3f& cloud_camera);

  /// Window half-size [px] used at each pixel by the last Compute: the window is
  /// (2r+1) x (2r+1); 0 where no normal was computed. With subsample 2: twice the radius of the
  /// half-resolution window, in full-resolution pixels (the window spans 4r + 1 of them).
  const ImageU8& window_radius_px() const;

  const NormalOptions& options() const { return options_; }

 private:
  struct Band;     // one band's integral rows and row buffers
  struct Buffers;  // integral rows, edge maps: private to the implementation

  int NumBands(int height) const;
  void SplitIntoBands(int num_bands);
  void PrepareFrame(const Image3f& cloud);
  void ComputeWindowRadii(const Image3f& cloud);
  void ComputeCovariance(const Image3f& cloud, int v_begin, int v_end, Band* band);
  void ComputeAverage3dGradient(const Image3f& cloud, int v_begin, int v_end, Band* band);
  void ComputeAverageDepthChange(const Image3f& cloud, int v_begin, int v_end, Band* band);
  void ComputeSubsampled(const Image3f& cloud);

  NormalOptions options_;
  std::unique_ptr<Buffers> buffers_;
};

/// One-shot convenience: NormalEstimator(options).Compute(cloud_camera), returned by value.
/// Throws ssta::Error on invalid options. Thread-safe (no shared state).
Image3f EstimateNormals(const Image3f& cloud_camera, const NormalOptions& options);

}  // namespace ssta
