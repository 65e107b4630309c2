#include "ssta/geometry/segmenter.h"

#include <algorithm>
#include <cmath>

#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {



// Root of i with path halving; roots are the smallest index of their set.
inline std::int32_t Find(std::int32_t* parent, std::int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

#if defined(__GNUC__)
#define SSTA_NOINLINE __attribute__((noinline))
#else
#define SSTA_NOINLINE
#endif

// Join tests of n pixel pairs (a[i], b[i]) given as packed xyz normals: 1 where
// a . b >= cos_min (false for NaN normals). Out of line so that __restrict lets it vectorise.
SSTA_NOINLINE void JoinTests(int n, const float* __restrict a, const float* __restrict b,
                             float cos_min, std::uint8_t* __restrict out) {
  for (int i = 0; i < n; ++i) {
    const float dot =
        a[3 * i] * b[3 * i] + a[3 * i + 1] * b[3 * i + 1] + a[3 * i + 2] * b[3 * i + 2];
    out[i] = dot >= cos_min ? 1 : 0;
  }
}

// As JoinTests, and the disparities (da[i], db[i]) [px] must be valid (> 0) and differ by at
// most max_jump (false for NaN).
SSTA_NOINLINE void JoinTestsWithDisparity(int n, const float* __restrict a,
                                          const float* __restrict b, const float* __restrict da,
                                          const float* __restrict db, float cos_min, float max_jump,
                                          std::uint8_t* __restrict out) {
  for (int i = 0; i < n; ++i) {
    const float dot =
        a[3 * i] * b[3 * i] + a[3 * i + 1] * b[3 * i + 1] + a[3 * i + 2] * b[3 * i + 2];
    const bool normal_ok = dot >= cos_min;
    const bool disparity_ok =
        (da[i] > 0.0f) & (db[i] > 0.0f) & (std::abs(da[i] - db[i]) <= max_jump);
    out[i] = (normal_ok & disparity_ok) ? 1 : 0;
  }
}

}  // namespace

const OptionFields<SegmenterOptions>& SegmenterOptions::Fields() {
  using O = SegmenterOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("roughness_deg", &O::roughness_deg, Open(0, 90), "deg",
                        "neighbours join while their normals differ by less (eq. 1)"));
    f.push_back(Real<O>("max_disparity_jump_px", &O::max_disparity_jump_px, AtLeast(0), "px",
                        "... and their disparities by at most this (0: off, the paper's pure normal test)"));
    f.push_back(Real<O>("max_segment_angle_deg", &O::max_segment_angle_deg, ClosedOpen(0, 90), "deg",
                        "... and the mean normals of their segments by less than this (0: off, the "
                        "paper's neighbour-only test): stops a gradual crease from chaining a ramp "
                        "into the ground"));
    return f;
  }();
  return fields;
}

bool SegmenterOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

int Segmentation::LargestSegment() const {
  if (sizes.empty()) return -1;
  return static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
}

Segmenter::Segmenter(const SegmenterOptions& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
}

// The join test of one Compute call: the pixels' packed xyz normals and their disparities (null
// when the disparity test is off), and the thresholds of the three tests.
struct Segmenter::JoinTest {
  const float* normals = nullptr;
  const float* disparity = nullptr;
  bool use_disparity = false;
  float cos_min = 0.0f;
  float max_jump = 0.0f;
  bool use_segment_angle = false;
  float cos_segment = 0.0f;
};

const Segmentation& Segmenter::Compute(const Image3f& normals, const ImageF* disparity) {
  const int width = normals.width();
  const int height = normals.height();
  SSTA_CHECK(disparity == nullptr || (disparity->width() == width && disparity->height() == height),
             "disparity and normals must have the same size");
  Segmentation& out = result_;
  if (out.labels.width() != width || out.labels.height() != height) {
    out.labels = ImageI32(width, height, -1);
  }
  out.sizes.clear();
  out.offsets.clear();
  out.pixel_indices.clear();
  JoinNeighbours(normals, disparity);
  const int num_segments = NumberSegments(width * height);
  ListPixels(num_segments);
  return out;
}

// Pass 1: join each valid pixel with its left and upper neighbours. Parents always point to
// smaller indices, so a set's root is its first pixel in raster order. The join tests of a
// row run first as vectorised kernels (a NaN normal fails them by itself).
void Segmenter::JoinNeighbours(const Image3f& normals, const ImageF* disparity) {
  const int width = normals.width();
  const int height = normals.height();
  JoinTest test;
  test.use_disparity = disparity != nullptr && options_.max_disparity_jump_px > 0.0;
  test.cos_min = static_cast<float>(std::cos(DegToRad(options_.roughness_deg)));
  test.max_jump = static_cast<float>(options_.max_disparity_jump_px);
  test.use_segment_angle = options_.max_segment_angle_deg > 0.0;
  test.cos_segment = static_cast<float>(std::cos(DegToRad(options_.max_segment_angle_deg)));
  parent_.resize(static_cast<std::size_t>(width) * height);
  if (test.use_segment_angle) normal_sum_.resize(parent_.size());
  join_left_.resize(static_cast<std::size_t>(width));
  join_up_.resize(static_cast<std::size_t>(width));
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "normals must be packed xyz");
  test.normals = normals.data()->data();
  test.disparity = test.use_disparity ? disparity->data() : nullptr;
  for (int v = 0; v < height; ++v) {
    TestRowJoins(test, v, width);
    JoinRow(normals, test, v);
  }
}

