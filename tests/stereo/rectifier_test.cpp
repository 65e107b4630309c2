#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include "ssta/core/error.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/io/image_io.h"
#include "ssta/stereo/rectifier.h"
#include "ssta_test_paths.h"
#include "stereo/synthetic_pair.h"

namespace ssta {
namespace {

const std::string kEuroc = std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini/mav0/";
const std::string kKitti = std::string(SSTA_TEST_DATA_DIR) + "/kitti-street-pair/";
const std::vector<std::string> kEurocFrames = {"1403715274262142976", "1403715274312143104",
                                               "1403715274362142976"};

StereoCalibration EurocCalibration() {
  return LoadStereoCalibration(kEuroc + "cam0/sensor.yaml", kEuroc + "cam1/sensor.yaml");
}

cv::Mat ToMat(const ImageU8& image) {
  return cv::Mat(image.height(), image.width(), CV_8UC1,
                 const_cast<std::uint8_t*>(image.data())).clone();
}

struct EpipolarError {
  double mean_abs_dv = 0.0;
  double median_abs_dv = 0.0;
  int matches = 0;    ///< cross-checked ORB matches with a plausible disparity
  int outliers = 0;   ///< of those, |dv| > 4 px (false matches), left out of the mean
  double median_abs_dv_all = 0.0;  ///< median over all matches, outliers included
};

/// ORB features, brute-force Hamming matching with cross-check, disparity in [0, 150] px.
EpipolarError MeasureRowAlignment(const ImageU8& left, const ImageU8& right) {
  auto orb = cv::ORB::create(3000);
  std::vector<cv::KeyPoint> kl, kr;
  cv::Mat dl, dr;
  orb->detectAndCompute(ToMat(left), cv::noArray(), kl, dl);
  orb->detectAndCompute(ToMat(right), cv::noArray(), kr, dr);
  cv::BFMatcher bf(cv::NORM_HAMMING, /*crossCheck=*/true);
  std::vector<cv::DMatch> matches;
  bf.match(dl, dr, matches);
  EpipolarError e;
  std::vector<double> dv, dv_all;
  for (const cv::DMatch& m : matches) {
    if (m.distance > 40) continue;
    const cv::Point2f pl = kl[m.queryIdx].pt;
    const cv::Point2f pr = kr[m.trainIdx].pt;
    const double disparity = pl.x - pr.x;
    if (disparity < 0 || disparity > 150) continue;
    ++e.matches;
    const double d = std::abs(pl.y - pr.y);
    dv_all.push_back(d);
    if (d > 4.0) {
      ++e.outliers;
      continue;
    }
    dv.push_back(d);
  }
  if (!dv.empty()) {
    double sum = 0;
    for (double d : dv) sum += d;
    e.mean_abs_dv = sum / dv.size();
    std::nth_element(dv.begin(), dv.begin() + dv.size() / 2, dv.end());
    e.median_abs_dv = dv[dv.size() / 2];
  }
  if (!dv_all.empty()) {
    std::nth_element(dv_all.begin(), dv_all.begin() + dv_all.size() / 2, dv_all.end());
    e.median_abs_dv_all = dv_all[dv_all.size() / 2];
  }
  return e;
}

TEST(Rectifier, EurocPairsAreRowAligned) {
  const StereoCalibration calibration = EurocCalibration();
  ASSERT_FALSE(calibration.IsRectified());
  const Rectifier rectifier(calibration, RectifierOptions{});
  EXPECT_FALSE(rectifier.passes_through());
  const RectifiedGeometry& g = rectifier.geometry();
  std::cout << "EuRoC rectified: f " << g.f << " px, baseline " << g.baseline_m << " m, crop "
            << g.crop_width << "x" << g.crop_height << " at (" << g.crop_u0 << ", " << g.crop_v0
            << "), cu " << g.cu << ", cv " << g.cv << "\n";
  EXPECT_EQ(g.full_width, 752);
  EXPECT_EQ(g.full_height, 480);
  EXPECT_GT(g.crop_width * g.crop_height, 0);
  EXPECT_LT(g.crop_width * g.crop_height, 752 * 480);
  EXPECT_GE(g.crop_u0, 0);
  EXPECT_GE(g.crop_v0, 0);
  EXPECT_LE(g.crop_u0 + g.crop_width, 752);
  EXPECT_LE(g.crop_v0 + g.crop_height, 480);
  EXPECT_NEAR(g.baseline_m, 0.110, 0.002);  // EuRoC's published baseline is about 11 cm
  EXPECT_GT(g.f, 250.0);
  EXPECT_LT(g.f, 500.0);
  EXPECT_GT(g.cu, 0.0);
  EXPECT_LT(g.cu, g.crop_width);
  EXPECT_GT(g.cv, 0.0);
  EXPECT_LT(g.cv, g.crop_height);
  EXPECT_NEAR(g.rectified_R_camera.determinant(), 1.0, 1e-9);

  for (const std::string& ts : kEurocFrames) {
    const ImageU8 left = ReadGreyImage(kEuroc + "cam0/data/" + ts + ".png");
    const ImageU8 right = ReadGreyImage(kEuroc + "cam1/data/" + ts + ".png");
    const RectifiedPair pair = rectifier.Rectify(left, right);
    ASSERT_EQ(pair.left.width(), g.crop_width);
    ASSERT_EQ(pair.left.height(), g.crop_height);
    ASSERT_EQ(pair.right.width(), g.crop_width);
    ASSERT_EQ(pair.left_full.width(), 752);
    ASSERT_EQ(pair.left_full.height(), 480);
    // The crop holds no black (unmapped) border: the corners are image content.
    EXPECT_GT(pair.left(0, 0) + pair.left(g.crop_height - 1, g.crop_width - 1), 0);

    const EpipolarError rectified = MeasureRowAlignment(pair.left, pair.right);
    const EpipolarError raw = MeasureRowAlignment(left, right);
    std::cout << "frame " << ts << ": rectified mean |dv| " << rectified.mean_abs_dv
              << " px (median " << rectified.median_abs_dv << ", " << rectified.matches
              << " matches, " << rectified.outliers << " outliers, median over all "
              << rectified.median_abs_dv_all << "); raw median |dv| over all "
              << raw.median_abs_dv_all << " px (" << raw.matches << " matches)\n";
    EXPECT_GT(rectified.matches, 100);
    EXPECT_LT(rectified.outliers, rectified.matches / 10);
    EXPECT_LT(rectified.mean_abs_dv, 1.0);
    EXPECT_LT(rectified.median_abs_dv_all, 0.5);
    // The raw pair is visibly not row-aligned (cv differs by 7 px, plus distortion), so the
    // same measurement can tell a good rectification from none.
    EXPECT_GT(raw.median_abs_dv_all, 3.0);
  }
}

TEST(Rectifier, ConcurrentRectifyGivesTheSameResult) {
  const Rectifier rectifier(EurocCalibration(), RectifierOptions{});
  const ImageU8 left = ReadGreyImage(kEuroc + "cam0/data/" + kEurocFrames[0] + ".png");
  const ImageU8 right = ReadGreyImage(kEuroc + "cam1/data/" + kEurocFrames[0] + ".png");
  const RectifiedPair reference = rectifier.Rectify(left, right);
  RectifiedPair a, b;
  std::thread t1([&] { a = rectifier.Rectify(left, right); });
  std::thread t2([&] { b = rectifier.Rectify(left, right); });
  t1.join();
  t2.join();
  EXPECT_TRUE(std::equal(a.left.data(), a.left.data() + a.left.size(), reference.left.data()));
  EXPECT_TRUE(std::equal(b.right.data(), b.right.data() + b.right.size(), reference.right.data()));
}

TEST(Rectifier, WithoutCroppingKeepsTheFullImage) {
  RectifierOptions options;
  options.crop_to_common_area = false;
  const Rectifier rectifier(EurocCalibration(), options);
  const RectifiedGeometry& g = rectifier.geometry();
  EXPECT_EQ(g.crop_u0, 0);
  EXPECT_EQ(g.crop_v0, 0);
  EXPECT_EQ(g.crop_width, 752);
  EXPECT_EQ(g.crop_height, 480);
}

TEST(Rectifier, AlreadyRectifiedKittiPassesThrough) {
  const StereoCalibration calibration =
      LoadStereoCalibration(kKitti + "cam0/sensor.yaml", kKitti + "cam1/sensor.yaml");
  ASSERT_TRUE(calibration.IsRectified());
  const Rectifier rectifier(calibration, RectifierOptions{});
  EXPECT_TRUE(rectifier.passes_through());
  const RectifiedGeometry& g = rectifier.geometry();
  EXPECT_EQ(g.crop_u0, 0);
  EXPECT_EQ(g.crop_v0, 0);
  EXPECT_EQ(g.crop_width, 1241);
  EXPECT_EQ(g.crop_height, 376);
  EXPECT_DOUBLE_EQ(g.f, 718.856);
  EXPECT_DOUBLE_EQ(g.cu, 607.1928);
  EXPECT_DOUBLE_EQ(g.cv, 185.2157);
  EXPECT_NEAR(g.baseline_m, 0.537, 1e-9);
  EXPECT_TRUE(g.rectified_R_camera.isIdentity(0.0));

  const cv::Mat l = testing::RandomTexture(1241, 376, 1);
  const cv::Mat r = testing::RandomTexture(1241, 376, 2);
  ImageU8 left(1241, 376), right(1241, 376);
  std::copy(l.data, l.data + left.size(), left.data());
  std::copy(r.data, r.data + right.size(), right.data());
  const RectifiedPair pair = rectifier.Rectify(left, right);
  EXPECT_TRUE(std::equal(left.data(), left.data() + left.size(), pair.left.data()));
  EXPECT_TRUE(std::equal(left.data(), left.data() + left.size(), pair.left_full.data()));
  EXPECT_TRUE(std::equal(right.data(), right.data() + right.size(), pair.right.data()));
}

TEST(Rectifier, WrongImageSizeThrowsAndNamesTheSizes) {
  const Rectifier rectifier(EurocCalibration(), RectifierOptions{});
  const ImageU8 good(752, 480, 100);
  try {
    rectifier.Rectify(good, ImageU8(640, 480));
    FAIL() << "wrong right image size accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("right"), std::string::npos) << what;
    EXPECT_NE(what.find("640x480"), std::string::npos) << what;
    EXPECT_NE(what.find("752x480"), std::string::npos) << what;
  }
  try {
    rectifier.Rectify(ImageU8(752, 479), good);
    FAIL() << "wrong left image size accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("left"), std::string::npos) << what;
    EXPECT_NE(what.find("752x479"), std::string::npos) << what;
  }
}

TEST(Rectifier, InvalidCalibrationOrOptionsThrow) {
  StereoCalibration bad = EurocCalibration();
  bad.right.body_T_camera = bad.left.body_T_camera;  // zero baseline
  EXPECT_THROW(Rectifier(bad, RectifierOptions{}), Error);

  // cam1 turned 80 degrees outwards about its y axis: the two views no longer overlap.
  StereoCalibration diverged = EurocCalibration();
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(80.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix();
  diverged.right.body_T_camera = diverged.right.body_T_camera * turn;
  ASSERT_TRUE(diverged.IsValid(nullptr));
  try {
    Rectifier rectifier(diverged, RectifierOptions{});
    FAIL() << "a rig without overlap was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no common valid area"), std::string::npos) << e.what();
  }

  RectifierOptions options;
  options.alpha = 1.5;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("alpha:", 0), 0u) << error;
  try {
    Rectifier rectifier(EurocCalibration(), options);
    FAIL() << "alpha 1.5 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("alpha:", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace ssta
