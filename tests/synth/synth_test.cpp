// Tests of the synthetic renderer: its ground truth must hold together, because every accuracy
// figure of the project is measured against it.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/error.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/synth/scene.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta/synth/terrain_truth.h"
#include "ssta/core/units.h"
#include "ssta/synth/vehicle_trajectory.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta::synth {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

/// The shared temporary folder (tests/temp_dir.h), with the Sub() spelling used below.
class TempDir {
 public:
  std::string Sub(const std::string& name) const { return dir_ / name; }

 private:
  testing::TempDir dir_;
};

/// Small, quick options: 320x240 with the default field of view (focal length halved).
SynthOptions SmallOptions(const std::string& scene, int frames) {
  SynthOptions o;
  o.scene = scene;
  o.frames = frames;
  o.rig.width = 320;
  o.rig.height = 240;
  o.rig.focal_px = 210;
  o.grid_resolution_m = 0.25;
  o.grid_seen_only = false;  // the scene checks below look at places the small cameras miss
  return o;
}

/// Rows of a CSV file without its '#' header, as numbers.
std::vector<std::vector<double>> ReadCsv(const std::string& path) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(ReadTextFile(path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<double> row;
    std::stringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::atof(cell.c_str()));
    rows.push_back(row);
  }
  return rows;
}

/// File names listed in a camN/data.csv.
std::vector<std::string> FrameNames(const std::string& csv) {
  std::vector<std::string> names;
  std::istringstream in(ReadTextFile(csv));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    names.push_back(line.substr(line.find(',') + 1));
  }
  return names;
}

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

/// Flat ground with one 0.15 m box and one 0.4 m deep pit.
Scene BoxAndPitWorld() {
  Scene s;
  Obstacle box;
  box.shape = Obstacle::Shape::kBox;
  box.x = 5;
  box.a = box.b = 0.5;
  box.z_min = -0.5;
  box.z_max = 0.15;
  s.obstacles.push_back(box);
  s.pits.push_back({10.0, 0.0, 0.0, 1.0, 1.0, 0.4});
  s.Finish();
  return s;
}

TEST(SynthScene, RaysMeetTheBoxTopItsFaceAndThePitsFarWall) {
  const Scene s = BoxAndPitWorld();
  const SurfaceHit top = s.CastRay({5.1, 0.2, 3.0}, {0, 0, -1}, 10);
  ASSERT_TRUE(top.hit);
  EXPECT_NEAR(top.p_world.z(), 0.15, 1e-9);
  EXPECT_NEAR(top.step_m, 0.15, 1e-9);
  const SurfaceHit face = s.CastRay({0.0, 0.1, 0.1}, {1, 0, 0}, 10);
  ASSERT_TRUE(face.hit);
  EXPECT_NEAR(face.t, 4.5, 1e-9);
  EXPECT_NEAR(face.normal_world.x(), -1.0, 1e-9);
  const SurfaceHit floor = s.CastRay({10.2, 0.3, 2.0}, {0, 0, -1}, 10);
  ASSERT_TRUE(floor.hit);
  EXPECT_NEAR(floor.p_world.z(), -0.4, 1e-6);
  EXPECT_NEAR(floor.step_m, -0.4, 1e-9);
  // A ray grazing into the pit meets its far wall (x = 11) from inside, facing back.
  const SurfaceHit wall = s.CastRay({9.2, 0.0, 0.1}, {1, 0, -0.2}, 10);
  ASSERT_TRUE(wall.hit);
  EXPECT_TRUE(wall.vertical_face);
  EXPECT_NEAR(wall.p_world.x(), 11.0, 1e-5);
  EXPECT_NEAR(wall.p_world.z(), 0.1 - 0.2 * 1.8, 1e-5);
  EXPECT_NEAR(wall.normal_world.x(), -1.0, 1e-9);
}

// The class rule (docs/interfaces.md, section 3) on analytic worlds, with the default vehicle:
// slope 15 / 25 deg, step 0.1 / 0.2 m, step radius 0.2 m.
constexpr std::uint8_t kTrav = 1, kSemi = 2, kNon = 3;

Obstacle Box(double x, double y, double half_x, double half_y, double height) {
  Obstacle b;
  b.shape = Obstacle::Shape::kBox;
  b.x = x;
  b.y = y;
  b.a = half_x;
  b.b = half_y;
  b.z_min = -0.5;
  b.z_max = height;
  return b;
}

TerrainTruth TruthOf(const Scene& s, const VehicleOptions& vehicle = {}) {
  return TerrainTruth(s, vehicle, Eigen::AlignedBox2d(Eigen::Vector2d(-5, -5), Eigen::Vector2d(15, 5)));
}

TEST(TerrainTruth, ATerraceIsLevelGroundInsideAndABandOfStepAroundItsEdge) {
  Scene s;
  s.obstacles.push_back(Box(5, 0, 1.5, 1.5, 0.4));  // 3 x 3 m, 0.4 m high: edges at x = 3.5, 6.5
  s.Finish();
  const TerrainTruth t = TruthOf(s);
  EXPECT_EQ(t.ClassAt(5.0, 0.0), kTrav);    // the middle of the terrace, 0.4 m up
  EXPECT_EQ(t.ClassAt(3.6, 0.0), kNon);     // on top, 0.1 m from the edge
  EXPECT_EQ(t.ClassAt(3.4, 0.0), kNon);     // at its foot, 0.1 m from the face
  EXPECT_EQ(t.ClassAt(3.0, 0.0), kTrav);    // 0.5 m from it
  EXPECT_NEAR(t.StepAt(3.45, 0.0), 0.4, 1e-6);
  EXPECT_NEAR(t.StepAt(5.0, 0.0), 0.0, 1e-6);
  EXPECT_EQ(t.ClassAt(3.0 + 0.5 + 0.2 + 2 * t.resolution_m(), 0.0), kTrav);  // just beyond the band
}

