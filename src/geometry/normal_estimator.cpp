#include "ssta/geometry/normal_estimator.h"

#include "geometry/normal_kernels.h"

namespace ssta {

using namespace normals;

namespace {

const EnumTable<NormalMethod>& NormalMethods() {
  static const EnumTable<NormalMethod> table("method", {{NormalMethod::kCovarianceMatrix, "covariance"},
                                                        {NormalMethod::kAverage3dGradient, "average_3d_gradient"},
                                                        {NormalMethod::kAverageDepthChange, "average_depth_change"}});
  return table;
}

}  // namespace

NormalMethod ParseNormalMethod(const std::string& name) { return NormalMethods().Parse(name); }

const char* NormalMethodName(NormalMethod method) { return NormalMethods().Name(method).c_str(); }

const OptionFields<NormalOptions>& NormalOptions::Fields() {
  using O = NormalOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Choice<O>("method", &O::method, NormalMethods(),
                          "covariance | average_3d_gradient | average_depth_change"));
    f.push_back(Integer<O>("smoothing_size_px", &O::smoothing_size_px, Closed(kMinSmoothingSizePx, kMaxSmoothingSizePx),
                           "px", "side of the smoothing window")
                    .Require([](const O& o) { return o.subsample == 1 || o.smoothing_size_px / 2 >= kMinSmoothingSizePx; },
                             "must be at least " + std::to_string(2 * kMinSmoothingSizePx) + " with subsample 2"));
    f.push_back(Real<O>("max_depth_change_factor", &O::max_depth_change_factor, OpenClosed(0, 100), "1/m",
                        "windows stop at jumps of inverse depth above this (a disparity jump of factor * f * b px)"));
    f.push_back(Flag<O>("depth_dependent_smoothing", &O::depth_dependent_smoothing,
                        "the window side scales with sqrt(depth / 5 m), 0.5x to 2x: far ground, whose "
                        "depth noise grows as Z^2, is averaged over more pixels"));
    f.push_back(Integer<O>("subsample", &O::subsample, Closed(1, 2), "",
                           "1 | 2: normals on every 2nd pixel in each direction (about 3x faster)"));
    f.push_back(Integer<O>("threads", &O::threads, Closed(0, 256), "",
                           "bands of rows on this many threads (0: OpenCV's count); the normals are the "
                           "same for any value"));
    return f;
  }();
  return fields;
}

bool NormalOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

NormalEstimator::NormalEstimator(const NormalOptions& options)
    : options_(options), buffers_(std::make_unique<Buffers>()) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
}

NormalEstimator::~NormalEstimator() = default;
NormalEstimator::NormalEstimator(NormalEstimator&&) noexcept = default;
NormalEstimator& NormalEstimator::operator=(NormalEstimator&&) noexcept = default;

const ImageU8& NormalEstimator::window_radius_px() const { return buffers_->radius; }

const Image3f& NormalEstimator::Compute(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  if (b.normals.width() != width || b.normals.height() != height) {
    b.normals = Image3f(width, height, NanVector3f());
    b.radius = ImageU8(width, height, 0);
    b.inverse_depth = ImageF(width, height, 0.0f);
    b.edge = ImageU8(width, height, 0);
  }
  if (cloud.empty()) return b.normals;
  if (options_.subsample == 2) {
    ComputeSubsampled(cloud);
    return b.normals;
  }

  PrepareFrame(cloud);
  const int num_bands = NumBands(height);
  b.bands.resize(static_cast<std::size_t>(num_bands));
  SplitIntoBands(num_bands);
  ComputeWindowRadii(cloud);
  if (b.max_abs_coordinate_m <= 0.0) {  // no valid point at all
    b.normals.Fill(NanVector3f());
    return b.normals;
  }
  if (options_.method == NormalMethod::kAverageDepthChange && !(b.fx_px > 0.0 && b.fy_px > 0.0)) {
    b.radius.Fill(0);  // the pinhole scale could not be recovered from the cloud
    b.normals.Fill(NanVector3f());
    return b.normals;
  }
  ForEachBand(b.band_rows, [&](int band, int v_begin, int v_end) {
    Band& state = b.bands[static_cast<std::size_t>(band)];
    switch (options_.method) {
      case NormalMethod::kCovarianceMatrix:
        ComputeCovariance(cloud, v_begin, v_end, &state);
        break;
      case NormalMethod::kAverage3dGradient:
        ComputeAverage3dGradient(cloud, v_begin, v_end, &state);
        break;
      case NormalMethod::kAverageDepthChange:
        ComputeAverageDepthChange(cloud, v_begin, v_end, &state);
        break;
    }
  });
  return b.normals;
}

