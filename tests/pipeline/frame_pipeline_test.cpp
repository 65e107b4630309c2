#include <gtest/gtest.h>

#include <cmath>

#include "analysis/hidden_drops.h"
#include "plane_stereo_renderer.h"
#include "ssta/analysis/frame_analysis.h"
#include "ssta/analysis/label_refinements.h"
#include "ssta/fusion/frame_points.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/stereo/rectifier.h"
#include "ssta/synth/scene.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta/synth/stereo_renderer.h"
#include "ssta/synth/vehicle_trajectory.h"

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

TEST(FramePipeline, MapPointsAtTheSubPixelDisparityLieCloserToTheSurface) {
  // map.subpixel_window_px (default 7): the frame keeps the matcher's right image, and the map's
  // points move along their rays to the refined disparity. On a rendered plane (whose SGBM
  // disparity locks to whole pixels) they lie closer to it; the labels are those of before.
  testing::PlaneScene scene;
  scene.slope_deg = 5.0;
  const ImageU8 left = testing::RenderPlane(scene, 0.0), right = testing::RenderPlane(scene, scene.baseline_m);
  Config config;
  ASSERT_EQ(config.map.subpixel_window_px, 7);
  FramePipeline pipeline(RectifiedRig(scene), config);
  const FrameResult r = pipeline.Process(left, right, scene.UpCamera());
  ASSERT_EQ(r.right_matched.width(), r.disparity.width());
  ASSERT_EQ(r.right_matched.height(), r.disparity.height());
  Config off = config;
  off.map.subpixel_window_px = 0;
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();  // a rectified rig: camera = rectified
  const auto refined = MapPointsOfFrame(r, identity, config.map, pipeline.geometry(), config.vehicle);
  const auto plain = MapPointsOfFrame(r, identity, off.map, pipeline.geometry(), off.vehicle);
  ASSERT_EQ(refined.size(), plain.size());
  ASSERT_GT(plain.size(), 20000u);
  const Eigen::Vector3f n = scene.NormalCamera().cast<float>();
  const float d = static_cast<float>(scene.camera_height_m * std::cos(scene.slope_deg * M_PI / 180.0));
  double plain_error = 0, refined_error = 0;
  std::size_t moved = 0;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    plain_error += std::abs(n.dot(plain[i].world_p) + d);
    refined_error += std::abs(n.dot(refined[i].world_p) + d);
    moved += refined[i].world_p != plain[i].world_p;
    ASSERT_EQ(refined[i].cls, plain[i].cls);
    // Along the same ray from the camera.
    ASSERT_LT(refined[i].world_p.normalized().cross(plain[i].world_p.normalized()).norm(), 1e-5f);
  }
  plain_error /= plain.size();
  refined_error /= plain.size();
  std::cout << "mean distance to the plane: SGBM " << plain_error << " m, refined " << refined_error << " m; "
            << moved << " of " << plain.size() << " points moved\n";
  EXPECT_GT(moved, plain.size() / 2);
  EXPECT_LT(refined_error, 0.8 * plain_error);  // measured 0.68

  // Off, or with a given disparity, the frame keeps no right image and the points stay put.
  EXPECT_TRUE(FramePipeline(RectifiedRig(scene), off).Process(left, right, scene.UpCamera()).right_matched.empty());
  EXPECT_TRUE(pipeline.ProcessWithDisparity(left, right, r.disparity, scene.UpCamera()).right_matched.empty());
}

TEST(FramePipeline, LabelsKeepTheRectifiedSizeAndClassTheRampBySlope) {
  testing::PlaneScene scene;
  scene.slope_deg = 20.0;  // semi-traversable by slope, and the only plane: the ground
  FramePipeline pipeline(RectifiedRig(scene), Config{});
  const FrameResult r = pipeline.Process(testing::RenderPlane(scene, 0.0),
                                         testing::RenderPlane(scene, scene.baseline_m), scene.UpCamera());
  EXPECT_NEAR(Largest(r.analysis).slope_deg, 20.0, 1.0);
  EXPECT_EQ(r.labels.width(), scene.width);
  EXPECT_EQ(r.labels.height(), scene.height);
  // A single 20-degree plane is the slope the vehicle climbs: the ground, semi-traversable.
  EXPECT_TRUE(r.analysis.quality.passed) << r.analysis.quality.reason;
  EXPECT_EQ(r.analysis.ground.surface_class, TravClass::kSemiTraversable);
  EXPECT_EQ(r.labels(scene.height - 20, scene.width / 2), static_cast<std::uint8_t>(TravClass::kSemiTraversable));
}