TEST(TerrainTruth, ADropOffsFloorIsTraversableAwayFromItsLipAndFoot) {
  Scene s;
  s.pits.push_back({15.0, 0.0, 0.0, 10.0, 10.0, 1.0});  // the ground ends at x = 5, 1 m down
  s.Finish();
  const TerrainTruth t = TruthOf(s);
  EXPECT_EQ(t.ClassAt(4.0, 0.0), kTrav);   // before the lip
  EXPECT_EQ(t.ClassAt(4.9, 0.0), kNon);    // the lip
  EXPECT_EQ(t.ClassAt(5.1, 0.0), kNon);    // the foot, 1 m below
  EXPECT_EQ(t.ClassAt(6.0, 0.0), kTrav);   // the lower level's floor
  EXPECT_NEAR(t.StepAt(6.0, 0.0), 0.0, 1e-6);
}

TEST(TerrainTruth, AFiveCentimetreCurbAndItsFaceAreTraversable) {
  Scene s;
  s.obstacles.push_back(Box(5, 0, 0.15, 1.0, 0.05));
  s.Finish();
  const TerrainTruth t = TruthOf(s);
  EXPECT_EQ(t.ClassAt(5.0, 0.0), kTrav);
  EXPECT_EQ(t.ClassAt(4.9, 0.0), kTrav);
  const SurfaceHit face = s.CastRay({0.0, 0.0, 0.02}, {1, 0, 0}, 10);
  ASSERT_TRUE(face.hit);
  EXPECT_NEAR(face.p_world.x(), 4.85, 1e-9);
  EXPECT_EQ(t.ClassOf(face), kTrav);  // a face is as bad as the jump it spans
  // The same face on a 0.15 m curb spans a semi-traversable jump.
  Scene higher;
  higher.obstacles.push_back(Box(5, 0, 0.15, 1.0, 0.15));
  higher.Finish();
  EXPECT_EQ(TruthOf(higher).ClassOf(higher.CastRay({0.0, 0.0, 0.05}, {1, 0, 0}, 10)), kSemi);
}

TEST(TerrainTruth, ANarrowTallRockIsNonTraversableWholeAndSoIsTheGroundAroundIt) {
  Scene s;
  Obstacle rock;
  rock.shape = Obstacle::Shape::kEllipsoid;
  rock.x = 5;
  rock.a = rock.b = 0.15;  // narrower than twice the step radius
  rock.c = 0.3;
  rock.z_min = -0.3;
  rock.z_max = 0.3;
  s.obstacles.push_back(rock);
  s.Finish();
  const TerrainTruth t = TruthOf(s);
  EXPECT_EQ(t.ClassAt(5.0, 0.0), kNon);   // its top
  EXPECT_EQ(t.ClassAt(5.25, 0.0), kNon);  // the ground within 0.2 m of it
  EXPECT_EQ(t.ClassAt(5.5, 0.0), kTrav);  // 0.35 m from it
}

TEST(TerrainTruth, ARampsFlankIsJudgedBySlopeAndItsPlateauIsLevelGround) {
  Scene s;
  s.ramps.push_back({5.0, 0.0, 0.0, 1.5, 1.5, 0.6, 20.0});  // 20 deg flanks up to a 3 x 3 m top
  s.Finish();
  const TerrainTruth t = TruthOf(s);
  const double foot = 5.0 - 1.5 - 0.6 / std::tan(DegToRad(20.0));
  EXPECT_EQ(t.ClassAt(foot + 0.8, 0.0), kSemi);  // on the flank: 20 deg, no step
  EXPECT_LT(t.StepAt(foot + 0.8, 0.0), 0.01);
  EXPECT_EQ(t.ClassAt(5.0, 0.0), kTrav);         // the plateau, 0.6 m up
  EXPECT_EQ(t.ClassAt(foot - 0.5, 0.0), kTrav);  // the ground before it
}

TEST(SynthGroundTruth, WarpingRightImageWithGtDisparityReproducesLeft) {
  TempDir tmp;
  const SynthOptions o = SmallOptions("yard", 2);
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const std::vector<std::string> names = FrameNames(tmp.Sub("seq/cam0/data.csv"));
  ASSERT_EQ(names.size(), 2u);
  for (const std::string& name : names) {
    const ImageU8 left = ReadGreyImage(tmp.Sub("seq/cam0/data/" + name));
    const ImageU8 right = ReadGreyImage(tmp.Sub("seq/cam1/data/" + name));
    const ImageU8 labels = ReadLabelImage(tmp.Sub("seq/gt/labels/" + name));
    const ImageU16 disparity = ReadImageU16(tmp.Sub("seq/gt/disparity/" + name));
    ASSERT_EQ(left.width(), 320);
    double sum = 0;
    int count = 0, close = 0;
    for (int v = 0; v < left.height(); ++v) {
      for (int u = 0; u < left.width(); ++u) {
        if (labels(v, u) == kDontCare || disparity(v, u) == 0) continue;
        const double ur = u - disparity(v, u) / 256.0;
        const int u0 = static_cast<int>(std::floor(ur));
        if (u0 < 0 || u0 + 1 >= right.width()) continue;
        const double a = ur - u0;
        const double r = (1 - a) * right(v, u0) + a * right(v, u0 + 1);
        const double diff = std::abs(r - left(v, u));
        sum += diff;
        ++count;
        close += diff <= 8 ? 1 : 0;
      }
    }
    ASSERT_GT(count, left.width() * left.height() / 3);
    const double mean = sum / count, fraction = static_cast<double>(close) / count;
    std::cout << "warp " << name << ": mean |L - warped R| " << mean << " grey, within 8: "
              << fraction << " of " << count << " px\n";
    EXPECT_LT(mean, 2.5);  // two images with 1.5 grey-level noise each: about 1.7 expected
    EXPECT_GT(fraction, 0.98);
  }
}

