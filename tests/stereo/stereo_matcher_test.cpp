#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <iostream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "ssta/core/error.h"
#include "ssta/stereo/stereo_matcher.h"
#include "stereo/synthetic_pair.h"

namespace ssta {
namespace {

using testing::MakePair;
using testing::SyntheticPair;

struct Score {
  double correct = 0.0;  ///< scored pixels with a disparity within 1 px of the truth
  double wrong = 0.0;    ///< valid scored pixels off by more than 1 px, over all valid scored
  double valid = 0.0;    ///< scored pixels with any disparity
};

Score ScoreDisparity(const ImageF& disparity, const SyntheticPair& pair) {
  long scored = 0, valid = 0, correct = 0;
  for (std::size_t i = 0; i < disparity.size(); ++i) {
    if (!pair.evaluate[i]) continue;
    ++scored;
    if (disparity[i] <= 0.0f) continue;
    ++valid;
    if (std::abs(disparity[i] - pair.truth[i]) <= 1.0f) ++correct;
  }
  Score s;
  s.correct = scored ? static_cast<double>(correct) / scored : 0.0;
  s.valid = scored ? static_cast<double>(valid) / scored : 0.0;
  s.wrong = valid ? static_cast<double>(valid - correct) / valid : 0.0;
  return s;
}

StereoMatcherOptions OptionsFor(MatcherType type) {
  StereoMatcherOptions o;
  o.algorithm = type;
  o.num_disparities = 64;
  o.block_size = 7;
  return o;
}

class EachMatcher : public ::testing::TestWithParam<MatcherType> {};

TEST_P(EachMatcher, RecoversPlaneAndNearerSquare) {
  // Background 20 px, square 36 px; columns u < 64 + 8 cannot see the whole search range.
  const SyntheticPair pair = MakePair(320, 240, 20, 36, 150, 70, 90, 8, 72);
  const StereoMatcher matcher(OptionsFor(GetParam()));
  const ImageF disparity = matcher.Compute(pair.left, pair.right);
  ASSERT_EQ(disparity.width(), 320);
  ASSERT_EQ(disparity.height(), 240);
  const Score s = ScoreDisparity(disparity, pair);
  std::cout << MatcherTypeName(GetParam()) << ": correct " << s.correct << ", valid " << s.valid
            << ", wrong among valid " << s.wrong << "\n";
  EXPECT_GT(s.correct, 0.90);
  EXPECT_LT(s.wrong, 0.02);
  // Sub-pixel values on an integer-disparity scene stay close to the integer.
  double abs_error = 0.0;
  long n = 0;
  for (std::size_t i = 0; i < disparity.size(); ++i) {
    if (pair.evaluate[i] && disparity[i] > 0.0f && std::abs(disparity[i] - pair.truth[i]) <= 1.0f) {
      abs_error += std::abs(disparity[i] - pair.truth[i]);
      ++n;
    }
  }
  ASSERT_GT(n, 0);
  EXPECT_LT(abs_error / n, 0.25);
}

TEST_P(EachMatcher, MatchesLeftColumnsWhosePartnerIsInTheRightImage) {
  // Background at 20 px: every left column from 20 + a half window on has its partner inside
  // the right image, also those below num_disparities (64) that a matcher leaves empty unless
  // the images are padded.
  const SyntheticPair pair = MakePair(320, 240, 20, 36, 150, 70, 90, 8, 20 + 8);
  const ImageF disparity = StereoMatcher(OptionsFor(GetParam())).Compute(pair.left, pair.right);
  long scored = 0, correct = 0, partner_outside = 0;
  for (int v = 8; v < 232; ++v) {
    for (int u = 0; u < 64; ++u) {
      if (u < 20 && disparity(v, u) > static_cast<float>(u)) ++partner_outside;
      if (!pair.evaluate(v, u)) continue;
      ++scored;
      correct += std::abs(disparity(v, u) - pair.truth(v, u)) <= 1.0f;
    }
  }
  ASSERT_GT(scored, 30 * 200);
  EXPECT_GT(static_cast<double>(correct) / scored, 0.85) << MatcherTypeName(GetParam());
  EXPECT_EQ(partner_outside, 0);  // no disparity points outside the right image
}

TEST_P(EachMatcher, RecoversSlantedFloorWithSubPixelAccuracy) {
  // Disparity 12 px at the top row to 40 px at the bottom: a floor receding to the horizon.
  const SyntheticPair floor = testing::MakeFloor(320, 240, 12.0, 40.0, 8, 72);
  const ImageF disparity = StereoMatcher(OptionsFor(GetParam())).Compute(floor.left, floor.right);
  const Score s = ScoreDisparity(disparity, floor);
  double abs_error = 0.0;
  long n = 0;
  for (std::size_t i = 0; i < disparity.size(); ++i) {
    if (floor.evaluate[i] && disparity[i] > 0.0f &&
        std::abs(disparity[i] - floor.truth[i]) <= 1.0f) {
      abs_error += std::abs(disparity[i] - floor.truth[i]);
      ++n;
    }
  }
  ASSERT_GT(n, 0);
  std::cout << MatcherTypeName(GetParam()) << " floor: correct " << s.correct << ", wrong "
            << s.wrong << ", mean |error| of correct " << abs_error / n << " px\n";
  EXPECT_GT(s.correct, 0.85);
  EXPECT_LT(s.wrong, 0.03);
  EXPECT_LT(abs_error / n, 0.3);
}

TEST_P(EachMatcher, ConcurrentComputeGivesTheSameResult) {
  const SyntheticPair pair = MakePair(200, 120, 12, 24, 100, 30, 50, 8, 72);
  const StereoMatcher matcher(OptionsFor(GetParam()));
  const ImageF reference = matcher.Compute(pair.left, pair.right);
  ImageF a, b;
  std::thread t1([&] { a = matcher.Compute(pair.left, pair.right); });
  std::thread t2([&] { b = matcher.Compute(pair.left, pair.right); });
  t1.join();
  t2.join();
  long differ = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    differ += (a[i] != reference[i]) + (b[i] != reference[i]);
  }
  EXPECT_EQ(differ, 0);
}

INSTANTIATE_TEST_SUITE_P(Stereo, EachMatcher,
                         ::testing::Values(MatcherType::kBlockMatching, MatcherType::kSemiGlobal,
                                           MatcherType::kPclBlockBased,
                                           MatcherType::kPclAdaptiveCost),
                         [](const ::testing::TestParamInfo<MatcherType>& info) {
                           return MatcherTypeName(info.param);
                         });

/// PCL 1.13's own ratio filter walks off its cost array when the best disparity is the first
/// or the last of the range; the wrapper must survive exactly those pixels.
class PclEndOfRange : public ::testing::TestWithParam<MatcherType> {};

TEST_P(PclEndOfRange, BestDisparityAtEitherEndDoesNotCrash) {
  for (const int min_disparity : {0, 16}) {
    StereoMatcherOptions o = OptionsFor(GetParam());
    o.min_disparity = min_disparity;
    o.num_disparities = 32;
    o.pcl_ratio_filter = 20;
    const int first = min_disparity;
    const int last = min_disparity + 31;
    const int min_u = min_disparity + 32 + 8;
    const StereoMatcher matcher(o);

    // Whole scene at the last disparity of the range (index maxdisp - 1 inside PCL).
    const SyntheticPair at_last = MakePair(240, 120, last, 0, 0, 0, 0, 8, min_u, 11);
    const ImageF d_last = matcher.Compute(at_last.left, at_last.right);
    const Score s_last = ScoreDisparity(d_last, at_last);
    std::cout << MatcherTypeName(GetParam()) << " min " << min_disparity << " at last " << last
              << ": correct " << s_last.correct << ", wrong " << s_last.wrong << "\n";
    EXPECT_GT(s_last.correct, 0.9);
    EXPECT_LT(s_last.wrong, 0.01);

    // Whole scene at the first disparity (index 0): PCL stores index 0 as 0 = invalid, so
    // every scored pixel must be invalid or right.
    const SyntheticPair at_first = MakePair(240, 120, first, 0, 0, 0, 0, 8, min_u, 12);
    const ImageF d_first = matcher.Compute(at_first.left, at_first.right);
    const Score s_first = ScoreDisparity(d_first, at_first);
    std::cout << MatcherTypeName(GetParam()) << " min " << min_disparity << " at first "
              << first << ": valid " << s_first.valid << ", wrong " << s_first.wrong << "\n";
    EXPECT_LT(s_first.wrong, 0.01);

    // Textureless pair: every cost ties and PCL picks index 0, the classic crash.
    const ImageU8 flat(240, 120, 128);
    const ImageF d_flat = matcher.Compute(flat, flat);
    long valid = 0;
    for (std::size_t i = 0; i < d_flat.size(); ++i) valid += d_flat[i] > 0.0f;
    EXPECT_EQ(valid, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Stereo, PclEndOfRange,
                         ::testing::Values(MatcherType::kPclBlockBased,
                                           MatcherType::kPclAdaptiveCost),
                         [](const ::testing::TestParamInfo<MatcherType>& info) {
                           return MatcherTypeName(info.param);
                         });

TEST(StereoMatcher, PclRatioFilterRejectsRepetitiveTexture) {
  // Vertical stripes repeating every 8 px at a true disparity of 26: costs tie at 2, 10, ...,
  // 58, and PCL's block matcher takes the first (2), which is wrong. Camera-like noise keeps
  // the best cost above 0 (a zero best cost passes any ratio test); the stripes have low
  // contrast so that PCL's pre-processing (which clamps at +-31) does not flatten the noise.
  const int width = 240, height = 120, period = 8, truth = 26;
  const cv::Mat texture = testing::RandomTexture(period, height, 5, 0.0);
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> noise(-2, 2);
  const auto pixel = [&](int value) {
    return static_cast<std::uint8_t>(std::clamp(value + noise(rng), 0, 255));
  };
  ImageU8 left(width, height), right(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      left(v, u) = pixel(108 + texture.at<std::uint8_t>(v, u % period) / 6);
      right(v, u) = pixel(108 + texture.at<std::uint8_t>(v, (u + truth) % period) / 6);
    }
  }
  StereoMatcherOptions o = OptionsFor(MatcherType::kPclBlockBased);
  o.speckle_window_size = 0;
  o.pcl_ratio_filter = 0;
  const ImageF unfiltered = StereoMatcher(o).Compute(left, right);
  o.pcl_ratio_filter = 20;
  const ImageF filtered = StereoMatcher(o).Compute(left, right);
  long scored = 0, wrong_unfiltered = 0, wrong_filtered = 0;
  for (int v = 10; v < height - 10; ++v) {
    for (int u = 64 + 10; u < width - 10; ++u) {
      ++scored;
      wrong_unfiltered += unfiltered(v, u) > 0.0f && std::abs(unfiltered(v, u) - truth) > 1.0f;
      wrong_filtered += filtered(v, u) > 0.0f && std::abs(filtered(v, u) - truth) > 1.0f;
    }
  }
  std::cout << "repetitive texture: wrong without ratio filter "
            << static_cast<double>(wrong_unfiltered) / scored << ", with "
            << static_cast<double>(wrong_filtered) / scored << "\n";
  EXPECT_GT(static_cast<double>(wrong_unfiltered) / scored, 0.3);
  EXPECT_LT(static_cast<double>(wrong_filtered) / scored, 0.02);
}

TEST(StereoMatcher, HalfSizeMatchingRecoversPlaneAndSquareAtFullResolution) {
  // Even disparities (20, 36 px) so that the half-size images hold 10 and 18 px exactly.
  const SyntheticPair pair = MakePair(320, 240, 20, 36, 150, 70, 90, 8, 72);
  StereoMatcherOptions o = OptionsFor(MatcherType::kSemiGlobal);
  o.downscale = 2;
  const ImageF disparity = StereoMatcher(o).Compute(pair.left, pair.right);
  ASSERT_EQ(disparity.width(), 320);
  ASSERT_EQ(disparity.height(), 240);
  const Score s = ScoreDisparity(disparity, pair);
  EXPECT_GT(s.correct, 0.85) << "valid " << s.valid << ", wrong " << s.wrong;
  EXPECT_LT(s.wrong, 0.05);
  // Inside the square (36 px) and the background (20 px) the interpolation of equal values
  // gives them back; at the square's edge no value lies between the two (no blending).
  int between = 0;
  for (std::size_t i = 0; i < disparity.size(); ++i) between += disparity[i] > 22.0f && disparity[i] < 34.0f;
  EXPECT_LT(between, 50);
  o.downscale = 3;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("downscale:", 0), 0u) << error;
}

TEST(StereoMatcher, BorderMarginLeavesTheSideBordersWithoutDisparity) {
  const SyntheticPair pair = MakePair(320, 240, 20, 36, 150, 70, 90, 8, 72);
  StereoMatcherOptions o = OptionsFor(MatcherType::kSemiGlobal);
  const ImageF full = StereoMatcher(o).Compute(pair.left, pair.right);
  o.border_margin = 5;
  const ImageF cut = StereoMatcher(o).Compute(pair.left, pair.right);
  int inner_same = 0, inner = 0;
  for (int v = 0; v < cut.height(); ++v) {
    for (int u = 0; u < cut.width(); ++u) {
      const bool border = u < 5 || u >= 315;  // rows are epipolar lines: no margin at top and bottom
      // Background disparity 20: partners closer than 5 px to the right image's edge are u < 25.
      const bool near_partner_edge = full(v, u) > 0 && u - full(v, u) < 5;
      if (border || near_partner_edge) {
        EXPECT_EQ(cut(v, u), 0.0f) << "u " << u << " v " << v;
      } else {
        ++inner;
        inner_same += cut(v, u) == full(v, u);
      }
    }
  }
  EXPECT_EQ(inner_same, inner);  // elsewhere the margin changes nothing ...
  int valid_left = 0;  // ... and the first columns whose partners lie inside still match
  for (int v = 100; v < 140; ++v) valid_left += cut(v, 26) > 0;
  EXPECT_GT(valid_left, 30);
  int top_bottom = 0;  // ... and the top and bottom rows keep the disparity they had
  for (int u = 40; u < 300; ++u) {
    for (int v : {0, 1, 2, 237, 238, 239}) top_bottom += full(v, u) > 0 && cut(v, u) == full(v, u);
  }
  EXPECT_GT(top_bottom, 6 * 200);
}

/// Mean and 90th percentile of |disparity - truth| over evaluated pixels within 1 px of it.
std::pair<double, double> SubPixelError(const ImageF& disparity, const SyntheticPair& pair) {
  std::vector<double> errors;
  for (std::size_t i = 0; i < disparity.size(); ++i) {
    const double e = std::abs(disparity[i] - pair.truth[i]);
    if (pair.evaluate[i] && disparity[i] > 0.0f && e <= 1.0) errors.push_back(e);
  }
  if (errors.empty()) return {1.0, 1.0};
  std::sort(errors.begin(), errors.end());
  double sum = 0.0;
  for (double e : errors) sum += e;
  return {sum / errors.size(), errors[errors.size() * 9 / 10]};
}

TEST(StereoMatcher, SubPixelRefinementUndoesPixelLockingOnASlantedFloor) {
  // SGBM's parabola pulls disparities towards whole pixels; on a floor whose disparity grows
  // 0.12 px per row the error is a saw tooth. The Gauss-Newton refinement removes most of it.
  const SyntheticPair floor = testing::MakeFloor(320, 240, 12.0, 40.0, 8, 72);
  StereoMatcherOptions o = OptionsFor(MatcherType::kSemiGlobal);
  const auto [plain_mean, plain_p90] = SubPixelError(StereoMatcher(o).Compute(floor.left, floor.right), floor);
  o.subpixel_window_px = 7;
  const ImageF refined = StereoMatcher(o).Compute(floor.left, floor.right);
  const auto [mean, p90] = SubPixelError(refined, floor);
  std::cout << "floor |error|: SGBM mean " << plain_mean << " p90 " << plain_p90 << "; refined mean " << mean
            << " p90 " << p90 << " px\n";
  EXPECT_LT(mean, 0.6 * plain_mean);
  EXPECT_LT(p90, 0.6 * plain_p90);
  EXPECT_GT(ScoreDisparity(refined, floor).correct, 0.85);  // no pixel lost to the refinement
}

TEST(StereoMatcher, SubPixelRefinementKeepsDepthEdges) {
  // Windows that straddle the square's 16 px jump (or a hole) keep the matcher's values
  // exactly, so no disparity between the two levels appears; elsewhere values move.
  const SyntheticPair pair = MakePair(320, 240, 20, 36, 150, 70, 90, 8, 72);
  StereoMatcherOptions o = OptionsFor(MatcherType::kSemiGlobal);
  const ImageF plain = StereoMatcher(o).Compute(pair.left, pair.right);
  o.subpixel_window_px = 7;
  const ImageF refined = StereoMatcher(o).Compute(pair.left, pair.right);
  long straddling = 0, kept = 0, inside = 0, moved = 0;
  for (int v = 3; v < 240 - 3; ++v) {
    for (int u = 3; u < 320 - 3; ++u) {
      if (plain(v, u) <= 0.0f) continue;
      float lo = plain(v, u), hi = lo;
      for (int dv = -3; dv <= 3; ++dv) {
        for (int du = -3; du <= 3; ++du) {
          lo = std::min(lo, plain(v + dv, u + du));
          hi = std::max(hi, plain(v + dv, u + du));
        }
      }
      if (lo > 0.0f && hi - lo <= 1.0f) {
        ++inside;
        moved += refined(v, u) != plain(v, u);
      } else {
        ++straddling;
        kept += refined(v, u) == plain(v, u);
      }
    }
  }
  ASSERT_GT(straddling, 500);
  EXPECT_EQ(kept, straddling);
  EXPECT_GT(static_cast<double>(moved) / inside, 0.9);
}

TEST(StereoMatcher, SubPixelRefinementOnItsOwnStaysInsideEachSurface) {
  // RefineDisparitySubpixel on the matcher's output, as the map runs it (one step): with the
  // floor split into two surface ids along a column, pixels whose window reaches across the
  // split (or into an id of -1) keep the matcher's value; the others move, and one step already
  // removes most of the pixel locking.
  const SyntheticPair floor = testing::MakeFloor(320, 240, 12.0, 40.0, 8, 72);
  const ImageF plain = StereoMatcher(OptionsFor(MatcherType::kSemiGlobal)).Compute(floor.left, floor.right);
  ImageF unrestricted = plain;
  RefineDisparitySubpixel(floor.left, floor.right, 7, 1, &unrestricted);
  ImageI32 ids(320, 240, 0);
  for (int v = 0; v < 240; ++v) {
    for (int u = 160; u < 320; ++u) ids(v, u) = 1;
    ids(v, 20) = -1;  // a column without a surface
  }
  ImageF refined = plain;
  RefineDisparitySubpixel(floor.left, floor.right, 7, 1, &refined, &ids);
  long near_split = 0, kept = 0, away = 0, same = 0;
  for (int v = 0; v < 240; ++v) {
    for (int u = 0; u < 320; ++u) {
      if (plain(v, u) <= 0.0f) continue;
      if ((u >= 160 - 3 && u <= 159 + 3) || std::abs(u - 20) <= 3) {  // the window holds two ids
        ++near_split;
        kept += refined(v, u) == plain(v, u);
      } else {
        ++away;
        same += refined(v, u) == unrestricted(v, u);
      }
    }
  }
  ASSERT_GT(near_split, 1500);
  EXPECT_EQ(kept, near_split);
  EXPECT_EQ(same, away);  // elsewhere exactly the unrestricted refinement
  const auto [plain_mean, plain_p90] = SubPixelError(plain, floor);
  const auto [mean, p90] = SubPixelError(refined, floor);
  EXPECT_LT(mean, 0.7 * plain_mean) << "SGBM " << plain_mean << " px, one step " << mean << " px";
  ImageI32 wrong_size(10, 10, 0);
  EXPECT_THROW(RefineDisparitySubpixel(floor.left, floor.right, 7, 1, &refined, &wrong_size), InternalError);
  EXPECT_THROW(RefineDisparitySubpixel(floor.left, floor.right, 6, 1, &refined), InternalError);
}

TEST(StereoMatcher, InvalidOptionsNameTheKey) {
  const auto error_of = [](const StereoMatcherOptions& o) {
    std::string error;
    EXPECT_FALSE(o.IsValid(&error));
    return error;
  };
  StereoMatcherOptions o;
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.num_disparities = 40;
  EXPECT_EQ(error_of(o).rfind("num_disparities: must be a positive multiple of 16", 0), 0u);
  o = StereoMatcherOptions{};
  o.block_size = 8;
  EXPECT_EQ(error_of(o).rfind("block_size:", 0), 0u);
  o = StereoMatcherOptions{};
  o.algorithm = MatcherType::kBlockMatching;
  o.block_size = 3;
  EXPECT_EQ(error_of(o).rfind("block_size:", 0), 0u);
  o = StereoMatcherOptions{};
  o.min_disparity = -1;
  EXPECT_EQ(error_of(o).rfind("min_disparity:", 0), 0u);
  o = StereoMatcherOptions{};
  o.uniqueness_ratio = 101;
  EXPECT_EQ(error_of(o).rfind("uniqueness_ratio:", 0), 0u);
  o = StereoMatcherOptions{};
  o.sgbm_p2 = o.sgbm_p1;
  EXPECT_EQ(error_of(o).rfind("sgbm_p2: must be greater than sgbm_p1", 0), 0u) << error_of(o);
  o = StereoMatcherOptions{};
  o.sgbm_p1 = 0;
  EXPECT_EQ(error_of(o).rfind("sgbm_p1:", 0), 0u);
  o = StereoMatcherOptions{};
  o.pcl_ratio_filter = 100;
  EXPECT_EQ(error_of(o).rfind("pcl_ratio_filter:", 0), 0u);
  o = StereoMatcherOptions{};
  o.subpixel_window_px = 6;
  EXPECT_EQ(error_of(o).rfind("subpixel_window_px:", 0), 0u);
  o = StereoMatcherOptions{};
  o.acso_gamma_s = 2.5;
  EXPECT_EQ(error_of(o).rfind("acso_gamma_s:", 0), 0u);
  o = StereoMatcherOptions{};
  o.acso_smoothness_strong = 5;
  EXPECT_EQ(error_of(o).rfind("acso_smoothness_strong:", 0), 0u);

  o = StereoMatcherOptions{};
  o.num_disparities = 0;
  try {
    StereoMatcher matcher(o);
    FAIL() << "invalid options accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("num_disparities:", 0), 0u) << e.what();
  }
}

TEST(StereoMatcher, SgbmPenaltiesReachTheMatcher) {
  // The same pair with OpenCV's usual penalties and with much larger ones: both recover the
  // plane and the square, but the disparities differ somewhere (the penalties are used).
  const SyntheticPair pair = MakePair(200, 120, 20, 36, 90, 30, 60, 8, 72);
  StereoMatcherOptions o = OptionsFor(MatcherType::kSemiGlobal);
  const ImageF usual = StereoMatcher(o).Compute(pair.left, pair.right);
  o.sgbm_p1 = 64;
  o.sgbm_p2 = 128;
  const ImageF smooth = StereoMatcher(o).Compute(pair.left, pair.right);
  long differ = 0;
  for (std::size_t i = 0; i < usual.size(); ++i) differ += usual[i] != smooth[i] ? 1 : 0;
  EXPECT_GT(differ, 0);
  EXPECT_GT(ScoreDisparity(smooth, pair).correct, 0.85);
}

TEST(StereoMatcher, ParsesAlgorithmNames) {
  for (const MatcherType t : {MatcherType::kBlockMatching, MatcherType::kSemiGlobal,
                              MatcherType::kPclBlockBased, MatcherType::kPclAdaptiveCost}) {
    EXPECT_EQ(ParseMatcherType(MatcherTypeName(t)), t);
  }
  EXPECT_EQ(ParseMatcherType("pcl_acso"), MatcherType::kPclAdaptiveCost);
  try {
    ParseMatcherType("census");
    FAIL() << "unknown name accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("algorithm:", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("census"), std::string::npos);
  }
}

TEST(StereoMatcher, BadImageSizesThrowAndNameTheSizes) {
  const StereoMatcher matcher(StereoMatcherOptions{});
  try {
    matcher.Compute(ImageU8(200, 100), ImageU8(199, 100));
    FAIL() << "size mismatch accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("200x100"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("199x100"), std::string::npos) << e.what();
  }
  try {
    matcher.Compute(ImageU8(60, 100), ImageU8(60, 100));  // narrower than 64 + 9
    FAIL() << "too narrow images accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("60x100"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("73"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ssta

namespace ssta {
namespace {

/// A 640 x 480 image: a grey ramp across (locally planar: no mask response), strong texture
/// (a 4 px checkerboard of +-40 grey levels) over its lower `textured_share` of rows, and white
/// Gaussian noise of `sigma` grey levels, rounded to 8 bits.
ImageU8 NoisyImage(double sigma, double textured_share, std::uint32_t seed) {
  ImageU8 image(640, 480, 0);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  const int textured_from = static_cast<int>(480 * (1.0 - textured_share));
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      double g = 80.0 + 0.1 * u + 0.05 * v;
      if (v >= textured_from) g += ((u / 4 + v / 4) % 2 == 0) ? 40.0 : -40.0;
      image(v, u) = static_cast<std::uint8_t>(std::clamp(std::lround(g + noise(rng)), 0L, 255L));
    }
  }
  return image;
}

TEST(ImageNoiseSigma, MeasuresTheSensorNoiseUnderTextureAndShading) {
  // Rounding to whole grey levels adds a uniform error of variance 1/12 to the noise. The
  // quietest tenth of the tiles lies below their mean by 1.3 times their scatter, about 5 %;
  // where blank tiles are few, the tenth reaches into their quieter half's top: within 10 %.
  for (const double sigma : {1.0, 2.0, 4.0}) {
    const double expected = std::sqrt(sigma * sigma + 1.0 / 12.0);
    for (const double textured : {0.0, 0.8}) {  // texture over four fifths: the quietest tenth is noise
      const double estimate = ImageNoiseSigma(NoisyImage(sigma, textured, 7));
      EXPECT_GT(estimate, 0.9 * expected) << sigma << " " << textured;
      EXPECT_LT(estimate, 1.05 * expected) << sigma << " " << textured;
    }
  }
  // A noiseless shaded image has no noise; an image smaller than a tile has no estimate.
  EXPECT_LT(ImageNoiseSigma(NoisyImage(0.0, 0.5, 9)), 0.1);
  EXPECT_EQ(ImageNoiseSigma(ImageU8(20, 20, 128)), 0.0);
  // A pure-noise block's standard deviation is the noise's: at 1.5 times the estimate, the
  // texture mask keeps none of a blank noisy sky and all of the checkerboard.
  const ImageU8 image = NoisyImage(3.0, 0.5, 10);
  const ImageU8 mask = TextureMask(image, 0, 0, 640, 480, 9, 1.5 * ImageNoiseSigma(image));
  long sky_kept = 0, texture_lost = 0;  // clear of the boundary at row 240 by a block
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      if (v < 230) sky_kept += mask(v, u) != 0;
      if (v >= 250) texture_lost += mask(v, u) == 0;
    }
  }
  EXPECT_EQ(sky_kept, 0);
  EXPECT_EQ(texture_lost, 0);
}

}  // namespace
}  // namespace ssta