TEST(FramePipeline, UntexturedSkyIsLabelledUnknownThoughItHasDepth) {
  // The level plane under a sky of constant grey (rows above the horizon, v < cv - f tan 15 deg
  // = 40). Fed a disparity everywhere (the plane's, and 3 px in the sky as a matcher's noise),
  // the sky's pixels have points; with label_min_texture they are labelled unknown.
  testing::PlaneScene scene;
  scene.slope_deg = 0.0;
  const ImageU8 left = testing::RenderPlane(scene, 0.0), right = testing::RenderPlane(scene, scene.baseline_m);
  Config config;
  FramePipeline reference(RectifiedRig(scene), config);
  const RectifiedGeometry& g = reference.geometry();
  ASSERT_EQ(g.crop_width, scene.width);  // a rectified rig: no crop
  ASSERT_EQ(g.crop_height, scene.height);
  ImageF disparity(scene.width, scene.height, 3.0f);
  const Eigen::Vector3d n = scene.NormalCamera();
  for (int v = 0; v < scene.height; ++v) {
    for (int u = 0; u < scene.width; ++u) {
      const double dot = n.dot(Eigen::Vector3d((u - scene.cu) / scene.f, (v - scene.cv) / scene.f, 1.0));
      if (dot < -1e-9) disparity(v, u) = static_cast<float>(scene.f * scene.baseline_m * -dot / scene.camera_height_m);
    }
  }
  const int half = config.stereo.block_size / 2;
  auto count = [&](const FrameResult& r, int v0, int v1, auto&& pred) {
    int n_pixels = 0;
    for (int v = v0; v < v1; ++v) {
      for (int u = 0; u < scene.width; ++u) n_pixels += pred(r.labels(v, u));
    }
    return n_pixels;
  };
  const auto unknown = [](std::uint8_t c) { return c == 0; };
  const int sky_rows = 40 - half - 1, ground_v0 = 41 + half, ground_v1 = scene.height;
  const int sky_pixels = sky_rows * scene.width, ground_pixels = (ground_v1 - ground_v0) * scene.width;

  config.analysis.label_min_texture = 2.0;
  FramePipeline masked(RectifiedRig(scene), config);
  const FrameResult on = masked.ProcessWithDisparity(left, right, disparity, scene.UpCamera());
  ASSERT_TRUE(on.analysis.quality.passed) << on.analysis.quality.reason;
  EXPECT_EQ(count(on, 0, sky_rows, unknown), sky_pixels);
  // The analysis is the same and the textured ground keeps its classes: the mask only relabels.
  // (Ground beyond triangulation.max_range_m, near the horizon, is unknown in both.)
  config.analysis.label_min_texture = 0.0;
  FramePipeline unmasked(RectifiedRig(scene), config);
  const FrameResult off = unmasked.ProcessWithDisparity(left, right, disparity, scene.UpCamera());
  EXPECT_EQ(count(off, 0, sky_rows, unknown), 0);
  EXPECT_EQ(off.num_segments, on.num_segments);
  EXPECT_EQ(count(on, ground_v0, ground_v1, unknown), count(off, ground_v0, ground_v1, unknown));
  EXPECT_LT(count(off, ground_v0, ground_v1, unknown), ground_pixels / 10);
  EXPECT_EQ(count(off, ground_v0, ground_v1, [](std::uint8_t c) { return c == 1; }),
            count(on, ground_v0, ground_v1, [](std::uint8_t c) { return c == 1; }));
}