TEST(SynthGroundTruth, PlaneDisparityMatchesClosedForm) {
  // On a planar ramp the vehicle sits on the plane, so every ground pixel's disparity is
  // f b (y cos(pitch) + sin(pitch)) / h with y = (v - cv) / f, h the camera height above it.
  for (double slope : {0.0, 20.0}) {
    TempDir tmp;
    SynthOptions o = SmallOptions("ramp", 1);
    o.ramp_slope_deg = slope;
    WriteSyntheticSequence(o, tmp.Sub("seq"));
    const std::string name = FrameNames(tmp.Sub("seq/cam0/data.csv")).at(0);
    const ImageU16 disparity = ReadImageU16(tmp.Sub("seq/gt/disparity/" + name));
    const double f = o.rig.focal_px, cv = 0.5 * (o.rig.height - 1), p = o.rig.pitch_down_deg * kDeg;
    double worst = 0;
    int valid = 0;
    for (int v = 0; v < disparity.height(); ++v) {
      for (int u = 0; u < disparity.width(); ++u) {
        if (disparity(v, u) == 0) continue;
        const double y = (v - cv) / f;
        const double expected = f * o.rig.baseline_m * (y * std::cos(p) + std::sin(p)) / o.rig.camera_height_m;
        worst = std::max(worst, std::abs(disparity(v, u) / 256.0 - expected));
        ++valid;
      }
    }
    std::cout << "ramp " << slope << " deg: worst disparity error " << worst << " px over " << valid
              << " px\n";
    EXPECT_GT(valid, disparity.width() * disparity.height() / 2);
    EXPECT_LT(worst, 0.01);
  }
}

TEST(SynthGroundTruth, Pose0AndExtrinsicsPutGtDepthOnTheSurface) {
  // Back-project every labelled pixel with its gt disparity, move it into the world with the
  // files alone (pose0 at the frame time, gt/extrinsics.yaml), and compare with the scene's
  // top surface there: this ties images, poses and calibration to one world.
  TempDir tmp;
  const SynthOptions o = SmallOptions("yard", 3);
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const Scene scene = MakeScene("yard", o.seed);
  const CameraCalibration cam = LoadCameraCalibration(tmp.Sub("seq/gt/extrinsics.yaml"));
  const auto pose = ReadCsv(tmp.Sub("seq/pose0/data.csv"));
  std::istringstream csv(ReadTextFile(tmp.Sub("seq/cam0/data.csv")));
  std::string line;
  int frames = 0;
  while (std::getline(csv, line)) {
    if (line.empty() || line[0] == '#') continue;
    const long long ns = std::stoll(line.substr(0, line.find(',')));
    const std::string name = line.substr(line.find(',') + 1);
    // pose0 runs at 200 Hz; interpolate linearly / slerp to the frame time.
    std::size_t k = 0;
    while (k + 2 < pose.size() && pose[k + 1][0] <= static_cast<double>(ns)) ++k;
    const double a = (static_cast<double>(ns) - pose[k][0]) / (pose[k + 1][0] - pose[k][0]);
    const Eigen::Quaterniond q0(pose[k][4], pose[k][5], pose[k][6], pose[k][7]);
    const Eigen::Quaterniond q1(pose[k + 1][4], pose[k + 1][5], pose[k + 1][6], pose[k + 1][7]);
    Eigen::Isometry3d world_T_body = Eigen::Isometry3d::Identity();
    world_T_body.linear() = q0.normalized().slerp(a, q1.normalized()).toRotationMatrix();
    for (int i = 0; i < 3; ++i) world_T_body.translation()[i] = (1 - a) * pose[k][1 + i] + a * pose[k + 1][1 + i];
    const Eigen::Isometry3d world_T_cam = world_T_body * cam.body_T_camera;

    const ImageU8 labels = ReadLabelImage(tmp.Sub("seq/gt/labels/" + name));
    const ImageU16 disparity = ReadImageU16(tmp.Sub("seq/gt/disparity/" + name));
    std::vector<double> errors;
    for (int v = 0; v < labels.height(); ++v) {
      for (int u = 0; u < labels.width(); ++u) {
        if (labels(v, u) == kDontCare || disparity(v, u) == 0) continue;
        const double z = cam.fu * o.rig.baseline_m / (disparity(v, u) / 256.0);
        const Eigen::Vector3d p_cam((u - cam.cu) / cam.fu * z, (v - cam.cv) / cam.fv * z, z);
        const Eigen::Vector3d p = world_T_cam * p_cam;
        const SurfaceHit top = scene.CastRay({p.x(), p.y(), p.z() + 5.0}, {0, 0, -1}, 20.0);
        ASSERT_TRUE(top.hit);
        // On walls the vertical ray meets the top instead: compare only where it is the same
        // surface seen from above (not steeper than 60 degrees).
        if (top.normal_world.z() < 0.5) continue;
        errors.push_back(std::abs(top.p_world.z() - p.z()));
      }
    }
    ASSERT_GT(errors.size(), labels.size() / 3);
    std::sort(errors.begin(), errors.end());
    const double median = errors[errors.size() / 2], p95 = errors[errors.size() * 95 / 100];
    std::cout << name << ": height error of back-projected gt points, median " << median
              << " m, 95th percentile " << p95 << " m over " << errors.size() << " px\n";
    EXPECT_LT(median, 0.001);  // disparity is stored in 1/256 px steps
    EXPECT_LT(p95, 0.005);
    ++frames;
  }
  EXPECT_EQ(frames, 3);
}

