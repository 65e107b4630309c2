// The pipeline on real recordings (copied small into tests/data with their licences): a KITTI
// street pair and EuRoC frames. Regions were chosen by hand on the images; the majority class
// in each region is asserted.

#include <gtest/gtest.h>

#include <array>

#include "ssta/io/sequence.h"
#include "ssta/io/image_io.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/sensors/gravity_provider.h"
#include "ssta/pipeline/sequence_classifier.h"
#include "ssta_test_paths.h"

namespace ssta {
namespace {

struct Region {
  int u0, v0, u1, v1;  // in the full rectified image, end exclusive
};

// Shares of classes 0..4 inside `r`.
std::array<double, 5> ClassShares(const ImageU8& labels, const Region& r) {
  std::array<double, 5> shares{};
  int n = 0;
  for (int v = r.v0; v < r.v1; ++v) {
    for (int u = r.u0; u < r.u1; ++u) {
      ++shares[labels(v, u)];
      ++n;
    }
  }
  for (double& s : shares) s /= n;
  return shares;
}

std::string Describe(const std::array<double, 5>& s) {
  std::string out;
  for (int c = 0; c < 5; ++c) out += std::string(ClassName(static_cast<TravClass>(c))) + "=" + std::to_string(s[c]) + " ";
  return out;
}

FrameResult ClassifyFirstFrame(const std::string& sequence_dir, const std::string& config_file) {
  const Sequence seq = Sequence::Open(sequence_dir);
  const Config config = LoadConfig(config_file);
  FramePipeline pipeline(seq.calibration(), config);
  const StereoFrame& f = seq.frames().front();
  const GravityProvider gravity(seq, config.gravity, config.attitude);
  const Eigen::Vector3d up = gravity.UpInCamera(f.timestamp_ns);
  return pipeline.Process(ReadGreyImage(f.left_path), ReadGreyImage(f.right_path), up);
}

TEST(RealData, KittiRoadAheadIsTraversableAndTheParkedCarIsNot) {
  const FrameResult r = ClassifyFirstFrame(std::string(SSTA_TEST_DATA_DIR) + "/kitti-street-pair",
                                           std::string(SSTA_CONFIG_DIR) + "/sensors/kitti.yaml");
  ASSERT_TRUE(r.analysis.quality.passed) << r.analysis.quality.reason;
  EXPECT_NEAR(r.analysis.ground.camera_height_m, 1.65, 0.15);
  const auto road = ClassShares(r.labels, {420, 250, 680, 350});
  EXPECT_GT(road[1], 0.5) << Describe(road);
  const auto car = ClassShares(r.labels, {770, 205, 960, 290});
  EXPECT_GT(car[3], 0.5) << Describe(car);
}

TEST(RealData, EurocFloorInFrontIsTraversable) {
  const FrameResult r = ClassifyFirstFrame(std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini",
                                           std::string(SSTA_CONFIG_DIR) + "/sensors/euroc.yaml");
  ASSERT_TRUE(r.analysis.quality.passed) << r.analysis.quality.reason;
  const auto floor = ClassShares(r.labels, {150, 330, 350, 440});
  EXPECT_GT(floor[1], 0.5) << Describe(floor);
}

}  // namespace
}  // namespace ssta
