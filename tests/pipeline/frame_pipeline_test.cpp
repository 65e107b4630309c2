#include <gtest/gtest.h>

#include <cmath>

#include "plane_stereo_renderer.h"
#include "ssta/pipeline/frame_pipeline.h"

namespace ssta {
namespace {

StereoCalibration RectifiedRig(const testing::PlaneScene& s) {
  CameraCalibration c;
  c.width = s.width;
  c.height = s.height;
  c.fu = c.fv = s.f;
  c.cu = s.cu;
  c.cv = s.cv;
  StereoCalibration rig{c, c};
  rig.right.body_T_camera.translation() = Eigen::Vector3d(s.baseline_m, 0, 0);
  return rig;
}

const SegmentResult& Largest(const AnalysisResult& a) {
  const SegmentResult* best = &a.segments.front();
  for (const auto& s : a.segments) {
    if (s.inliers > best->inliers) best = &s;
  }
  return *best;
}

TEST(FramePipeline, RecoversTheSlopeOfARenderedTiltedPlaneWithinOneDegree) {
  for (const double slope : {0.0, 7.0, 13.0}) {  // traversable: each is the ground plane
    testing::PlaneScene scene;
    scene.slope_deg = slope;
    const ImageU8 left = testing::RenderPlane(scene, 0.0);
    const ImageU8 right = testing::RenderPlane(scene, scene.baseline_m);
    FramePipeline pipeline(RectifiedRig(scene), Config{});
    const FrameResult r = pipeline.Process(left, right, scene.UpCamera());
    const SegmentResult& plane = Largest(r.analysis);
    EXPECT_GT(plane.inliers, 0.5 * scene.width * scene.height) << slope;
    EXPECT_NEAR(plane.slope_deg, slope, 1.0) << slope;
    EXPECT_GT(plane.normal.dot(scene.NormalCamera()), std::cos(1.0 * M_PI / 180)) << slope;
    ASSERT_TRUE(r.analysis.quality.passed) << r.analysis.quality.reason;
    EXPECT_NEAR(r.analysis.ground.camera_height_m, scene.camera_height_m * std::cos(slope * M_PI / 180), 0.03);
  }
}

TEST(FramePipeline, LabelsKeepTheRectifiedSizeAndClassTheRampBySlope) {
  testing::PlaneScene scene;
  scene.slope_deg = 20.0;  // semi-traversable by slope, yet the only plane: no ground plane
  FramePipeline pipeline(RectifiedRig(scene), Config{});
  const FrameResult r = pipeline.Process(testing::RenderPlane(scene, 0.0),
                                         testing::RenderPlane(scene, scene.baseline_m), scene.UpCamera());
  EXPECT_NEAR(Largest(r.analysis).slope_deg, 20.0, 1.0);
  EXPECT_EQ(r.labels.width(), scene.width);
  EXPECT_EQ(r.labels.height(), scene.height);
  // A single 20-degree plane is not traversable, so there is no dominant ground plane and
  // nothing is guessed: depth pixels are undecided.
  EXPECT_FALSE(r.analysis.quality.passed);
  EXPECT_EQ(r.labels(scene.height - 20, scene.width / 2), static_cast<std::uint8_t>(TravClass::kUndecided));
}

TEST(FramePipeline, WrongImageSizeIsAnError) {
  testing::PlaneScene scene;
  FramePipeline pipeline(RectifiedRig(scene), Config{});
  EXPECT_THROW(pipeline.Process(ImageU8(100, 100), ImageU8(100, 100), scene.UpCamera()), Error);
}

}  // namespace
}  // namespace ssta