// FrameAnalyzer runs the costly parts of the pixel-slope and face steps beside the plane, ground,
// fragment and local-step steps and applies them at their places: its labels must be those of
// the steps run one after the other, on a rendered yard frame where the steps change labels, with
// the face test on, with the shipped options, and with unwindowed slopes.
TEST(FrameAnalyzer, ConcurrentStepsGiveTheLabelsOfTheStepsInOrder) {
  synth::SynthOptions o;
  const Config shipped;
  o.vehicle = shipped.vehicle;
  const synth::Scene scene = synth::MakeScene("yard", o.seed, o.ramp_slope_deg);
  const synth::VehicleTrajectory trajectory(scene, o.motion);
  const synth::StereoRenderer renderer(scene, o.rig, o.render, nullptr, o.seed);
  const Eigen::Isometry3d body_T_cam0 = synth::TrueBodyTCam0(o.rig, o.motion);
  StereoCalibration rig{renderer.Intrinsics(), renderer.Intrinsics()};
  rig.left.body_T_camera = body_T_cam0;
  rig.right.body_T_camera = body_T_cam0 * Eigen::Translation3d(o.rig.baseline_m, 0, 0);
  const Eigen::Isometry3d world_T_body = trajectory.WorldTBody(1.5);
  const synth::StereoFrame pair = renderer.Render(world_T_body * body_T_cam0, 0);
  const Eigen::Vector3d up_camera =
      (body_T_cam0.linear().transpose() * world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ()).normalized();
  FramePipeline pipeline(rig, shipped);
  const FrameResult r = pipeline.Process(pair.left, pair.right, up_camera);
  const RectifiedGeometry& g = pipeline.geometry();
  const Image3f normals = EstimateNormals(r.cloud, shipped.normals);
  const double fb = g.f * g.baseline_m;
  ASSERT_TRUE(shipped.analysis.pixel_slopes);
  ASSERT_GT(shipped.analysis.pixel_slope_window_px, 1);
  ASSERT_EQ(shipped.analysis.step_reference, StepReference::kLocal);
  Config faces = shipped;  // every step of the chain on
  faces.analysis.face_window_px = 11;

  Config plain = shipped;
  plain.analysis.pixel_slope_window_px = 1;
  plain.analysis.face_window_px = 0;
  const DepthNoise noise{shipped.stereo.disparity_sigma_px / fb};
  for (const Config& config : {faces, shipped, plain}) {
    SCOPED_TRACE(config.analysis.face_window_px > 0 ? "with the face test" : "shipped");
    const AnalysisResult concurrent = FrameAnalyzer(config.vehicle, config.analysis, config.stereo.disparity_sigma_px)
                                          .Analyze({&g, &r.disparity, &r.cloud, &normals, &r.segment_ids,
                                                    r.num_segments, r.up_rectified});

    AnalysisResult a = AnalyzeSurfaces(r.cloud, r.segment_ids, r.num_segments, r.up_rectified, config.vehicle,
                                       config.analysis, noise);
    ASSERT_TRUE(a.quality.passed);
    const ImageU8 before_slopes = a.labels;
    RefineByPixelSlope(normals, r.up_rectified, config.vehicle, &a.labels, &r.segment_ids,
                       config.analysis.pixel_slope_window_px,
                       config.analysis.step_reference == StepReference::kLocal);
    int slope_changes = 0;
    for (std::size_t i = 0; i < a.labels.size(); ++i) slope_changes += a.labels[i] != before_slopes[i];
    EXPECT_GT(slope_changes, 100);  // the slope step matters on this frame
    RefineByGroundDisparity(r.cloud, r.segment_ids, fb, config.analysis, &a);
    RefineByFragmentPlanes(r.cloud, r.segment_ids, fb, config.analysis, &a);
    const ImageU8 before_steps = a.labels;
    RefineByLocalSteps(r.cloud, normals, r.up_rectified, config.vehicle, noise, &a.labels);
    int step_changes = 0;
    for (std::size_t i = 0; i < a.labels.size(); ++i) step_changes += a.labels[i] != before_steps[i];
    EXPECT_GT(step_changes, 100);  // the local steps matter (the crate's band, the curbs)
    const ImageU8 before_faces = a.labels;
    RefineByDisparityFaces(r.disparity, g.f, g.cu, g.cv, r.up_rectified, config.analysis, &a.labels);
    if (config.analysis.face_window_px > 0 && config.analysis.face_by_height) {
      JudgeFacesByHeight(r.cloud, r.up_rectified, config.vehicle, before_faces, &a.labels);
    }
    int face_changes = 0;
    for (std::size_t i = 0; i < a.labels.size(); ++i) face_changes += a.labels[i] != before_faces[i];
    if (config.analysis.face_window_px > 0) {
      EXPECT_GT(face_changes, 100);  // the face test matters too
    }
    // The fill leaves the points the local steps held undecided beside a jump to the obstacle.
    ImageU8 step_classes;
    LocalStepClasses(r.cloud, normals, r.up_rectified, config.vehicle, noise, &step_classes);
    FillUndecidedByConsensus(config.analysis, &a.labels, &step_classes);
    // Last, the lips of hidden drops (the analyzer above has no range: FrameAnalyzer's default).
    ApplyHiddenDrops(internal::FindFramesHiddenDrops(r.cloud, r.up_rectified, noise.per_m2, config.vehicle, 0.0),
                     &a.labels);
    // Then the band of a jump that the noise cannot place.
    const ImageU8 before_band = a.labels;
    ApplySmearedStepBand(step_classes, &a.labels);
    int band_changes = 0;
    for (std::size_t i = 0; i < a.labels.size(); ++i) band_changes += a.labels[i] != before_band[i];
    EXPECT_GT(band_changes, 0);  // the frame holds such points

    ASSERT_EQ(concurrent.labels.size(), a.labels.size());
    int differ = 0;
    for (std::size_t i = 0; i < a.labels.size(); ++i) differ += concurrent.labels[i] != a.labels[i];
    EXPECT_EQ(differ, 0);
    ASSERT_EQ(concurrent.segments.size(), a.segments.size());
    for (std::size_t k = 0; k < a.segments.size(); ++k) {
      EXPECT_EQ(concurrent.segments[k].verdict, a.segments[k].verdict) << "segment " << k;
    }
  }
}

TEST(FramePipeline, WrongImageSizeIsAnError) {
  testing::PlaneScene scene;
  FramePipeline pipeline(RectifiedRig(scene), Config{});
  EXPECT_THROW(pipeline.Process(ImageU8(100, 100), ImageU8(100, 100), scene.UpCamera()), Error);
}

}  // namespace
}  // namespace ssta