// Bands of at least kMinBandRows rows, one per thread: each band builds 2 R extra integral rows
// above it, so thin bands would cost more than they save.
int NormalEstimator::NumBands(int height) const {
  const int threads = options_.threads > 0 ? options_.threads : std::max(1, cv::getNumThreads());
  return std::clamp(height / kMinBandRows, 1, threads);
}

// Band boundaries with about equal work in each band: a row costs its valid points (the window
// sums and the eigen solve) plus a share of its width (building its integral row), so the sky
// at the top of a frame does not leave one thread idle. Any boundaries give the same normals.
void NormalEstimator::SplitIntoBands(int num_bands) {
  Buffers& b = *buffers_;
  const int height = static_cast<int>(b.row_points.size());
  const int width = b.normals.width();
  std::int64_t total = 0;
  for (const int n : b.row_points) total += n + width / 4;
  b.band_rows.assign(static_cast<std::size_t>(num_bands) + 1, height);
  b.band_rows[0] = 0;
  std::int64_t acc = 0;
  int band = 1;
  for (int v = 0; v < height && band < num_bands; ++v) {
    acc += b.row_points[static_cast<std::size_t>(v)] + width / 4;
    // Close band `band - 1` after row v once it holds its share, keeping kMinBandRows rows.
    if (acc * num_bands >= total * band && v + 1 - b.band_rows[band - 1] >= kMinBandRows) {
      b.band_rows[band++] = v + 1;
    }
  }
  for (int k = 1; k <= num_bands; ++k) b.band_rows[k] = std::max(b.band_rows[k], b.band_rows[k - 1]);
}


// The estimator runs on the (even row, even column) points with half the smoothing size, so
// its windows cover the same metric area; each pixel with a valid point then takes its 2 x 2
// block's normal, turned towards its own point (NaN when the block's even pixel has none).
// Its neighbours are two pixels apart, a gap of one (g invalid even points between: 2 g + 1),
// so its depth-edge threshold is the full image's at that gap, sqrt(2) times as large:
// factor * sqrt(2 + 2 g) = sqrt(2) factor * sqrt(1 + g). With the one-pixel threshold, noisy
// far ground at a grazing angle became edge pixels without normals, which cut the hills
// scene's ground beyond its rises off from the ground below (docs/performance.md).
void NormalEstimator::ComputeSubsampled(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int half_width = (width + 1) / 2, half_height = (height + 1) / 2;
  if (!b.half) {
    NormalOptions half_options = options_;
    half_options.subsample = 1;
    half_options.smoothing_size_px = options_.smoothing_size_px / 2;
    half_options.max_depth_change_factor = options_.max_depth_change_factor * std::sqrt(2.0);
    b.half = std::make_unique<NormalEstimator>(half_options);
  }
  if (b.half_cloud.width() != half_width || b.half_cloud.height() != half_height) {
    b.half_cloud = Image3f(half_width, half_height, NanVector3f());
  }
  for (int v = 0; v < half_height; ++v) {
    const Eigen::Vector3f* src = cloud.row(2 * v);
    Eigen::Vector3f* dst = b.half_cloud.row(v);
    for (int u = 0; u < half_width; ++u) dst[u] = src[2 * u];
  }
  const Image3f& half_normals = b.half->Compute(b.half_cloud);
  const ImageU8& half_radius = b.half->window_radius_px();
  for (int v = 0; v < height; ++v) {
    const Eigen::Vector3f* points = cloud.row(v);
    const Eigen::Vector3f* block_normals = half_normals.row(v / 2);
    const std::uint8_t* block_radius = half_radius.row(v / 2);
    Eigen::Vector3f* normals = b.normals.row(v);
    std::uint8_t* radius = b.radius.row(v);
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3f& p = points[u];
      const Eigen::Vector3f& n = block_normals[u / 2];
      if (!IsValidPoint(p) || !std::isfinite(n.x())) {
        normals[u] = NanVector3f();
        radius[u] = 0;
        continue;
      }
      normals[u] = n.dot(p) > 0.0f ? Eigen::Vector3f(-n) : n;
      radius[u] = static_cast<std::uint8_t>(std::min(255, 2 * block_radius[u / 2]));
    }
  }
}

