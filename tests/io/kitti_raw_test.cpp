#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>

#include "ssta/core/error.h"
#include "ssta/io/image_io.h"
#include "ssta/io/sequence.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;

// A three-frame KITTI raw drive in a date folder, with KITTI-like calibration: the IMU sits
// behind and below the velodyne, the camera in front of it, rectified focal 721.5 px and a
// 0.54 m baseline. The vehicle moves 0.0001 deg of longitude east per frame and yaws.
class KittiRawFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    date_ = root_.path() / "2011_09_26";
    drive_ = date_ / "2011_09_26_drive_0001_sync";
    fs::create_directories(drive_);
    std::ofstream(date_ / "calib_cam_to_cam.txt")
        << std::setprecision(10) << "calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\n"
        << "S_rect_00: 1.242000e+03 3.750000e+02\n"
        << "R_rect_00: 1 0 0 0 1 0 0 0 1\n"
        << "P_rect_00: 721.5377 0 609.5593 0 0 721.5377 172.854 0 0 0 1 0\n"
        << "P_rect_01: 721.5377 0 609.5593 " << -721.5377 * 0.54 << " 0 721.5377 172.854 0 0 0 1 0\n";
    // Velodyne: x fwd, y left, z up; camera x right, y down, z fwd, 0.27 m ahead, 0.08 m lower.
    std::ofstream(date_ / "calib_velo_to_cam.txt") << "calib_time: 15-Mar-2012 11:37:16\n"
                                                   << "R: 0 -1 0 0 0 -1 1 0 0\nT: 0 -0.08 -0.27\n";
    std::ofstream(date_ / "calib_imu_to_velo.txt") << "calib_time: 25-May-2012 16:47:16\n"
                                                   << "R: 1 0 0 0 1 0 0 0 1\nT: -0.81 0.32 -0.80\n";
    for (const char* cam : {"image_00", "image_01"}) {
      fs::create_directories(drive_ / cam / "data");
      std::ofstream ts(drive_ / cam / "timestamps.txt");
      for (int i = 0; i < 3; ++i) {
        ts << "2011-09-26 13:02:25." << std::setw(9) << std::setfill('0') << 100000000 * (i + 1) + 7 << "\n";
        char name[32];
        std::snprintf(name, sizeof(name), "%010d.png", i);
        if (!(std::string(cam) == "image_01" && i == 2)) WriteImage(ImageU8(16, 8, 9), (drive_ / cam / "data" / name).string());
      }
    }
    fs::create_directories(drive_ / "oxts/data");
    std::ofstream ts(drive_ / "oxts/timestamps.txt");
    for (int i = 0; i < 3; ++i) {
      ts << "2011-09-26 13:02:25." << std::setw(9) << std::setfill('0') << 100000000 * (i + 1) << "\n";
      char name[32];
      std::snprintf(name, sizeof(name), "%010d.txt", i);
      std::ofstream(drive_ / "oxts/data" / name) << std::setprecision(12) << 49.0 << " " << 8.0 + 0.0001 * i << " "
                                                 << 110.0 + 0.5 * i << " 0.01 -0.02 " << 0.1 * i
                                                 << " 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n";
    }
  }
  testing::TempDir root_;
  fs::path date_, drive_;
};

TEST_F(KittiRawFixture, ReadsRectifiedCalibrationFromTheDateFolder) {
  const Sequence seq = Sequence::Open(drive_.string());
  EXPECT_EQ(seq.format(), "kitti_raw");
  const StereoCalibration& c = seq.calibration();
  EXPECT_EQ(c.left.width, 1242);
  EXPECT_DOUBLE_EQ(c.left.fu, 721.5377);
  EXPECT_TRUE(c.LeftTRight().translation().isApprox(Eigen::Vector3d(0.54, 0, 0), 1e-9));
  EXPECT_TRUE(c.IsRectified());
  // The camera optical axis (z) is the body's forward axis (x).
  EXPECT_TRUE((c.left.body_T_camera.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-9));
  // Camera origin in the body: velodyne origin (0.81, -0.32, 0.80) + camera offset (0.27 fwd, 0.08 down).
  EXPECT_TRUE(c.left.body_T_camera.translation().isApprox(Eigen::Vector3d(1.08, -0.32, 0.72), 1e-9))
      << c.left.body_T_camera.translation().transpose();
}