TEST(SynthOptions, DefaultRigSuitsTheDefaultStereoRange) {
  // Flat ground seen by the default rig: the bottom row has the largest ground disparity,
  // which must stay below the default 64-disparity search range; the horizon must be in view.
  const RigOptions rig;
  const double p = rig.pitch_down_deg * kDeg;
  const double y_bottom = 0.5 * (rig.height - 1) / rig.focal_px;
  const double d_max = rig.focal_px * rig.baseline_m * (y_bottom * std::cos(p) + std::sin(p)) / rig.camera_height_m;
  const double horizon_row = 0.5 * (rig.height - 1) - rig.focal_px * std::tan(p);
  std::cout << "default rig: largest ground disparity " << d_max << " px, horizon at row " << horizon_row << "\n";
  EXPECT_LT(d_max, 60.0);
  EXPECT_GT(d_max, 40.0);
  EXPECT_GT(horizon_row, 0.1 * rig.height);
  EXPECT_LT(horizon_row, 0.4 * rig.height);
}

TEST(SynthGroundTruth, RampLabelsEqualClosedFormClass) {
  const VehicleOptions vehicle;  // semi 15 deg, max 25 deg
  const std::pair<double, TravClass> cases[] = {{10.0, TravClass::kTraversable},
                                                {20.0, TravClass::kSemiTraversable},
                                                {30.0, TravClass::kNonTraversable}};
  for (const auto& [slope, expected] : cases) {
    TempDir tmp;
    SynthOptions o = SmallOptions("ramp", 1);
    o.ramp_slope_deg = slope;
    WriteSyntheticSequence(o, tmp.Sub("seq"));
    const std::string name = FrameNames(tmp.Sub("seq/cam0/data.csv")).at(0);
    const ImageU8 labels = ReadLabelImage(tmp.Sub("seq/gt/labels/" + name));
    int labelled = 0, right = 0;
    for (std::size_t i = 0; i < labels.size(); ++i) {
      if (labels[i] == kDontCare) continue;
      ++labelled;
      right += labels[i] == static_cast<std::uint8_t>(expected) ? 1 : 0;
    }
    std::cout << "ramp " << slope << " deg: " << right << " of " << labelled << " labelled px\n";
    EXPECT_GT(labelled, static_cast<int>(labels.size()) / 3);
    EXPECT_EQ(right, labelled);
    // The world grid agrees.
    const ImageU8 grid = ReadLabelImage(tmp.Sub("seq/gt/grid_classes.png"));
    int grid_right = 0;
    for (std::size_t i = 0; i < grid.size(); ++i) grid_right += grid[i] == static_cast<std::uint8_t>(expected);
    EXPECT_EQ(grid_right, static_cast<int>(grid.size()));
  }
}

TEST(SynthGroundTruth, YardGridClassesAtKnownPlaces) {
  TempDir tmp;
  SynthOptions o = SmallOptions("yard", 1);
  o.rig.width = 64;
  o.rig.height = 48;
  o.rig.focal_px = 42;
  o.grid_resolution_m = 0.1;
  o.render.max_label_range_m = 20.0;  // the grid spans the label range: reach the 0.30 m step at 12.5 m
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const ImageU8 grid = ReadLabelImage(tmp.Sub("seq/gt/grid_classes.png"));
  const std::string yaml = ReadTextFile(tmp.Sub("seq/gt/grid.yaml"));
  const auto at = yaml.find("origin: [");
  ASSERT_NE(at, std::string::npos);
  double x0 = 0, y0 = 0;
  ASSERT_EQ(std::sscanf(yaml.c_str() + at, "origin: [%lf, %lf", &x0, &y0), 2);
  EXPECT_NE(yaml.find("resolution: 0.1"), std::string::npos);
  EXPECT_NE(yaml.find("image: grid_classes.png"), std::string::npos);
  EXPECT_NE(yaml.find(std::string("\nseen: ") + kTruthSeenBothCameras + "\n"), std::string::npos);
  auto class_at = [&](double x, double y) {
    const int col = static_cast<int>(std::floor((x - x0) / 0.1));
    const int row = grid.height() - 1 - static_cast<int>(std::floor((y - y0) / 0.1));
    return static_cast<TravClass>(grid(row, col));
  };
  EXPECT_EQ(class_at(0.0, 0.0), TravClass::kTraversable);           // the start
  EXPECT_EQ(class_at(4.0, 2.0), TravClass::kTraversable);           // top of the 0.05 m curb
  EXPECT_EQ(class_at(4.5, -1.8), TravClass::kSemiTraversable);      // top of the 0.15 m curb
  EXPECT_EQ(class_at(12.5, 4.2), TravClass::kTraversable);          // middle of the 0.30 m terrace
  EXPECT_EQ(class_at(12.5, 4.2 + 1.0 - 0.05), TravClass::kNonTraversable);  // its edge
  EXPECT_EQ(class_at(12.5, 4.2 + 1.0 + 0.05), TravClass::kNonTraversable);  // the ground at its foot
  EXPECT_EQ(class_at(8.0, -0.6), TravClass::kTraversable);          // the middle of the crate's top
  EXPECT_EQ(class_at(8.0 + 0.25, -0.6), TravClass::kNonTraversable);  // near its edge
  EXPECT_EQ(class_at(8.0, 4.6 - 0.6 - 0.6), TravClass::kTraversable);  // 8 deg ramp flank
  EXPECT_EQ(class_at(8.0, 4.6), TravClass::kTraversable);           // its flat top
}