namespace {

/// Inverse-depth jump [1/m] that makes a depth edge between two valid points with `gap` invalid
/// pixels between them, for gap = 0 .. max_gap: factor * sqrt(1 + gap).
void EdgeThresholds(double max_depth_change_factor, int max_gap, std::vector<float>* threshold) {
  threshold->resize(static_cast<std::size_t>(max_gap) + 1);
  for (int gap = 0; gap <= max_gap; ++gap) {
    (*threshold)[gap] = static_cast<float>(max_depth_change_factor * std::sqrt(1.0 + gap));
  }
}

/// Extremes of a frame's valid points, gathered row by row in raster order: the largest
/// |x|, |y| or z [m] and inverse depth [1/m], and the normalised image coordinates X/Z at the
/// leftmost and rightmost valid columns and Y/Z at the first valid point of the top and bottom
/// rows with valid points (for PinholeScale).
struct FrameExtremes {
  float max_abs = 0.0f, max_rho = 0.0f;
  int u_min = std::numeric_limits<int>::max(), u_max = -1, v_min = -1, v_max = -1;
  double xhat_at_u_min = 0.0, xhat_at_u_max = 0.0, yhat_at_v_min = 0.0, yhat_at_v_max = 0.0;
};

/// What the raster scan for depth edges reads and writes besides the cloud.
struct EdgeScan {
  const float* threshold;  // [gap]: EdgeThresholds [1/m]
  int max_gap;             // points at the ends of longer gaps are not compared
  std::int32_t* last_row;  // per column, the row of the last valid point above, -1 for none
  float* last_rho;         // per column, its inverse depth [1/m]
  ImageF* inverse_depth;   // 1/Z [1/m], 0 where the point is invalid
  ImageU8* edge;           // 1 at depth-edge pixels
};

/// Scans row v of the cloud: its inverse depth, the depth edges between each valid point and the
/// valid point before it in its row and in its column (marking both ends, on earlier rows too),
/// and its valid points' extremes, taken into `extremes`. Returns the row's valid points.
int ScanRowForEdges(const Image3f& cloud, int v, const EdgeScan& scan, FrameExtremes* extremes) {
  const int width = cloud.width(), max_gap = scan.max_gap;
  const Eigen::Vector3f* points = cloud.row(v);
  float* rho_row = scan.inverse_depth->row(v);
  ImageU8& edge_image = *scan.edge;
  std::uint8_t* edge = edge_image.row(v);
  const float* threshold = scan.threshold;
  std::int32_t* last_row = scan.last_row;
  float* last_rho_column = scan.last_rho;
  FrameExtremes e = *extremes;  // a local copy, which the edge stores cannot alias
  int last_u = -1, row_valid = 0;
  float last_rho = 0.0f;
  for (int u = 0; u < width; ++u) {
    const Eigen::Vector3f& p = points[u];
    if (!IsValidPoint(p)) {
      rho_row[u] = 0.0f;
      continue;
    }
    ++row_valid;
    const float rho = 1.0f / p.z();
    rho_row[u] = rho;
    e.max_abs = std::max(e.max_abs, std::max(std::max(std::abs(p.x()), std::abs(p.y())), p.z()));
    e.max_rho = std::max(e.max_rho, rho);
    if (last_u >= 0) {
      const int gap = u - last_u - 1;
      if (gap <= max_gap && std::abs(rho - last_rho) > threshold[gap]) {
        edge[u] = 1;
        edge[last_u] = 1;
      }
    } else if (u < e.u_min) {
      e.u_min = u;
      e.xhat_at_u_min = p.x() / p.z();
    }
    const int row_above = last_row[u];
    if (row_above >= 0) {
      const int gap = v - row_above - 1;
      if (gap <= max_gap && std::abs(rho - last_rho_column[u]) > threshold[gap]) {
        edge[u] = 1;
        edge_image(row_above, u) = 1;
      }
    }
    if (v != e.v_max) {
      if (e.v_min < 0) {
        e.v_min = v;
        e.yhat_at_v_min = p.y() / p.z();
      }
      e.v_max = v;
      e.yhat_at_v_max = p.y() / p.z();
    }
    last_row[u] = v;
    last_rho_column[u] = rho;
    last_u = u;
    last_rho = rho;
  }
  if (last_u > e.u_max) {
    e.u_max = last_u;
    e.xhat_at_u_max = points[last_u].x() / points[last_u].z();
  }
  *extremes = e;
  return row_valid;
}

/// Pinhole scale [px] along one image axis (X/Z = (u - cu) / fx) from the valid pixels at
/// positions a and b [px] with normalised coordinates at_a and at_b: 0 when they do not
/// determine it.
inline double PinholeScale(int a, int b, double at_a, double at_b) {
  return (b > a && at_b != at_a) ? (b - a) / (at_b - at_a) : 0.0;
}

/// Summed-area table of the edge map, (width + 1) x (height + 1) row-major: entry (v, u)
/// counts the edge pixels in rows < v and columns < u.
void BuildEdgeIntegral(const ImageU8& edge_map, std::vector<std::int32_t>* edge_integral) {
  const int width = edge_map.width();
  const int height = edge_map.height();
  const std::size_t stride = static_cast<std::size_t>(width) + 1;
  edge_integral->resize(stride * (height + 1));
  std::int32_t* integral = edge_integral->data();
  std::fill(integral, integral + stride, 0);
  for (int v = 0; v < height; ++v) {
    const std::uint8_t* edge = edge_map.row(v);
    const std::int32_t* prev = integral + stride * v;
    std::int32_t* cur = integral + stride * (v + 1);
    std::int32_t acc = 0;
    cur[0] = 0;
    for (int u = 0; u < width; ++u) {
      acc += edge[u];
      cur[u + 1] = prev[u + 1] + acc;
    }
  }
}

/// Depth-dependent radius [px] at inverse depth rho [1/m]: the window side
/// smoothing_size_px * sqrt(Z / kReferenceDepthM), clamped, halved.
inline int DepthRadius(float rho, int smoothing_size_px) {
  const double scale = std::clamp(std::sqrt(1.0 / (rho * kReferenceDepthM)), kMinDepthScale, kMaxDepthScale);
  return static_cast<int>(smoothing_size_px * scale) / 2;
}

/// at_most[k] for k = near_radius .. far_radius - 1: the smallest inverse depth [1/m] whose
/// DepthRadius is <= k (0 elsewhere). DepthRadius is non-increasing in rho (each rounded step
/// is monotonic), so a bisection over the float bit patterns finds each.
void DepthRadiusThresholds(int smoothing_size_px, int near_radius, int far_radius, std::vector<float>* at_most) {
  at_most->assign(static_cast<std::size_t>(far_radius) + 1, 0.0f);
  for (int k = near_radius; k < far_radius; ++k) {
    std::uint32_t lo = 0x00800000u, hi = 0x7f7fffffu;  // smallest normal .. largest float
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      float rho;
      std::memcpy(&rho, &mid, sizeof rho);
      if (DepthRadius(rho, smoothing_size_px) <= k) hi = mid; else lo = mid + 1;
    }
    std::memcpy(&(*at_most)[k], &lo, sizeof lo);
  }
}

