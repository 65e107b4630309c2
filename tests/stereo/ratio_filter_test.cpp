#include <iostream>
#include <random>

#include <gtest/gtest.h>

#include "stereo/ratio_filter.h"
#include "stereo/synthetic_pair.h"

namespace ssta::internal {
namespace {

/// A random-texture pair where left(v, u) = right(v, u - shift).
void ShiftedPair(int width, int height, int shift, ImageU8* left, ImageU8* right) {
  const cv::Mat t = ssta::testing::RandomTexture(width + shift, height, 3);
  *left = ImageU8(width, height);
  *right = ImageU8(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      (*right)(v, u) = t.at<std::uint8_t>(v, u + shift);
      (*left)(v, u) = t.at<std::uint8_t>(v, u);
    }
  }
  // left(u) = t(u) and right(u - shift) = t(u): the match of left u is right u - shift.
}

long CountKept(const ImageI32& index, int from_u) {
  long kept = 0;
  for (int v = 0; v < index.height(); ++v) {
    for (int u = from_u; u < index.width(); ++u) kept += index(v, u) >= 0;
  }
  return kept;
}

TEST(RatioFilter, KeepsTrueMatchesAtBothEndsOfTheRange) {
  const int num = 16, radius = 3;
  for (const int shift : {0, num - 1, 7}) {
    ImageU8 left, right;
    ShiftedPair(100, 40, shift, &left, &right);
    ImageI32 index(100, 40, shift);
    ApplyRatioFilter(left, right, radius, num, 0, 20, &index);
    // Columns whose window reaches past the right image's left edge for the match are dropped.
    const long kept = CountKept(index, shift + radius);
    const long total = static_cast<long>(40) * (100 - shift - radius);
    EXPECT_GT(static_cast<double>(kept) / total, 0.97) << "shift " << shift;
    if (shift > 0) {
      EXPECT_EQ(CountKept(index, 0) - kept, 0) << "shift " << shift;
    }
  }
}

TEST(RatioFilter, RejectsAWrongBestIndex) {
  ImageU8 left, right;
  ShiftedPair(100, 40, 5, &left, &right);
  ImageI32 index(100, 40, 12);  // claims disparity 12, the true one (5) is far cheaper
  ApplyRatioFilter(left, right, 3, 16, 0, 20, &index);
  EXPECT_EQ(CountKept(index, 0), 0);
}

TEST(RatioFilter, XOffsetShiftsTheRange) {
  ImageU8 left, right;
  ShiftedPair(100, 40, 20, &left, &right);
  ImageI32 index(100, 40, 4);  // disparity 16 + 4 = 20
  ApplyRatioFilter(left, right, 3, 16, 16, 20, &index);
  const long kept = CountKept(index, 23);
  EXPECT_GT(static_cast<double>(kept) / (40 * 77), 0.97);
}

TEST(RatioFilter, RejectsTiesAndLeavesInvalidPixelsAlone) {
  // Stripes that repeat every 4 px, plus camera-like noise (a perfect match costs 0, and a
  // zero best cost passes any ratio): the costs at d and d +- 4 nearly tie.
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> noise(-3, 3);
  ImageU8 left(60, 20), right(60, 20);
  for (int v = 0; v < 20; ++v) {
    for (int u = 0; u < 60; ++u) {
      left(v, u) = static_cast<std::uint8_t>(((u % 4) * 60 + v * 3) % 200 + 20 + noise(rng));
      right(v, u) =
          static_cast<std::uint8_t>((((u + 2) % 4) * 60 + v * 3) % 200 + 20 + noise(rng));
    }
  }
  ImageI32 index(60, 20, 2);
  index(10, 30) = -1;
  ApplyRatioFilter(left, right, 4, 16, 0, 20, &index);
  // From u = 14 + 4 on, the tying candidates 6, 10 and 14 all lie inside the right image; the
  // 9x9 window keeps the noise in the costs small against the 20% margin.
  const double kept = static_cast<double>(CountKept(index, 18)) / (20 * 42);
  std::cout << "repeating stripes: kept " << kept << "\n";
  EXPECT_LT(kept, 0.03);
  EXPECT_EQ(index(10, 30), -1);
}

}  // namespace
}  // namespace ssta::internal