TEST(SynthCli, AnAddedBoxStandsInTheTruthAndIsListed) {
  const std::string binary = SSTA_BINARY;
  TempDir tmp;
  const std::string log = " > " + tmp.Sub("log.txt") + " 2>&1";
  // A 0.6 m crate, 0.5 m tall, on the open yard 4 m ahead: ground before, an obstacle after.
  const std::string common = " synth --scene yard --frames 1 --width 64 --height 48 --focal 42 --grid-all-cells --max-label-range 8 --out ";
  ASSERT_EQ(std::system((binary + common + tmp.Sub("bare") + log).c_str()), 0) << ReadTextFile(tmp.Sub("log.txt"));
  ASSERT_EQ(std::system((binary + common + tmp.Sub("box") + " --add-box 4.0,0.6,0.6,0.6,0.5,30" + log).c_str()), 0)
      << ReadTextFile(tmp.Sub("log.txt"));
  auto class_at = [&](const std::string& seq, double x, double y) {
    const ImageU8 grid = ReadLabelImage(seq + "/gt/grid_classes.png");
    const std::string yaml = ReadTextFile(seq + "/gt/grid.yaml");
    double x0 = 0, y0 = 0, r = 0;
    EXPECT_EQ(std::sscanf(yaml.c_str() + yaml.find("resolution: "), "resolution: %lf", &r), 1);
    EXPECT_EQ(std::sscanf(yaml.c_str() + yaml.find("origin: ["), "origin: [%lf, %lf", &x0, &y0), 2);
    const int col = static_cast<int>(std::floor((x - x0) / r));
    const int row = grid.height() - 1 - static_cast<int>(std::floor((y - y0) / r));
    return static_cast<TravClass>(grid(row, col));
  };
  EXPECT_EQ(class_at(tmp.Sub("bare"), 4.0, 0.6), TravClass::kTraversable);
  EXPECT_EQ(class_at(tmp.Sub("box"), 4.0, 0.6 + 0.25), TravClass::kNonTraversable);  // near its edge
  EXPECT_EQ(class_at(tmp.Sub("box"), 4.0, -0.5), TravClass::kTraversable);  // beside it
  EXPECT_NE(ReadTextFile(tmp.Sub("box/gt/rig.yaml")).find("added_boxes: [[4, 0.6, 0.6, 0.6, 0.5, 30]]"),
            std::string::npos)
      << ReadTextFile(tmp.Sub("box/gt/rig.yaml"));
  EXPECT_NE(std::system((binary + common + tmp.Sub("bad") + " --add-box 4,0.6,0.6" + log).c_str()), 0);
  EXPECT_NE(ReadTextFile(tmp.Sub("log.txt")).find("ssta: error: --add-box: expected X,Y,LENGTH,WIDTH,HEIGHT[,YAW_DEG]"),
            std::string::npos)
      << ReadTextFile(tmp.Sub("log.txt"));
  EXPECT_NE(std::system((binary + common + tmp.Sub("bad") + " --add-box 4,0.6,0.6,0.6,-1" + log).c_str()), 0);
  EXPECT_NE(ReadTextFile(tmp.Sub("log.txt")).find("ssta: error: --add-box: height must be in (0, 20] m"),
            std::string::npos)
      << ReadTextFile(tmp.Sub("log.txt"));
}

TEST(SynthGroundTruth, GridScoresOnlyCellsTheCamerasSaw) {
  TempDir tmp;
  SynthOptions o = SmallOptions("ramp", 2);
  o.ramp_slope_deg = 10.0;
  o.grid_seen_only = true;
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const ImageU8 grid = ReadLabelImage(tmp.Sub("seq/gt/grid_classes.png"));
  const std::string yaml = ReadTextFile(tmp.Sub("seq/gt/grid.yaml"));
  double x0 = 0, y0 = 0;
  ASSERT_EQ(std::sscanf(yaml.c_str() + yaml.find("origin: ["), "origin: [%lf, %lf", &x0, &y0), 2);
  auto class_at = [&](double x, double y) {
    const int col = static_cast<int>(std::floor((x - x0) / 0.25));
    const int row = grid.height() - 1 - static_cast<int>(std::floor((y - y0) / 0.25));
    return grid(row, col);
  };
  EXPECT_EQ(class_at(-3.0, 0.0), kDontCare);  // behind the start: never in view
  EXPECT_EQ(class_at(4.0, 0.0), static_cast<std::uint8_t>(TravClass::kTraversable));  // ahead
  int seen = 0, dont_care = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    seen += grid[i] == static_cast<std::uint8_t>(TravClass::kTraversable);
    dont_care += grid[i] == kDontCare;
  }
  EXPECT_GT(seen, 50);
  EXPECT_GT(dont_care, seen);  // the grid spans the label range around the whole path
}