/// What a pixel's window radius depends on besides its inverse depth and position.
struct RadiusRule {
  int base_radius;                    // smoothing_size_px / 2 [px]
  bool depth_dependent;               // the radius follows the inverse depth (at_most)
  int near_radius, far_radius;        // DepthRadius at the largest and the smallest rho [px]
  const float* at_most;               // DepthRadiusThresholds
  const std::int32_t* edge_integral;  // BuildEdgeIntegral
  int width, height;
};

/// Edge pixels in the window of radius r [px] around pixel (v, u) (inside the image).
inline std::int32_t EdgesInWindow(const std::int32_t* integral, std::size_t stride, int v, int u, int r) {
  const std::int32_t* top = integral + stride * (v - r);
  const std::int32_t* bottom = integral + stride * (v + r + 1);
  return bottom[u + r + 1] - bottom[u - r] - top[u + r + 1] + top[u - r];
}

/// Window radii [px] of row v (0: no normal) from its inverse depths rho [1/m].
///
/// The chessboard distance D to the nearest edge pixel changes by at most 1 between
/// neighbours, and a pixel whose radius the edges cut has D = r + 1 at most: so the next pixel's
/// radius is at most r + 1, and the shrinking starts there instead of at the smoothing radius
/// (same result, since every window larger than the first edge-free one holds an edge). The
/// depth-dependent radius walks from the left neighbour's along at_most: the same integers as
/// DepthRadius, without a square root and a division per pixel.
void RowRadii(const float* rho, int v, const RadiusRule& rule, std::uint8_t* r_out) {
  const int width = rule.width, base_radius = rule.base_radius;
  const int near_radius = rule.near_radius;
  const bool depth_dependent = rule.depth_dependent;
  const float* at_most = rule.at_most;
  const std::int32_t* integral = rule.edge_integral;
  const std::size_t stride = static_cast<std::size_t>(width) + 1;
  const int border_v = std::min(v, rule.height - 1 - v);
  int edge_bound = std::numeric_limits<int>::max();  // upper bound on this pixel's radius
  int depth_r = rule.far_radius;
  for (int u = 0; u < width; ++u) {
    if (!(rho[u] > 0.0f)) {
      r_out[u] = 0;
      edge_bound = std::numeric_limits<int>::max();
      continue;
    }
    int r = base_radius;
    if (depth_dependent) {
      const float p = std::max(rho[u], std::numeric_limits<float>::min());
      while (depth_r > near_radius && p >= at_most[depth_r - 1]) --depth_r;
      while (p < at_most[depth_r]) ++depth_r;
      r = depth_r;
    }
    const int uncut = std::min({r, border_v, u, width - 1 - u});
    r = std::min(uncut, edge_bound);
    while (r >= kMinRadiusPx && EdgesInWindow(integral, stride, v, u, r) > 0) --r;
    edge_bound = r < uncut ? r + 1 : std::numeric_limits<int>::max();
    r_out[u] = static_cast<std::uint8_t>(r >= kMinRadiusPx ? r : 0);
  }
}

}  // namespace

