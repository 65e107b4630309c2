#include <gtest/gtest.h>

#include <fstream>

#include "ssta/core/error.h"
#include "ssta/io/camera_calibration.h"
#include "temp_dir.h"

namespace ssta {
namespace {

const char* kEurocStyle = R"(%YAML:1.0
# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam0 (MT9M034)
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
)";

void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

std::string ErrorOf(const std::string& path) {
  try {
    LoadCameraCalibration(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(CameraCalibration, ReadsOpenCvStyleSensorYaml) {
  testing::TempDir dir;
  Write(dir / "s.yaml", kEurocStyle);
  const CameraCalibration c = LoadCameraCalibration(dir / "s.yaml");
  EXPECT_EQ(c.width, 752);
  EXPECT_EQ(c.height, 480);
  EXPECT_DOUBLE_EQ(c.fu, 458.654);
  EXPECT_DOUBLE_EQ(c.cv, 248.375);
  EXPECT_DOUBLE_EQ(c.distortion[0], -0.28340811);
  EXPECT_NEAR(c.body_T_camera.translation().y(), -0.064676986768, 1e-12);
  EXPECT_TRUE(c.HasDistortion());
}

TEST(CameraCalibration, RoundTripsThroughSave) {
  testing::TempDir dir;
  Write(dir / "s.yaml", kEurocStyle);
  const CameraCalibration a = LoadCameraCalibration(dir / "s.yaml");
  SaveCameraCalibration(a, dir / "t.yaml", "round trip");
  const CameraCalibration b = LoadCameraCalibration(dir / "t.yaml");
  EXPECT_TRUE(a.body_T_camera.isApprox(b.body_T_camera, 1e-15));
  EXPECT_EQ(a.distortion, b.distortion);
  EXPECT_DOUBLE_EQ(a.cu, b.cu);
}

TEST(CameraCalibration, ErrorsNameTheFileAndKey) {
  testing::TempDir dir;
  const std::string p = dir / "bad.yaml";
  auto with = [&](const std::string& from, const std::string& to) {
    std::string text = kEurocStyle;
    text.replace(text.find(from), from.size(), to);
    Write(p, text);
    return ErrorOf(p);
  };
  EXPECT_NE(with("458.654, 457.296", "-1.0, 457.296").find("intrinsics"), std::string::npos);
  EXPECT_NE(with("458.654, 457.296", ".nan, 457.296").find("intrinsics"), std::string::npos);
  EXPECT_NE(with("0.0148655429818, -0.999880929698", "2.0, -0.999880929698").find("T_BS"), std::string::npos);
  EXPECT_NE(with("-0.28340811, 0.07395907, ", "-0.28340811, ").find("distortion_coefficients"), std::string::npos);
  EXPECT_NE(with("rate_hz", "frame_rate").find("frame_rate: unknown key"), std::string::npos);
  const std::string missing = ErrorOf(dir / "nope.yaml");
  EXPECT_NE(missing.find("nope.yaml"), std::string::npos);
  EXPECT_NE(missing.find("not found"), std::string::npos);
}

CameraCalibration Pinhole(double tx) {
  CameraCalibration c;
  c.width = 640;
  c.height = 480;
  c.fu = c.fv = 400;
  c.cu = 320;
  c.cv = 240;
  c.body_T_camera.translation() = Eigen::Vector3d(0, -tx, 1);  // body y left = -camera x
  c.body_T_camera.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return c;
}

TEST(StereoCalibration, RecognisesARectifiedRigAndItsBaseline) {
  const StereoCalibration s{Pinhole(0.0), Pinhole(0.12)};
  std::string error;
  EXPECT_TRUE(s.IsValid(&error)) << error;
  EXPECT_TRUE(s.IsRectified());
  EXPECT_TRUE(s.LeftTRight().translation().isApprox(Eigen::Vector3d(0.12, 0, 0), 1e-12));
  StereoCalibration distorted = s;
  distorted.left.distortion[0] = 0.1;
  EXPECT_FALSE(distorted.IsRectified());
}

TEST(StereoCalibration, RejectsZeroAndWrongWayBaselines) {
  std::string error;
  EXPECT_FALSE((StereoCalibration{Pinhole(0.0), Pinhole(0.0)}.IsValid(&error)));
  EXPECT_NE(error.find("baseline"), std::string::npos) << error;
  EXPECT_FALSE((StereoCalibration{Pinhole(0.0), Pinhole(-0.12)}.IsValid(&error)));
  EXPECT_NE(error.find("right of cam0"), std::string::npos) << error;
}

}  // namespace
}  // namespace ssta