TEST(SynthGroundTruth, GridScoresTheCellsBesideObstaclesWhateverTheLabelBand) {
  // The labels leave a don't-care band along every class change; the grid takes its classes
  // from the world, so a wide band must not unscore the cells at a crate's foot.
  auto grid_for_band = [](int band, const std::string& dir) {
    SynthOptions o = SmallOptions("ramp", 1);
    o.ramp_slope_deg = 0.0;
    o.grid_seen_only = true;
    o.render.boundary_band_px = band;
    o.added_boxes.push_back({4.0, 0.0, 0.6, 0.6, 0.5, 0.0});
    WriteSyntheticSequence(o, dir);
    return ReadLabelImage(dir + "/gt/grid_classes.png");
  };
  TempDir tmp;
  const ImageU8 narrow = grid_for_band(0, tmp.Sub("band0"));
  const ImageU8 wide = grid_for_band(6, tmp.Sub("band6"));
  ASSERT_EQ(narrow.size(), wide.size());
  int red = 0, differ = 0;
  for (std::size_t i = 0; i < narrow.size(); ++i) {
    red += narrow[i] == static_cast<std::uint8_t>(TravClass::kNonTraversable);
    differ += narrow[i] != wide[i];
  }
  EXPECT_GT(red, 8);  // the crate's seen faces and the ring at its foot (0.25 m cells)
  EXPECT_EQ(differ, 0);
}

TEST(SynthMotion, ImuIntegratesBackToPose) {
  TempDir tmp;
  SynthOptions o = SmallOptions("hills", 31);  // 2 s of driving over rolling hills
  o.rig.width = 32;
  o.rig.height = 24;
  o.rig.focal_px = 21;
  o.grid_resolution_m = 1.0;
  o.motion.weave_amplitude_m = 0.4;
  o.motion.weave_period_s = 3.0;
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const auto imu = ReadCsv(tmp.Sub("seq/imu0/data.csv"));
  const auto pose = ReadCsv(tmp.Sub("seq/pose0/data.csv"));
  ASSERT_EQ(imu.size(), pose.size());
  ASSERT_GT(imu.size(), 400u);
  const double dt = 1.0 / o.motion.imu_rate_hz;
  auto position = [&](std::size_t k) { return Eigen::Vector3d(pose[k][1], pose[k][2], pose[k][3]); };
  auto rotation = [&](std::size_t k) {
    return Eigen::Quaterniond(pose[k][4], pose[k][5], pose[k][6], pose[k][7]).normalized().toRotationMatrix();
  };
  Eigen::Matrix3d r = rotation(0);
  Eigen::Vector3d p = position(0);
  Eigen::Vector3d v = (-3 * position(0) + 4 * position(1) - position(2)) / (2 * dt);
  double worst_angle_deg = 0, worst_position_m = 0;
  for (std::size_t k = 0; k + 1 < imu.size(); ++k) {
    const Eigen::Vector3d w0(imu[k][1], imu[k][2], imu[k][3]), w1(imu[k + 1][1], imu[k + 1][2], imu[k + 1][3]);
    const Eigen::Vector3d f0(imu[k][4], imu[k][5], imu[k][6]), f1(imu[k + 1][4], imu[k + 1][5], imu[k + 1][6]);
    const Eigen::Vector3d a0 = r * f0 + kGravityWorld;
    const Eigen::Matrix3d r1 = r * Exp(0.5 * (w0 + w1) * dt);
    const Eigen::Vector3d a1 = r1 * f1 + kGravityWorld;
    const Eigen::Vector3d v1 = v + 0.5 * (a0 + a1) * dt;
    p += 0.5 * (v + v1) * dt;
    v = v1;
    r = r1;
    worst_angle_deg = std::max(worst_angle_deg,
                               Eigen::AngleAxisd(r.transpose() * rotation(k + 1)).angle() / kDeg);
    worst_position_m = std::max(worst_position_m, (p - position(k + 1)).norm());
  }
  const double travelled = (position(imu.size() - 1) - position(0)).norm();
  std::cout << "IMU dead reckoning over " << imu.size() * dt << " s, " << travelled
            << " m: worst rotation error " << worst_angle_deg << " deg, worst position error "
            << worst_position_m << " m\n";
  EXPECT_GT(travelled, 1.8);
  EXPECT_LT(worst_angle_deg, 0.01);
  EXPECT_LT(worst_position_m, 0.002);
}

TEST(SynthMotion, ImuAtRestReadsGravityAlongBodyUp) {
  for (double slope : {0.0, 20.0}) {
    const Scene scene = MakeScene("ramp", 1, slope);
    MotionOptions still;
    still.speed_mps = 0;
    still.weave_amplitude_m = 0;
    const VehicleTrajectory trajectory(scene, still);
    const ImuSample s = trajectory.Imu(1.0);
    EXPECT_NEAR(s.gyro_rad_s.norm(), 0.0, 1e-9);
    EXPECT_NEAR(s.accel_m_s2.z(), 9.81 * std::cos(slope * kDeg), 1e-6);
    EXPECT_NEAR(s.accel_m_s2.x(), 9.81 * std::sin(slope * kDeg), 1e-6);  // nose up the ramp
    EXPECT_NEAR(s.accel_m_s2.y(), 0.0, 1e-6);
  }
}

std::string FileBytes(const std::string& path) { return ReadTextFile(path); }

