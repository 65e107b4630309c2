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

}  // namespace

bool SegmenterOptions::IsValid(std::string* error) const {
  if (!(roughness_deg > 0.0 && roughness_deg < 90.0)) {
    return Fail(error, "roughness_deg: must be in (0, 90) degrees");
  }
  if (!(max_disparity_jump_px >= 0.0 && std::isfinite(max_disparity_jump_px))) {
    return Fail(error, "max_disparity_jump_px: must be >= 0 pixels (0 disables the test)");
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
  SSTA_CHECK(disparity == nullptr || (disparity->width() == width && disparity->height() == height),
             "disparity and normals must have the same size");
  const bool use_disparity = disparity != nullptr && options_.max_disparity_jump_px > 0.0;
  const float cos_min = static_cast<float>(std::cos(options_.roughness_deg * kPi / 180.0));
  const float max_jump = static_cast<float>(options_.max_disparity_jump_px);

  Segmentation& out = result_;
  if (out.labels.width() != width || out.labels.height() != height) {
    out.labels = ImageI32(width, height, -1);
  }
  out.sizes.clear();
  out.offsets.clear();
  out.pixel_indices.clear();
  parent_.resize(static_cast<std::size_t>(width) * height);
  std::int32_t* parent = parent_.data();

  // Pass 1: join each valid pixel with its left and upper neighbours. Parents always point to
  // smaller indices, so a set's root is its first pixel in raster order.
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
      const bool left = u > 0 && joins(i, i - 1);
      const bool up = v > 0 && joins(i, i - width);
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
  std::int32_t* labels = out.labels.data();
  int num_segments = 0;
  const std::int32_t num_pixels = width * height;
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
      labels[i] = labels[p];
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