TEST_F(KittiRawFixture, PairsFramesByIndexAndReportsMissingImages) {
  const Sequence seq = Sequence::OpenKittiRaw(drive_.string());
  ASSERT_EQ(seq.frames().size(), 2u);
  ASSERT_EQ(seq.skipped().size(), 1u);
  EXPECT_NE(seq.skipped()[0].reason.find("cam1 image missing"), std::string::npos);
  // 2011-09-26 13:02:25 UTC = 1317042145 s since the epoch.
  EXPECT_EQ(seq.frames()[0].timestamp_ns, 1317042145LL * 1'000'000'000LL + 100000007);
}

TEST_F(KittiRawFixture, OxtsBecomesLocalMetricPosesAsTheDevkitComputes) {
  const Sequence seq = Sequence::OpenKittiRaw(drive_.string());
  ASSERT_EQ(seq.poses().size(), 3u);
  EXPECT_NEAR(seq.poses()[0].world_p_body.norm(), 0.0, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(seq.poses()[0].world_q_body).angle(), 0.0, 1e-9);
  // 0.0001 deg of longitude at 49 deg N on the devkit's Mercator: cos(49)*pi*6378137/180*1e-4.
  const double east = std::cos(49.0 * M_PI / 180) * M_PI * 6378137.0 / 180.0 * 1e-4;
  // The first pose is rotated (roll 0.01, pitch -0.02): the offset is expressed in its frame.
  const Eigen::Matrix3d r0 = (Eigen::AngleAxisd(0.0, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(-0.02, Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const Eigen::Vector3d expected = r0.transpose() * Eigen::Vector3d(east, 0, 0.5);
  EXPECT_TRUE(seq.poses()[1].world_p_body.isApprox(expected, 1e-6)) << seq.poses()[1].world_p_body.transpose();
  EXPECT_NEAR(east, 7.303, 0.001);
}

TEST_F(KittiRawFixture, MissingCalibrationNamesTheFile) {
  fs::remove(date_ / "calib_imu_to_velo.txt");
  try {
    Sequence::Open(drive_.string());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("calib_imu_to_velo.txt"), std::string::npos) << e.what();
  }
}

/// Sequence::Open's error message (fails the test when it opens).
std::string OpenError(const fs::path& drive) {
  try {
    Sequence::Open(drive.string());
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "opened";
  return "";
}

TEST_F(KittiRawFixture, AnImageSizeThatIsNoPixelCountIsAnError) {
  // 1e300 used to be cast to int (undefined behaviour).
  for (const char* size : {"1e300 375", "nan 375", "-1242 375", "1242.5 375", "0 375"}) {
    std::string text;
    {
      std::ifstream in(date_ / "calib_cam_to_cam.txt");
      text.assign(std::istreambuf_iterator<char>(in), {});
    }
    std::ofstream(date_ / "calib_cam_to_cam.txt") << text.replace(text.find("1.242000e+03 3.750000e+02"), 25, size);
    const std::string m = OpenError(drive_);
    // ("nan" is no number to the reader: the key counts as missing.)
    EXPECT_NE(m.find("calib_cam_to_cam.txt: "), std::string::npos) << size << ": " << m;
    EXPECT_NE(m.find("S_rect_00"), std::string::npos) << size << ": " << m;
    std::ofstream(date_ / "calib_cam_to_cam.txt") << text.replace(text.find(size), std::string(size).size(),
                                                                  "1.242000e+03 3.750000e+02");
  }
}

TEST_F(KittiRawFixture, AnEmptyDriveIsAnErrorNamingItsTimestamps) {
  std::ofstream(drive_ / "image_00/timestamps.txt").close();
  EXPECT_NE(OpenError(drive_).find("image_00/timestamps.txt: lists no frames"), std::string::npos);
}

TEST_F(KittiRawFixture, ABadTimestampNamesTheFileAndLine) {
  std::ofstream(drive_ / "oxts/timestamps.txt", std::ios::app) << "2011-09-26 13:02:25.x\n";
  EXPECT_NE(OpenError(drive_).find("oxts/timestamps.txt:4: bad timestamp"), std::string::npos);
}

}  // namespace
}  // namespace ssta