TEST(SynthDeterminism, SameSeedSameBytesOtherSeedOtherScene) {
  TempDir tmp;
  SynthOptions o = SmallOptions("yard", 2);
  o.rig.width = 160;
  o.rig.height = 120;
  o.rig.focal_px = 105;
  o.faults.imu_gyro_noise = 0.01;
  o.render.threads = 1;
  WriteSyntheticSequence(o, tmp.Sub("a"));
  o.render.threads = 3;  // the thread count must not change a byte
  WriteSyntheticSequence(o, tmp.Sub("b"));
  o.seed = 2;
  WriteSyntheticSequence(o, tmp.Sub("c"));
  const std::vector<std::string> names = FrameNames(tmp.Sub("a/cam0/data.csv"));
  for (const std::string& file :
       {"cam0/data/" + names[1], "cam1/data/" + names[1], "gt/labels/" + names[1],
        "gt/disparity/" + names[1], std::string("imu0/data.csv"), std::string("pose0/data.csv"),
        std::string("gt/grid_classes.png")}) {
    EXPECT_EQ(FileBytes(tmp.Sub("a/" + file)), FileBytes(tmp.Sub("b/" + file))) << file;
  }
  EXPECT_NE(FileBytes(tmp.Sub("a/cam0/data/" + names[1])), FileBytes(tmp.Sub("c/cam0/data/" + names[1])));
  EXPECT_NE(FileBytes(tmp.Sub("a/gt/grid_classes.png")), FileBytes(tmp.Sub("c/gt/grid_classes.png")));
  EXPECT_NE(FileBytes(tmp.Sub("a/imu0/data.csv")), FileBytes(tmp.Sub("c/imu0/data.csv")));
}

TEST(SynthFaults, MountErrorRotatesSensorYamlButNotTheTruth) {
  TempDir tmp;
  SynthOptions o = SmallOptions("yard", 3);
  o.rig.width = 64;
  o.rig.height = 48;
  o.rig.focal_px = 42;
  o.grid_resolution_m = 1.0;
  o.faults.mount_pitch_error_deg = 2.0;
  o.faults.mount_roll_error_deg = -1.0;
  o.faults.drop_frame_indices = {1};
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const CameraCalibration written = LoadCameraCalibration(tmp.Sub("seq/cam0/sensor.yaml"));
  const CameraCalibration truth = LoadCameraCalibration(tmp.Sub("seq/gt/extrinsics.yaml"));
  const StereoCalibration pair =
      LoadStereoCalibration(tmp.Sub("seq/cam0/sensor.yaml"), tmp.Sub("seq/cam1/sensor.yaml"));
  const Eigen::Matrix3d r_err = written.body_T_camera.linear() * truth.body_T_camera.linear().transpose();
  const Eigen::Matrix3d expected = (Eigen::AngleAxisd(2.0 * kDeg, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(-1.0 * kDeg, Eigen::Vector3d::UnitX())).toRotationMatrix();
  EXPECT_LT((r_err - expected).norm(), 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(r_err).angle() / kDeg, std::hypot(2.0, 1.0), 1e-3);
  EXPECT_LT((written.body_T_camera.translation() - truth.body_T_camera.translation()).norm(), 1e-12);
  EXPECT_TRUE(pair.IsRectified());  // the rig stays rigid
  EXPECT_NEAR(pair.LeftTRight().translation().x(), o.rig.baseline_m, 1e-12);
  const Eigen::Isometry3d true_mount = TrueBodyTCam0(o.rig, o.motion);
  EXPECT_LT((truth.body_T_camera.matrix() - true_mount.matrix()).norm(), 1e-12);

  const std::string faults = ReadTextFile(tmp.Sub("seq/gt/faults.yaml"));
  EXPECT_NE(faults.find("mount_pitch_error_deg: 2\n"), std::string::npos);
  EXPECT_NE(faults.find("mount_roll_error_deg: -1\n"), std::string::npos);
  const std::vector<std::string> left = FrameNames(tmp.Sub("seq/cam0/data.csv"));
  const std::vector<std::string> right = FrameNames(tmp.Sub("seq/cam1/data.csv"));
  ASSERT_EQ(left.size(), 3u);
  ASSERT_EQ(right.size(), 2u);
  EXPECT_FALSE(fs::exists(tmp.Sub("seq/cam1/data/" + left[1])));
  EXPECT_NE(faults.find("dropped_frames: [" + left[1].substr(0, left[1].size() - 4) + "]"),
            std::string::npos);
}

TEST(SynthFaults, WithoutFaultsSensorYamlIsTheTruth) {
  TempDir tmp;
  SynthOptions o = SmallOptions("yard", 1);
  o.rig.width = 64;
  o.rig.height = 48;
  o.rig.focal_px = 42;
  o.grid_resolution_m = 1.0;
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const CameraCalibration written = LoadCameraCalibration(tmp.Sub("seq/cam0/sensor.yaml"));
  const CameraCalibration truth = LoadCameraCalibration(tmp.Sub("seq/gt/extrinsics.yaml"));
  EXPECT_LT((written.body_T_camera.matrix() - truth.body_T_camera.matrix()).norm(), 1e-15);
  EXPECT_DOUBLE_EQ(written.fu, 42.0);
  EXPECT_DOUBLE_EQ(written.cu, 31.5);
}

TEST(SynthFaults, PoseDriftTiltsPose0Linearly) {
  TempDir tmp;
  SynthOptions o = SmallOptions("ramp", 2);
  o.ramp_slope_deg = 0;
  o.rig.width = 32;
  o.rig.height = 24;
  o.rig.focal_px = 21;
  o.grid_resolution_m = 1.0;
  o.motion.weave_amplitude_m = 0;
  o.faults.pose_drift_roll_deg_per_s = 1.0;
  o.faults.pose_drift_pitch_deg_per_s = -2.0;
  WriteSyntheticSequence(o, tmp.Sub("seq"));
  const auto pose = ReadCsv(tmp.Sub("seq/pose0/data.csv"));
  const auto imu = ReadCsv(tmp.Sub("seq/imu0/data.csv"));
  const auto& last = pose.back();
  const double t = (last[0] - pose.front()[0]) * 1e-9;
  const Eigen::Matrix3d r = Eigen::Quaterniond(last[4], last[5], last[6], last[7]).toRotationMatrix();
  EXPECT_NEAR(std::atan2(r(2, 1), r(2, 2)) / kDeg, 1.0 * t, 1e-6);   // roll
  EXPECT_NEAR(std::asin(-r(2, 0)) / kDeg, -2.0 * t, 1e-6);           // pitch
  EXPECT_NEAR(imu.back()[6], 9.81, 1e-6);                             // the IMU stays true
}

TEST(SynthOptions, IsValidNamesTheOffendingOption) {
  SynthOptions o;
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.frames = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("frames:", 0), 0u) << error;
  o = SynthOptions();
  o.rig.focal_px = -1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("rig.focal_px:", 0), 0u) << error;
  o = SynthOptions();
  o.scene = "moon";
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("scene:", 0), 0u) << error;
  o = SynthOptions();
  o.vehicle.semi_slope_deg = 40;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("vehicle.semi_slope_deg:", 0), 0u) << error;
  TempDir tmp;
  EXPECT_THROW(WriteSyntheticSequence(o, tmp.Sub("seq")), Error);
}

}  // namespace
}  // namespace ssta::synth