// The join tests of row v's pixels with their left neighbours (join_left_, 0 in column 0) and
// their upper neighbours (join_up_, all 0 in row 0), by the vectorised kernels.
void Segmenter::TestRowJoins(const JoinTest& test, int v, int width) {
  std::uint8_t* join_left = join_left_.data();
  std::uint8_t* join_up = join_up_.data();
  auto join_tests = [&](std::int32_t a, std::int32_t b, int n, std::uint8_t* out) {
    if (n <= 0) return;
    if (test.use_disparity) {
      JoinTestsWithDisparity(n, test.normals + 3 * static_cast<std::size_t>(a),
                             test.normals + 3 * static_cast<std::size_t>(b), test.disparity + a,
                             test.disparity + b, test.cos_min, test.max_jump, out);
    } else {
      JoinTests(n, test.normals + 3 * static_cast<std::size_t>(a),
                test.normals + 3 * static_cast<std::size_t>(b), test.cos_min, out);
    }
  };
  const std::int32_t row = v * width;
  join_left[0] = 0;
  join_tests(row + 1, row, width - 1, join_left + 1);
  if (v > 0) {
    join_tests(row, row - width, width, join_up);
  } else {
    std::fill(join_up, join_up + width, std::uint8_t{0});
  }
}

// Row v of pass 1: unions each valid pixel with the neighbours its join tests passed.
void Segmenter::JoinRow(const Image3f& normals, const JoinTest& test, int v) {
  const int width = normals.width();
  std::int32_t* parent = parent_.data();
  Eigen::Vector3f* normal_sum = normal_sum_.data();
  const std::uint8_t* join_left = join_left_.data();
  const std::uint8_t* join_up = join_up_.data();
  const bool use_segment_angle = test.use_segment_angle;
  const float cos_segment = test.cos_segment;
  // With the segment test, sets join only while their mean normals (sums, kept at the roots)
  // agree. Roots stay the smaller index, so parents still point backwards.
  auto agree = [&](std::int32_t ra, std::int32_t rb) {
    const Eigen::Vector3f& sa = normal_sum[ra];
    const Eigen::Vector3f& sb = normal_sum[rb];
    return sa.dot(sb) >= cos_segment * sa.norm() * sb.norm();
  };
  auto merge_roots = [&](std::int32_t ra, std::int32_t rb) {
    if (ra == rb) return ra;
    const std::int32_t root = std::min(ra, rb), child = std::max(ra, rb);
    parent[child] = root;
    normal_sum[root] += normal_sum[child];
    return root;
  };
  const std::int32_t row = v * width;
  for (int u = 0; u < width; ++u) {
    const std::int32_t i = row + u;
    if (!IsFinite(normals[i])) {
      parent[i] = -1;
      continue;
    }
    const bool left = join_left[u] != 0;
    const bool up = join_up[u] != 0;
    if (use_segment_angle) {
      parent[i] = i;
      normal_sum[i] = normals[i];
      std::int32_t root = i;
      if (left) {
        const std::int32_t ra = Find(parent, i - 1);
        if (agree(ra, root)) root = merge_roots(ra, root);
      }
      if (up) {
        const std::int32_t rb = Find(parent, i - width);
        if (rb != root && agree(rb, root)) root = merge_roots(rb, root);
      }
      continue;
    }
    if (left && up) {
      const std::int32_t a = Find(parent, i - 1), b = Find(parent, i - width);
      if (a < b) {
        parent[b] = a;
        parent[i] = a;
      } else {
        parent[a] = b;
        parent[i] = b;
      }
    } else if (left) {
      parent[i] = parent[i - 1];
    } else if (up) {
      parent[i] = Find(parent, i - width);
    } else {
      parent[i] = i;
    }
  }
}

// Pass 2: roots get ids in raster order; every other pixel takes its parent's id, which is
// already final because the parent comes earlier and, by induction, holds its root's id.
// Counts each segment's pixels; returns the number of segments.
int Segmenter::NumberSegments(std::int32_t num_pixels) {
  Segmentation& out = result_;
  const std::int32_t* parent = parent_.data();
  std::int32_t* labels = out.labels.data();
  int num_segments = 0;
  for (std::int32_t i = 0; i < num_pixels; ++i) {
    const std::int32_t p = parent[i];
    if (p < 0) {
      labels[i] = -1;
      continue;
    }
    if (p == i) {
      labels[i] = num_segments++;
      out.sizes.push_back(0);
    } else {
      // Parents point backwards, so labels[p] is final; with the segment test p may be a
      // non-root whose chain was not compressed, which labels[p] already accounts for.
      labels[i] = labels[p];
    }
    ++out.sizes[labels[i]];
  }
  return num_segments;
}

// CSR pixel lists by counting sort (raster order within a segment).
void Segmenter::ListPixels(int num_segments) {
  Segmentation& out = result_;
  const std::int32_t* labels = out.labels.data();
  const std::int32_t num_pixels = static_cast<std::int32_t>(out.labels.size());
  out.offsets.resize(static_cast<std::size_t>(num_segments) + 1);
  out.offsets[0] = 0;
  for (int k = 0; k < num_segments; ++k) out.offsets[k + 1] = out.offsets[k] + out.sizes[k];
  out.pixel_indices.resize(out.offsets[num_segments]);
  cursor_.assign(out.offsets.begin(), out.offsets.end() - 1);
  for (std::int32_t i = 0; i < num_pixels; ++i) {
    const int label = labels[i];
    if (label >= 0) out.pixel_indices[cursor_[label]++] = i;
  }
}

Segmentation SegmentNormals(const Image3f& normals, const ImageF* disparity,
                            const SegmenterOptions& options) {
  Segmenter segmenter(options);
  return segmenter.Compute(normals, disparity);
}

}  // namespace ssta
