#include "ssta/geometry/segmenter.h"

#include <algorithm>
#include <cmath>

namespace ssta {
namespace {

constexpr double kPi = 3.14159265358979323846;

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

// Root of i with path halving; roots are the smallest index of their set.
inline std::int32_t Find(std::int32_t* parent, std::int32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

inline void Union(std::int32_t* parent, std::int32_t a, std::int32_t b) {
  a = Find(parent, a);
  b = Find(parent, b);
  if (a < b) {
    parent[b] = a;
  } else if (b < a) {
    parent[a] = b;
  }
}

}  // namespace

bool SegmenterOptions::IsValid(std::string* error) const {
  if (!(roughness_deg > 0.0 && roughness_deg < 90.0)) {
    return Fail(error, "roughness_deg: must be in (0, 90) degrees");
  }
  if (!(max_disparity_jump_px >= 0.0 && std::isfinite(max_disparity_jump_px))) {
    return Fail(error, "max_disparity_jump_px: must be >= 0 pixels (0 disables the test)");
  }
  if (!(max_segment_angle_deg >= 0.0 && max_segment_angle_deg < 90.0)) {
    return Fail(error, "max_segment_angle_deg: must be in [0, 90) degrees (0 disables the test)");
  }
  return true;
}

int Segmentation::LargestSegment() const {
  if (sizes.empty()) return -1;
  return static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
}

Segmenter::Segmenter(const SegmenterOptions& options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw Error(error);
}

const Segmentation& Segmenter::Compute(const Image3f& normals, const ImageF* disparity) {
  const int width = normals.width();
  const int height = normals.height();
  SSTA_CHECK(disparity == nullptr ||
                 (disparity->width() == width && disparity->height() == height),
             "disparity and normals must have the same size");
  const bool use_disparity = disparity != nullptr && options_.max_disparity_jump_px > 0.0;
  const float cos_min = static_cast<float>(std::cos(options_.roughness_deg * kPi / 180.0));
  const float max_jump = static_cast<float>(options_.max_disparity_jump_px);
  const bool use_segment_angle = options_.max_segment_angle_deg > 0.0;
  const float cos_segment = static_cast<float>(std::cos(options_.max_segment_angle_deg * kPi / 180.0));

  Segmentation& out = result_;
  if (out.labels.width() != width || out.labels.height() != height) {
    out.labels = ImageI32(width, height, -1);
  }
  out.sizes.clear();
  out.offsets.clear();
  out.pixel_indices.clear();
  parent_.resize(static_cast<std::size_t>(width) * height);
  std::int32_t* parent = parent_.data();
  if (use_segment_angle) normal_sum_.resize(parent_.size());
  Eigen::Vector3f* normal_sum = normal_sum_.data();

  // Joins the sets of a and b; with the segment test, only while their mean normals agree.
  auto merge = [&](std::int32_t a, std::int32_t b) {
    if (!use_segment_angle) {
      Union(parent, a, b);
      return;
    }
    const std::int32_t ra = Find(parent, a), rb = Find(parent, b);
    if (ra == rb) return;
    const Eigen::Vector3f& sa = normal_sum[ra];
    const Eigen::Vector3f& sb = normal_sum[rb];
    if (sa.dot(sb) < cos_segment * sa.norm() * sb.norm()) return;
    const std::int32_t root = std::min(ra, rb), child = std::max(ra, rb);
    parent[child] = root;
    normal_sum[root] = sa + sb;
  };

  // Pass 1: join each valid pixel with its left and upper neighbours.
  auto joins = [&](std::int32_t a, std::int32_t b) {
    if (parent[b] < 0) return false;
    if (normals[a].dot(normals[b]) < cos_min) return false;
    if (use_disparity) {
      const float da = (*disparity)[a], db = (*disparity)[b];
      // Also false for NaN or invalid (<= 0) disparities.
      if (!(da > 0.0f && db > 0.0f && std::abs(da - db) <= max_jump)) return false;
    }
    return true;
  };
  for (int v = 0; v < height; ++v) {
    const std::int32_t row = v * width;
    for (int u = 0; u < width; ++u) {
      const std::int32_t i = row + u;
      if (!IsFinite(normals[i])) {
        parent[i] = -1;
        continue;
      }
      parent[i] = i;
      if (use_segment_angle) normal_sum[i] = normals[i];
      if (u > 0 && joins(i, i - 1)) merge(i, i - 1);
      if (v > 0 && joins(i, i - width)) merge(i, i - width);
    }
  }

  // Pass 2: a root is its set's first pixel in raster order, so labels are assigned in order.
  std::int32_t* labels = out.labels.data();
  int num_segments = 0;
  const std::int32_t num_pixels = width * height;
  for (std::int32_t i = 0; i < num_pixels; ++i) {
    if (parent[i] < 0) {
      labels[i] = -1;
      continue;
    }
    const std::int32_t root = Find(parent, i);
    if (root == i) {
      labels[i] = num_segments++;
      out.sizes.push_back(0);
    } else {
      labels[i] = labels[root];
    }
    ++out.sizes[labels[i]];
  }

  // CSR pixel lists by counting sort (raster order within a segment).
  out.offsets.resize(static_cast<std::size_t>(num_segments) + 1);
  out.offsets[0] = 0;
  for (int k = 0; k < num_segments; ++k) out.offsets[k + 1] = out.offsets[k] + out.sizes[k];
  out.pixel_indices.resize(out.offsets[num_segments]);
  cursor_.assign(out.offsets.begin(), out.offsets.end() - 1);
  for (std::int32_t i = 0; i < num_pixels; ++i) {
    const int label = labels[i];
    if (label >= 0) out.pixel_indices[cursor_[label]++] = i;
  }
  return out;
}

Segmentation SegmentNormals(const Image3f& normals, const ImageF* disparity,
                            const SegmenterOptions& options) {
  Segmenter segmenter(options);
  return segmenter.Compute(normals, disparity);
}

}  // namespace ssta