namespace ssta::synth {
namespace {

TEST(SynthCli, WritesASequenceAndRejectsBadOptions) {
  const std::string binary = SSTA_BINARY;
  TempDir tmp;
  const std::string out = tmp.Sub("seq");
  const std::string common = " synth --width 64 --height 48 --focal 42 --grid-resolution 1";
  const std::string log = " > " + tmp.Sub("log.txt") + " 2>&1";
  EXPECT_EQ(std::system((binary + common + " --scene forest --frames 4 --drop-frames 1,2 --out " + out + log).c_str()), 0)
      << ReadTextFile(tmp.Sub("log.txt"));
  EXPECT_EQ(FrameNames(out + "/cam0/data.csv").size(), 4u);
  EXPECT_EQ(FrameNames(out + "/cam1/data.csv").size(), 2u);
  for (const char* file : {"/vehicle.yaml", "/imu0/sensor.yaml", "/gt/grid.yaml", "/gt/grid_classes.png",
                           "/gt/extrinsics.yaml", "/gt/faults.yaml", "/pose0/data.csv"}) {
    EXPECT_TRUE(fs::exists(out + file)) << file;
  }
  // A shorter run into the same folder leaves none of the longer run's frames to be scored.
  EXPECT_EQ(std::system((binary + common + " --scene forest --frames 2 --out " + out + log).c_str()), 0)
      << ReadTextFile(tmp.Sub("log.txt"));
  // 4 cam0 images, 2 cam1 (two dropped), 4 label and 4 disparity images.
  EXPECT_NE(ReadTextFile(tmp.Sub("log.txt")).find("removed 14 frame files of an earlier run"), std::string::npos)
      << ReadTextFile(tmp.Sub("log.txt"));
  for (const char* dir : {"/cam0/data", "/cam1/data", "/gt/labels", "/gt/disparity"}) {
    int files = 0;
    for (const auto& e : fs::directory_iterator(out + dir)) files += e.is_regular_file() ? 1 : 0;
    EXPECT_EQ(files, 2) << dir;
  }
  // A recorded sequence (data.csv, no gt/) is not overwritten.
  const std::string recorded = tmp.Sub("recorded");
  fs::create_directories(recorded + "/cam0/data");
  std::ofstream(recorded + "/cam0/data.csv") << "#timestamp [ns],filename\n";
  std::ofstream(recorded + "/cam0/data/1.png") << "x";
  EXPECT_NE(std::system((binary + common + " --frames 1 --out " + recorded + log).c_str()), 0);
  EXPECT_NE(ReadTextFile(tmp.Sub("log.txt")).find(recorded + ": holds a recorded sequence"), std::string::npos)
      << ReadTextFile(tmp.Sub("log.txt"));
  EXPECT_TRUE(fs::exists(recorded + "/cam0/data/1.png"));
  EXPECT_NE(std::system((binary + common + " --scene moon --out " + tmp.Sub("bad") + log).c_str()), 0);
  EXPECT_NE(ReadTextFile(tmp.Sub("log.txt")).find("--scene: unknown scene 'moon'"), std::string::npos);
  // A bad value names the option the user typed, not the key behind it.
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {" --width 0", "ssta: error: --width: must be in [16, 8192] px"},
           {" --speed nan", "ssta: error: --speed:"},
           {" --frames 0", "ssta: error: --frames: must be in [1, 100000]"},
           {" --frames 2 --drop-frames 5", "ssta: error: --drop-frames: frame index 5 is not below frames"},
           {" --mount-pitch-error-deg 50", "ssta: error: --mount-pitch-error-deg: must be within +-30 degrees"}}) {
    EXPECT_NE(std::system((binary + " synth" + args + " --out " + tmp.Sub("bad") + log).c_str()), 0) << args;
    EXPECT_EQ(ReadTextFile(tmp.Sub("log.txt")).rfind(expected, 0), 0u) << ReadTextFile(tmp.Sub("log.txt"));
  }
  EXPECT_FALSE(fs::exists(tmp.Sub("bad/cam0"))) << "a bad option must stop synth before it writes";
  EXPECT_NE(std::system((binary + common + " --drop-frames 0.x --out " + tmp.Sub("bad") + log).c_str()), 0);
  EXPECT_NE(ReadTextFile(tmp.Sub("log.txt")).find("--drop-frames"), std::string::npos);
}

}  // namespace
}  // namespace ssta::synth
