#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iomanip>

#include "ssta/core/error.h"
#include "ssta/io/sequence.h"
#include "ssta/io/image_io.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;

CameraCalibration Pinhole(double tx) {
  CameraCalibration c;
  c.width = 8;
  c.height = 6;
  c.fu = c.fv = 10;
  c.cu = 4;
  c.cv = 3;
  c.body_T_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  c.body_T_camera.translation() = Eigen::Vector3d(0, -tx, 1);
  return c;
}

// Writes a small ASL sequence: left frames at 0, 100, 200, 300 ms; right frames offset by
// 0.4 ms except the last (5 ms off, unpaired); the image of right frame 100 ms is missing.
class AslFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int cam = 0; cam < 2; ++cam) {
      const std::string dir = root_ / ("cam" + std::to_string(cam));
      fs::create_directories(dir + "/data");
      SaveCameraCalibration(Pinhole(cam * 0.1), dir + "/sensor.yaml");
      std::ofstream csv(dir + "/data.csv");
      csv << "#timestamp [ns],filename\n";
      for (int i = 0; i < 4; ++i) {
        std::int64_t t = i * 100'000'000LL + (cam == 1 ? (i == 3 ? 5'000'000 : 400'000) : 0);
        csv << t << "," << t << ".png\n";
        if (!(cam == 1 && i == 1)) WriteImage(ImageU8(8, 6, 50), dir + "/data/" + std::to_string(t) + ".png");
      }
    }
  }
  testing::TempDir root_;
};

TEST_F(AslFixture, PairsWithinOneMillisecondAndReportsWhatItSkips) {
  const Sequence seq = Sequence::Open(root_.path().string());
  ASSERT_EQ(seq.frames().size(), 2u);
  EXPECT_EQ(seq.frames()[0].timestamp_ns, 0);
  EXPECT_EQ(seq.frames()[1].timestamp_ns, 200'000'000);
  EXPECT_NE(seq.frames()[1].right_path.find("200400000.png"), std::string::npos);
  // Left 100 ms (its cam1 image is missing), left 300 ms (no cam1 within 1 ms) and the cam1 row
  // at 305 ms that no cam0 frame pairs with.
  ASSERT_EQ(seq.skipped().size(), 3u);
  EXPECT_NE(seq.skipped()[0].reason.find("cam1 image missing"), std::string::npos);
  EXPECT_NE(seq.skipped()[1].reason.find("no cam1 frame within 1 ms"), std::string::npos);
  EXPECT_EQ(seq.skipped()[2].timestamp_ns, 305'000'000);
  EXPECT_NE(seq.skipped()[2].reason.find("cam1 frame without a cam0 frame"), std::string::npos);
}

TEST_F(AslFixture, AMissingCam0ImageSkipsItsPairOnce) {
  fs::remove(root_ / "cam0/data/200000000.png");
  const Sequence seq = Sequence::Open(root_.path().string());
  ASSERT_EQ(seq.frames().size(), 1u);
  // 100 ms (cam1 image missing), 200 ms (cam0 image missing: its cam1 row is not reported
  // again as unpaired), 300 ms and the cam1 row at 305 ms: 4 + 1 = 5 rows listed, 1 frame used.
  ASSERT_EQ(seq.skipped().size(), 4u);
  EXPECT_EQ(seq.skipped()[1].timestamp_ns, 200'000'000);
  EXPECT_NE(seq.skipped()[1].reason.find("cam0 image missing"), std::string::npos);
  for (const SkippedFrame& s : seq.skipped()) EXPECT_NE(s.timestamp_ns, 200'400'000) << s.reason;
}

TEST_F(AslFixture, FindsTheMav0SubFolder) {
  testing::TempDir outer;
  fs::copy(root_.path(), outer.path() / "mav0", fs::copy_options::recursive);
  const Sequence seq = Sequence::Open(outer.path().string());
  EXPECT_EQ(seq.frames().size(), 2u);
  EXPECT_NE(seq.root().find("mav0"), std::string::npos);
}

TEST_F(AslFixture, OutOfOrderTimestampsNameTheLine) {
  std::ofstream(root_ / "cam0/data.csv") << "#timestamp [ns],filename\n100,100.png\n50,50.png\n";
  try {
    Sequence::Open(root_.path().string());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cam0/data.csv:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("out of order"), std::string::npos) << e.what();
  }
}

TEST_F(AslFixture, InterpolatesPosesLinearlyAndWithSlerp) {
  fs::create_directories(root_ / "pose0");
  const Eigen::Quaterniond q1(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  std::ofstream(root_ / "pose0/data.csv") << std::setprecision(17) << "#timestamp [ns],p_x [m],p_y,p_z,q_w,q_x,q_y,q_z\n"
                                          << "0,0,0,0,1,0,0,0\n"
                                          << "400000000,2,0,0," << q1.w() << ",0,0," << q1.z() << "\n";
  const Sequence seq = Sequence::Open(root_.path().string());
  const auto pose = seq.WorldTBodyAt(100'000'000);  // a quarter of the way
  ASSERT_TRUE(pose.has_value());
  EXPECT_NEAR(pose->translation().x(), 0.5, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(pose->rotation()).angle(), 0.1, 1e-9);
  EXPECT_FALSE(seq.WorldTBodyAt(2'000'000'000).has_value());
}

TEST_F(AslFixture, PosesAreNotInterpolatedAcrossALongGap) {
  fs::create_directories(root_ / "pose0");
  std::ofstream(root_ / "pose0/data.csv") << "#timestamp [ns],p_x [m],p_y,p_z,q_w,q_x,q_y,q_z\n"
                                          << "0,0,0,0,1,0,0,0\n100000000,1,0,0,1,0,0,0\n"
                                          << "900000000,2,0,0,1,0,0,0\n";
  const Sequence seq = Sequence::Open(root_.path().string());
  EXPECT_TRUE(seq.WorldTBodyAt(50'000'000).has_value());
  EXPECT_FALSE(seq.WorldTBodyAt(500'000'000).has_value());  // inside the 0.8 s gap
  EXPECT_NE(seq.NoPoseReason(500'000'000).find("pose gap of 0.8 s"), std::string::npos)
      << seq.NoPoseReason(500'000'000);
  EXPECT_NE(seq.NoPoseReason(2'000'000'000).find("outside the pose time range"), std::string::npos);
  EXPECT_EQ(seq.NoPoseReason(50'000'000), "");
}

TEST(Sequence, SelectFramesTakesEveryNthUpToALimit) {
  std::vector<StereoFrame> frames(10);
  for (int i = 0; i < 10; ++i) frames[i].timestamp_ns = i;
  const auto picked = SelectFrames(frames, 3, 0);
  ASSERT_EQ(picked.size(), 4u);
  EXPECT_EQ(picked[3].timestamp_ns, 9);
  EXPECT_EQ(SelectFrames(frames, 2, 2).size(), 2u);
  EXPECT_EQ(SelectFrames(frames, 1, 0).size(), 10u);
}

TEST(Sequence, MissingFolderIsAnErrorNamingIt) {
  try {
    Sequence::Open("/nonexistent/seq");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/seq"), std::string::npos);
  }
}

}  // namespace
}  // namespace ssta