// One raster pass: inverse depth per pixel, depth-edge pixels (horizontal and vertical
// neighbours, bridging short gaps of invalid pixels), the largest coordinate (for the fixed-point
// scales) and the pinhole scale fx, fy from the extreme valid pixels.
void NormalEstimator::PrepareFrame(const Image3f& cloud) {
  Buffers& b = *buffers_;
  const int width = cloud.width();
  const int height = cloud.height();
  const int base_radius = options_.smoothing_size_px / 2;
  b.max_radius_px = options_.depth_dependent_smoothing
                        ? static_cast<int>(options_.smoothing_size_px * kMaxDepthScale) / 2
                        : base_radius;
  // A gap of invalid pixels longer than this cannot fit inside any window with valid pixels on
  // both of its sides, so the points at its ends need no comparison.
  const int max_gap = 2 * b.max_radius_px - 1;
  EdgeThresholds(options_.max_depth_change_factor, max_gap, &b.edge_threshold);

  b.edge.Fill(0);
  b.row_points.assign(static_cast<std::size_t>(height), 0);
  b.last_valid_row.assign(width, -1);
  b.last_inverse_depth.assign(width, 0.0f);
  const EdgeScan scan{b.edge_threshold.data(), max_gap, b.last_valid_row.data(), b.last_inverse_depth.data(),
                      &b.inverse_depth, &b.edge};
  FrameExtremes extremes;
  for (int v = 0; v < height; ++v) {
    b.row_points[static_cast<std::size_t>(v)] = ScanRowForEdges(cloud, v, scan, &extremes);
  }
  b.max_abs_coordinate_m = extremes.max_abs;
  b.max_inverse_depth = extremes.max_rho;
  b.fx_px = PinholeScale(extremes.u_min, extremes.u_max, extremes.xhat_at_u_min, extremes.xhat_at_u_max);
  b.fy_px = PinholeScale(extremes.v_min, extremes.v_max, extremes.yhat_at_v_min, extremes.yhat_at_v_max);
}

// Radius per pixel: the smoothing radius (depth-dependent if asked), cut by the image border and
// shrunk until the square window holds no depth-edge pixel (edge counts from a summed-area
// table). Edge pixels themselves get no normal: their window would reach across the edge.
void NormalEstimator::ComputeWindowRadii(const Image3f& cloud) {
  Buffers& b = *buffers_;
  BuildEdgeIntegral(b.edge, &b.edge_integral);
  // Rather than a square root and a division per pixel, the depth-dependent radius comes from
  // the smallest rho at which it is <= k, found once per k.
  const int size = options_.smoothing_size_px;
  const int far_radius = DepthRadius(std::numeric_limits<float>::min(), size);
  const int near_radius = DepthRadius(std::numeric_limits<float>::max(), size);
  if (options_.depth_dependent_smoothing) {
    DepthRadiusThresholds(size, near_radius, far_radius, &b.radius_threshold);
  }
  const RadiusRule rule{size / 2, options_.depth_dependent_smoothing, near_radius, far_radius,
                        b.radius_threshold.data(), b.edge_integral.data(), cloud.width(), cloud.height()};
  // Rows are independent once the edge table is built: the bands run in parallel.
  ForEachBand(b.band_rows, [&](int, int v_begin, int v_end) {
    for (int v = v_begin; v < v_end; ++v) RowRadii(b.inverse_depth.row(v), v, rule, b.radius.row(v));
  });
}

Image3f EstimateNormals(const Image3f& cloud_camera, const NormalOptions& options) {
  NormalEstimator estimator(options);
  return estimator.Compute(cloud_camera);
}

}  // namespace ssta
