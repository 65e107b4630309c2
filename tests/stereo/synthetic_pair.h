#pragma once

#include <algorithm>
#include <cmath>
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
/// Both images get independent uniform noise of +-`noise` grey levels, as a camera would add.
inline SyntheticPair MakePair(int width, int height, int d_background, int d_square, int u0,
                              int v0, int side, int border, int min_valid_u, unsigned seed = 7,
                              int noise = 3) {
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
  std::mt19937 rng(seed + 2);
  std::uniform_int_distribution<int> jitter(-noise, noise);
  for (ImageU8* image : {&p.left, &p.right}) {
    for (std::size_t i = 0; i < image->size(); ++i) {
      (*image)[i] = static_cast<std::uint8_t>(std::clamp((*image)[i] + jitter(rng), 0, 255));
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

namespace ssta::testing {

/// A floor seen by a level camera: the disparity grows linearly from `d_top` in row 0 to
/// `d_bottom` in the last row (constant along each row), so most rows have a fractional
/// disparity. The right image is resampled from the texture with linear interpolation;
/// `border` px and the columns u < min_valid_u are excluded from `evaluate`.
inline SyntheticPair MakeFloor(int width, int height, double d_top, double d_bottom, int border,
                               int min_valid_u, unsigned seed = 21, int noise = 2) {
  const cv::Mat texture = RandomTexture(width + 256, height, seed, 1.2);
  std::mt19937 rng(seed + 1);
  std::uniform_int_distribution<int> jitter(-noise, noise);
  const auto pixel = [&](double value) {
    return static_cast<std::uint8_t>(std::clamp(static_cast<int>(std::lround(value)) + jitter(rng), 0, 255));
  };
  SyntheticPair p{ImageU8(width, height), ImageU8(width, height), ImageF(width, height),
                  ImageU8(width, height, 0)};
  for (int v = 0; v < height; ++v) {
    const double d = d_top + (d_bottom - d_top) * v / (height - 1);
    const std::uint8_t* t = texture.ptr<std::uint8_t>(v);
    for (int u = 0; u < width; ++u) {
      p.left(v, u) = pixel(t[u]);
      const double x = u + d;  // texture column seen at right u
      const int x0 = static_cast<int>(std::floor(x));
      const double a = x - x0;
      p.right(v, u) = pixel((1.0 - a) * t[x0] + a * t[x0 + 1]);
      p.truth(v, u) = static_cast<float>(d);
      p.evaluate(v, u) = v >= border && v < height - border && u >= std::max(border, min_valid_u) &&
                         u < width - border;
    }
  }
  return p;
}

}  // namespace ssta::testing
