#pragma once

#include <algorithm>
#include <cstdint>
#include <random>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ssta/core/image.h"

namespace ssta::testing {

/// A rendered rectified pair whose disparity is known exactly: a fronto-parallel textured
/// background at one integer disparity and, optionally, a nearer textured square at another.
struct SyntheticPair {
  ImageU8 left, right;
  ImageF truth;       ///< true disparity of each left pixel [px]
  ImageU8 evaluate;   ///< 1 where the pixel is visible in both images and away from edges
};

/// Random texture, lightly blurred so that it looks like a camera image and not like noise.
inline cv::Mat RandomTexture(int width, int height, unsigned seed, double blur_sigma = 0.8) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> grey(0, 255);
  cv::Mat t(height, width, CV_8UC1);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) t.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(grey(rng));
  }
  if (blur_sigma > 0) cv::GaussianBlur(t, t, cv::Size(0, 0), blur_sigma);
  return t;
}

/// Background at `d_background`; a square [u0, u0 + side) x [v0, v0 + side) (left image
/// coordinates) at `d_square` when side > 0. Pixels near the square's edges, the background strip
/// it hides in the right image, `border` px at the image edges and the columns u < min_valid_u
/// are excluded from `evaluate`.
inline SyntheticPair MakePair(int width, int height, int d_background, int d_square, int u0,
                              int v0, int side, int border, int min_valid_u, unsigned seed = 7) {
  const cv::Mat bg = RandomTexture(width + 256, height, seed);
  const cv::Mat fg = RandomTexture(width + 256, height, seed + 1);
  auto in_square = [&](int v, int u_left) {
    return side > 0 && v >= v0 && v < v0 + side && u_left >= u0 && u_left < u0 + side;
  };
  SyntheticPair p{ImageU8(width, height), ImageU8(width, height), ImageF(width, height),
                  ImageU8(width, height, 0)};
  // Texture column x of a surface is seen at left u = x and right u = x - d.
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const bool sq = in_square(v, u);
      p.left(v, u) = sq ? fg.at<std::uint8_t>(v, u) : bg.at<std::uint8_t>(v, u);
      p.truth(v, u) = static_cast<float>(sq ? d_square : d_background);
      const bool sq_right = in_square(v, u + d_square);
      p.right(v, u) = sq_right ? fg.at<std::uint8_t>(v, u + d_square)
                               : bg.at<std::uint8_t>(v, u + d_background);
    }
  }
  // Pixels whose matching window straddles two depths, or that the square hides in the right
  // image (the background strip of width d_square - d_background left of it), are not scored.
  constexpr int kMargin = 6;
  const int occluded = d_square - d_background;
  for (int v = border; v < height - border; ++v) {
    for (int u = std::max(border, min_valid_u); u < width - border; ++u) {
      const bool near_square = side > 0 && v >= v0 - kMargin && v < v0 + side + kMargin &&
                               u >= u0 - occluded - kMargin && u < u0 + side + kMargin;
      const bool inside_square = side > 0 && v >= v0 + kMargin && v < v0 + side - kMargin &&
                                 u >= u0 + kMargin && u < u0 + side - kMargin;
      p.evaluate(v, u) = (near_square && !inside_square) ? 0 : 1;
    }
  }
  return p;
}

}  // namespace ssta::testing
