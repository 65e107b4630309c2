// What a planner is told: obstacles the frames saw survive fusion, stereo noise at range does
// not block open ground, and lips whose foot no frame sees are found. Analytic worlds whose
// answers are known by construction.

#include <cmath>
#include <type_traits>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "map_test_util.h"
#include "analysis/hidden_drops.h"
#include "ssta/core/units.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta {
namespace {

using internal::FindFramesHiddenDrops;
using internal::FindHiddenDrops;
using testing::C;

/// The rock: columns on x, y in [1.8, 2.2), whose top no camera sees.
bool Rock(int ix, int iy) { return ix >= 18 && ix < 22 && iy >= 18 && iy < 22; }

/// A level floor at z = 0 over x, y in [0, 4) m around the rock, one point per 0.1 m voxel at
/// its centre height 0 (`height(ix, iy)` where given), every point with height sigma `sigma_m`
/// (horizontal 0.01 m); the points whose voxel column satisfies `red(ix, iy)` are labelled
/// non-traversable, the rest traversable.
template <typename Red, typename Height>
std::vector<ClassifiedPoint> Floor(float sigma_m, const Red& red, const Height& height) {
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 40; ++ix) {
    for (int iy = 0; iy < 40; ++iy) {
      if (Rock(ix, iy)) continue;
      ClassifiedPoint p = testing::Pt(C(ix), C(iy), height(ix, iy), red(ix, iy) ? TravClass::kNonTraversable
                                                                                   : TravClass::kTraversable);
      p.height_sigma_m = sigma_m;
      p.horizontal_sigma_m = 0.01f;
      points.push_back(p);
    }
  }
  return points;
}

template <typename Red>
std::vector<ClassifiedPoint> Floor(float sigma_m, const Red& red) {
  return Floor(sigma_m, red, [](int, int) { return 0.0; });
}

/// The ring of a rock at the floor's centre: columns whose centre lies within 0.2 m of the
/// 0.4 m square on x, y in [1.8, 2.2), outside it.
bool Ring(int ix, int iy) {
  const double dx = std::max({0.0, 1.8 - C(ix), C(ix) - 2.2}), dy = std::max({0.0, 1.8 - C(iy), C(iy) - 2.2});
  const double d = std::hypot(dx, dy);
  return d > 0.0 && d <= 0.2;
}

TravClass ClassAt(const TraversabilityMap& map, double x, double y) { return map.TopSurfaceAt(x, y).cls; }

MapOptions Options() {
  MapOptions o;
  o.max_range_m = 30.0;
  return o;
}

const Eigen::Vector3d kSensor(-3.0, 2.0, 1.0);

TEST(SafeFusion, ARockRingOneClearViewSawIsKeptUnderNoisyFarViews) {
  // One near view (height sigma 2 cm) sees the ring red; eight far views (sigma 25 cm, more
  // than the 0.2 m step they should judge) call it traversable, as a far matcher does.
  auto build = [](const MapOptions& options) {
    TraversabilityMap map(options);
    map.InsertFrame(Floor(0.02f, Ring), kSensor, 0);
    for (int k = 1; k <= 8; ++k) map.InsertFrame(Floor(0.25f, [](int, int) { return false; }), kSensor, k);
    return map;
  };
  const TraversabilityMap map = build(Options());
  int ring = 0, kept = 0;
  for (int ix = 0; ix < 40; ++ix) {
    for (int iy = 0; iy < 40; ++iy) {
      if (!Ring(ix, iy)) continue;
      ++ring;
      kept += ClassAt(map, C(ix), C(iy)) == TravClass::kNonTraversable;
    }
  }
  EXPECT_GT(ring, 40);
  EXPECT_EQ(kept, ring);
  EXPECT_EQ(ClassAt(map, 0.55, 0.55), TravClass::kTraversable);  // open floor stays open

  // Counting every vote alike (no obstacle gain, no noise weighting), the far views erase it.
  MapOptions plain = Options();
  plain.class_obstacle_gain = 1.0;
  plain.class_vote_noise_steps = 0.0;
  plain.class_vote_smear_radii = 0.0;
  plain.class_prior_traversable_log_odds = 0.0;
  EXPECT_EQ(ClassAt(build(plain), C(17), C(20)), TravClass::kTraversable);
}

TEST(SafeFusion, FarViewsWhoseDepthNoiseSmearsAnObstacleSidewaysDoNotBlockTheFloorBehindIt) {
  // A strip of floor that three near views (horizontal sigma 1 cm) see traversable, and that
  // four far views call non-traversable: an obstacle's points their depth noise moved along
  // the ray, 1.2 m sideways at 1 sigma (vertical noise 2 cm: a ray grazes the ground).
  const auto strip = [](int ix, int) { return ix == 25 || ix == 26; };
  const auto none = [](int, int) { return false; };
  auto build = [&](const MapOptions& options) {
    TraversabilityMap map(options);
    for (int k = 0; k < 3; ++k) map.InsertFrame(Floor(0.02f, none), kSensor, k);
    for (int k = 3; k < 7; ++k) {
      std::vector<ClassifiedPoint> far = Floor(0.02f, strip);
      for (ClassifiedPoint& p : far) p.horizontal_sigma_m = 1.2f;
      map.InsertFrame(far, kSensor, k);
    }
    return map;
  };
  // Each far vote counts 1 / (1 + (1.2 / (3 x 0.2))^2) = 1/5 of a near one.
  EXPECT_EQ(ClassAt(build(Options()), C(25), C(10)), TravClass::kTraversable);
  EXPECT_EQ(ClassAt(build(Options()), C(10), C(10)), TravClass::kTraversable);
  // Weighed by their height noise alone, the four far views outvote the three near ones.
  MapOptions unweighted = Options();
  unweighted.class_vote_smear_radii = 0.0;
  EXPECT_EQ(ClassAt(build(unweighted), C(25), C(10)), TravClass::kNonTraversable);
}

TEST(SafeFusion, ALipBandEveryViewSawSurvivesASurfaceThatLooksWhole) {
  // The floor beyond a drop-off is hidden, and stereo smears the upper level a cell or two past
  // the edge: the fused surface then holds level heights over the whole disc of the lip's
  // columns and finds open ground there. Views that saw the lip (a 0.2 m band, two columns,
  // from near: height sigma 2 cm) call it red in every frame.
  const auto band = [](int ix, int) { return ix == 30 || ix == 31; };
  const auto none = [](int, int) { return false; };
  auto build = [&](const MapOptions& options, int red_views, int open_views) {
    TraversabilityMap map(options);
    for (int k = 0; k < red_views + open_views; ++k) {
      map.InsertFrame(k < red_views ? Floor(0.02f, band) : Floor(0.02f, none), kSensor, k);
    }
    return map;
  };
  const TraversabilityMap map = build(Options(), 2, 0);
  int kept = 0;
  for (int iy = 3; iy < 37; ++iy) {  // clear of the floor's ends, where the disc is not whole
    for (const int ix : {30, 31}) {
      const CellInfo cell = map.TopSurfaceAt(C(ix), C(iy));
      kept += cell.cls == TravClass::kNonTraversable;
      ASSERT_TRUE(map.ExplainColumn(C(ix), C(iy)).disc_fully_seen);  // the surface judged it whole
    }
  }
  EXPECT_EQ(kept, 68);
  EXPECT_EQ(ClassAt(map, C(27), C(5)), TravClass::kTraversable);  // the floor next to it stays open
  // Two views: the frames' odds for the lip are e^(2 * 1.7 + 2 * 0.8 - 0.5) = 90 to one, more
  // than the (1 - 2e/3) / (e/3) = 28 that the surface's open ground is worth at e = 0.1. One
  // view of two (odds e^(1.7 - 0.4 - (0.85 - 0.8) - 0.5) = 2.1) does not outweigh it.
  EXPECT_EQ(ClassAt(build(Options(), 1, 1), C(30), C(5)), TravClass::kTraversable);
  // Where the surface's word is final, it erases the lip every view saw.
  MapOptions final_word = Options();
  final_word.class_surface_miss_prob = 0.0;
  EXPECT_EQ(ClassAt(build(final_word, 10, 0), C(30), C(5)), TravClass::kTraversable);
}


TEST(SafeFusion, AVoxelOnTheEdgeOfAnObstacleBandIsTheBands) {
  // A lip band from x = 2.9875 to 3.2125 m: four points per 0.1 m voxel along x (at 0.025 m
  // spacing), so the voxel columns x in [2.9, 3.0) and [3.2, 3.3) hold one red point of four.
  // A cell's class is the worst of the ground in it: both edge columns are non-traversable.
  auto build = [](const MapOptions& options) {
    TraversabilityMap map(options);
    std::vector<ClassifiedPoint> points;
    for (int q = 0; q < 160; ++q) {  // x = (q + 0.5) * 0.025 over [0, 4) m
      for (int iy = 0; iy < 40; ++iy) {
        const bool red = q >= 119 && q < 129;
        ClassifiedPoint p = testing::Pt((q + 0.5) * 0.025, C(iy), 0.0,
                                        red ? TravClass::kNonTraversable : TravClass::kTraversable);
        p.height_sigma_m = 0.02f;
        p.horizontal_sigma_m = 0.01f;
        points.push_back(p);
      }
    }
    for (int k = 0; k < 3; ++k) map.InsertFrame(points, kSensor, k);
    return map;
  };
  const TraversabilityMap map = build(Options());
  for (const int ix : {29, 30, 31, 32}) {
    EXPECT_EQ(ClassAt(map, C(ix), C(20)), TravClass::kNonTraversable) << "column " << ix;
  }
  EXPECT_EQ(ClassAt(map, C(28), C(20)), TravClass::kTraversable);
  EXPECT_EQ(ClassAt(map, C(33), C(20)), TravClass::kTraversable);
  // A share above one point in four, or the plurality of the points, gives the edges to the
  // open ground beside them: the band shrinks by a cell on each side.
  MapOptions half = Options();
  half.class_worst_share = 0.3;
  MapOptions plurality = Options();
  plurality.class_worst_share = 0.0;
  for (const MapOptions& options : {half, plurality}) {
    const TraversabilityMap narrow = build(options);
    EXPECT_EQ(ClassAt(narrow, C(29), C(20)), TravClass::kTraversable);
    EXPECT_EQ(ClassAt(narrow, C(30), C(20)), TravClass::kNonTraversable);
    EXPECT_EQ(ClassAt(narrow, C(32), C(20)), TravClass::kTraversable);
  }
}
TEST(SafeFusion, FarNoiseLeavesALevelFloorTraversableWithALowerConfidence) {
  // Two views whose labels call a 0.3 m patch of level floor red: at a far range (height sigma
  // 0.3 m, more than the 0.2 m step) that is what noise explains. The same two views of a
  // 0.3 m box there, from near (2 cm), show an obstacle.
  const auto patch = [](int ix, int iy) { return ix >= 30 && ix < 33 && iy >= 30 && iy < 33; };
  TraversabilityMap far(Options()), near(Options());
  for (int k = 0; k < 2; ++k) {
    far.InsertFrame(Floor(0.3f, patch), kSensor, k);
    near.InsertFrame(Floor(0.02f, patch, [&](int ix, int iy) { return patch(ix, iy) ? 0.3 : 0.0; }), kSensor, k);
  }
  const CellInfo noisy = far.TopSurfaceAt(C(31), C(31));
  EXPECT_EQ(noisy.cls, TravClass::kTraversable);
  const CellInfo clean = far.TopSurfaceAt(C(5), C(5));
  EXPECT_EQ(clean.cls, TravClass::kTraversable);
  // Less sure than the floor no one doubted, and a planner pays for it, below semi's 0.25.
  EXPECT_LT(noisy.confidence, clean.confidence - 0.1);
  EXPECT_GT(noisy.cost, clean.cost);
  EXPECT_LT(noisy.cost, 0.25);
  EXPECT_EQ(near.TopSurfaceAt(C(31), C(31)).cls, TravClass::kNonTraversable);
}

TEST(SafeFusion, GroundWithinTheSmearOfAFarJumpIsUndecidedNotOpen) {
  // A 0.4 m log across the floor on x in [2.0, 2.5), seen from far behind it (the sensor at
  // (-3, 2), 7 deg off the row judged): the heights are right to 2 cm, but each may belong 0.2 m along its ray
  // (as much as the step radius), and no frame resolved the log's faces, so every vote calls
  // it traversable.
  const auto log = [](int ix, int) { return ix >= 20 && ix < 25 ? 0.4 : 0.0; };
  auto build = [&](const MapOptions& options) {
    TraversabilityMap map(options);
    for (int k = 0; k < 4; ++k) {
      std::vector<ClassifiedPoint> far = Floor(0.02f, [](int, int) { return false; }, log);
      for (ClassifiedPoint& p : far) p.horizontal_sigma_m = 0.2f;
      map.InsertFrame(far, kSensor, k);
    }
    return map;
  };
  MapOptions on = Options();
  on.class_smeared_surface_hazards = true;
  const TraversabilityMap map = build(on);
  // The column on x in [1.7, 1.8), 0.2 m and more before the log (beyond its step radius), but
  // within the smear along the ray (0.45 m from its centre): the log may be within the radius or
  // not, which these views cannot tell.
  const ColumnExplanation before = map.ExplainColumn(C(17), C(25));
  EXPECT_EQ(before.cell.cls, TravClass::kUndecided);
  EXPECT_EQ(before.rule, JudgeRule::kSmearedHazard);
  EXPECT_EQ(before.cell.decided_by, ClassJudge::kNone);  // as any undecided column: no judge, no cost
  EXPECT_TRUE(std::isnan(before.cell.cost));
  EXPECT_TRUE(before.surface.smeared);
  EXPECT_NEAR(before.smeared_region.along_m, 0.45, 1e-6);
  EXPECT_NEAR(before.smeared_region.axis.y() / before.smeared_region.axis.x(), (C(25) - 2.0) / (C(17) + 3.0), 1e-6);
  EXPECT_NEAR(before.smeared_surface.step_m, 0.4 - 2 * 0.01, 0.005);  // four views of 2 cm each
  EXPECT_EQ(ClassAt(map, C(22), C(25)), TravClass::kUndecided);  // the log's top: its edges are as near
  // Beyond the smear, level floor stays open: 0.55 m before the log and 0.55 m after it.
  EXPECT_EQ(ClassAt(map, C(14), C(25)), TravClass::kTraversable);
  EXPECT_EQ(ClassAt(map, C(30), C(25)), TravClass::kTraversable);
  // Without the smeared judgement the frames' votes call the whole log open ground.
  MapOptions off = Options();
  off.class_smeared_surface_hazards = false;
  const TraversabilityMap open = build(off);
  EXPECT_EQ(ClassAt(open, C(17), C(25)), TravClass::kTraversable);
  EXPECT_EQ(open.ExplainColumn(C(17), C(25)).rule, JudgeRule::kFramesAlone);
  EXPECT_EQ(ClassAt(open, C(22), C(25)), TravClass::kTraversable);
}

TEST(SafeFusion, WithAnEvidenceFloorGroundNoViewResolvedIsUndecided) {
  // Six views from about 17 m on the default rig (height sigma 0.35 m, horizontal 1.4 m): each
  // vote counts 1 / (1 + (0.35 / 0.1)^2) / (1 + (1.4 / 0.6)^2) = 0.0117 of a clear one, so six
  // of them are 0.07 clear views, under the quarter map.class_min_evidence_views asks. Whether
  // they call a patch non-traversable (a slope just over the limit, say) or the floor around
  // it traversable, no view resolved that ground: it is undecided. Two near views of a 0.3 m
  // box there decide.
  const auto patch = [](int ix, int iy) { return ix >= 30 && ix < 33 && iy >= 30 && iy < 33; };
  auto build = [&](const MapOptions& options, bool near_views) {
    TraversabilityMap map(options);
    for (int k = 0; k < 6; ++k) {
      std::vector<ClassifiedPoint> far = Floor(0.35f, patch);
      for (ClassifiedPoint& p : far) p.horizontal_sigma_m = 1.4f;
      map.InsertFrame(far, kSensor, k);
    }
    for (int k = 6; near_views && k < 8; ++k) {
      map.InsertFrame(Floor(0.02f, patch, [&](int ix, int iy) { return patch(ix, iy) ? 0.3 : 0.0; }), kSensor, k);
    }
    return map;
  };
  MapOptions floor = Options();
  floor.class_min_evidence_views = 0.25;
  const TraversabilityMap far = build(floor, false);
  EXPECT_EQ(ClassAt(far, C(31), C(31)), TravClass::kUndecided);
  EXPECT_EQ(ClassAt(far, C(5), C(5)), TravClass::kUndecided);
  EXPECT_NEAR(far.ExplainColumn(C(5), C(5)).evidence_views, 6 * 0.0117, 0.005);
  EXPECT_NEAR(far.ExplainColumn(C(31), C(31)).evidence_views, 6 * 0.0117, 0.005);
  const TraversabilityMap seen = build(floor, true);
  EXPECT_EQ(ClassAt(seen, C(31), C(31)), TravClass::kNonTraversable);
  EXPECT_EQ(ClassAt(seen, C(5), C(5)), TravClass::kTraversable);

  // The shipped defaults (no evidence floor): the floor, whose weak votes lean to open ground,
  // is traversable by the prior; the patch, whose weak votes lean to an obstacle, is undecided
  // (map.class_prior_min_evidence_views, 0.25): the prior does not overrule them.
  const TraversabilityMap shipped = build(Options(), false);
  EXPECT_EQ(ClassAt(shipped, C(5), C(5)), TravClass::kTraversable);
  const ColumnExplanation withheld = shipped.ExplainColumn(C(31), C(31));
  EXPECT_EQ(withheld.cell.cls, TravClass::kUndecided);
  EXPECT_EQ(withheld.rule, JudgeRule::kPriorWithheld);
  EXPECT_EQ(ClassAt(build(Options(), true), C(31), C(31)), TravClass::kNonTraversable);
  // With that floor off, the prior alone makes both traversable.
  MapOptions prior_answers = Options();
  prior_answers.class_prior_min_evidence_views = 0.0;
  const TraversabilityMap prior = build(prior_answers, false);
  EXPECT_EQ(ClassAt(prior, C(31), C(31)), TravClass::kTraversable);
  EXPECT_EQ(ClassAt(prior, C(5), C(5)), TravClass::kTraversable);
}

TEST(SafeFusion, ObstacleEvidenceUnderHalfAClearViewIsUndecidedNotBlocked) {
  // Views whose points have a height sigma of 0.1 m and a horizontal one of 0.7 m: each vote
  // counts 1 / (1 + (0.1 / 0.1)^2) / (1 + (0.7 / 0.6)^2) = 0.212 of a clear one, as a far frame
  // beyond resolving the step radius gives. Two of them (the fewest that make a voxel occupied)
  // call a patch red, a smeared step, say: 0.42 clear views of obstacle evidence, under the
  // half that map.class_obstacle_min_evidence_views asks, so the patch is undecided, not
  // blocked; the floor around it, which the same views call open, stays traversable. A third
  // view that agrees makes 0.64 clear views: then the patch is an obstacle.
  const auto patch = [](int ix, int iy) { return ix >= 30 && ix < 33 && iy >= 30 && iy < 33; };
  auto build = [&](const MapOptions& options, int views) {
    TraversabilityMap map(options);
    for (int k = 0; k < views; ++k) {
      std::vector<ClassifiedPoint> far = Floor(0.1f, patch);
      for (ClassifiedPoint& p : far) p.horizontal_sigma_m = 0.7f;
      map.InsertFrame(far, kSensor, k);
    }
    return map;
  };
  const TraversabilityMap two = build(Options(), 2);
  const ColumnExplanation withheld = two.ExplainColumn(C(31), C(31));
  EXPECT_EQ(withheld.cell.cls, TravClass::kUndecided);
  EXPECT_EQ(withheld.rule, JudgeRule::kObstacleWithheld);
  EXPECT_NEAR(withheld.evidence_views, 2 * 0.212, 0.005);
  EXPECT_GT(withheld.frame_probability[2], withheld.frame_probability[0]);  // the votes do lean to an obstacle
  EXPECT_EQ(ClassAt(two, C(5), C(5)), TravClass::kTraversable);
  const ColumnExplanation three = build(Options(), 3).ExplainColumn(C(31), C(31));
  EXPECT_EQ(three.cell.cls, TravClass::kNonTraversable);
  EXPECT_NEAR(three.evidence_views, 3 * 0.212, 0.005);
  // With the floor off, the two views block the patch.
  MapOptions any_lead = Options();
  any_lead.class_obstacle_min_evidence_views = 0.0;
  EXPECT_EQ(ClassAt(build(any_lead, 2), C(31), C(31)), TravClass::kNonTraversable);
}

TEST(SafeFusion, AnEvidenceFloorLeavesTheFusedSurfaceItsSay) {
  // Two views of level floor whose labels call a patch red, at a height sigma of 0.3 m (0.1 of
  // a clear vote each: 0.2 clear views) but placed to a centimetre sideways: the frames give no
  // verdict under the floor, and the fused surface, level, judges the patch alone.
  const auto patch = [](int ix, int iy) { return ix >= 30 && ix < 33 && iy >= 30 && iy < 33; };
  MapOptions floor = Options();
  floor.class_min_evidence_views = 0.25;
  TraversabilityMap map(floor);
  for (int k = 0; k < 2; ++k) map.InsertFrame(Floor(0.3f, patch), kSensor, k);
  const ColumnExplanation why = map.ExplainColumn(C(31), C(31));
  EXPECT_NEAR(why.evidence_views, 0.2, 0.01);
  EXPECT_EQ(why.rule, JudgeRule::kSurfaceAlone);
  EXPECT_EQ(why.cell.cls, TravClass::kTraversable);
}

/// An organized cloud rendered by ray casting a world of height `ground(x)` or `ground(x, y)`
/// (x forward, y left) from a pinhole camera at height `camera_z` pitched `pitch_deg` down
/// (f 400 px, `width` x 240, principal point at the centre), in the rectified camera frame
/// (x right, y down, z forward); pixels that meet no ground within 60 m have no point.
/// `world_T_rectified`: the camera's pose in the world (x forward, z up).
template <typename Ground>
Image3f Render(double camera_z, double pitch_deg, const Ground& ground, Eigen::Isometry3d* world_T_rectified,
               int width = 32) {
  const double pitch = DegToRad(pitch_deg);
  Eigen::Matrix3d world_R_level;  // camera axes x right, y down, z forward in a world x fwd, z up
  world_R_level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d world_R = world_R_level * Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitX()).toRotationMatrix();
  *world_T_rectified = Eigen::Isometry3d::Identity();
  world_T_rectified->linear() = world_R;
  world_T_rectified->translation() = Eigen::Vector3d(0, 0, camera_z);
  Image3f cloud(width, 240, Eigen::Vector3f::Constant(std::nanf("")));
  const Eigen::Vector3d origin = world_T_rectified->translation();
  const auto below = [&](double t, const Eigen::Vector3d& ray_w) {
    const Eigen::Vector3d p = origin + t * ray_w;
    if constexpr (std::is_invocable_v<Ground, double, double>) {
      return p.z() <= ground(p.x(), p.y());
    } else {
      return p.z() <= ground(p.x());
    }
  };
  for (int v = 0; v < 240; ++v) {
    for (int u = 0; u < width; ++u) {
      const Eigen::Vector3d ray_c((u - 0.5 * width) / 400.0, (v - 120) / 400.0, 1.0);
      const Eigen::Vector3d ray_w = world_R * ray_c;
      // March along the ray until it passes below the ground, then bisect to 0.1 mm.
      for (double t = 0.02; t < 60.0; t += 0.02) {
        if (!below(t, ray_w)) continue;
        double lo = t - 0.02, hi = t;
        while (hi - lo > 1e-4) (below(0.5 * (lo + hi), ray_w) ? hi : lo) = 0.5 * (lo + hi);
        cloud(v, u) = (hi * ray_c).cast<float>();
        break;
      }
    }
  }
  return cloud;
}

/// The extent (world x) of the lip's points along the image's centre column, and their largest
/// weight.
struct LipProfile {
  double first_x = NAN, last_x = NAN;  ///< extent of the marked points [m]
  int max_weight = 0;
};

LipProfile Profile(const Image3f& cloud, const ImageU8& lip, const Eigen::Isometry3d& world_T) {
  LipProfile p;
  const int u = cloud.width() / 2;
  for (int v = 0; v < cloud.height(); ++v) {
    if (lip(v, u) == 0) continue;
    const double x = (world_T * cloud(v, u).cast<double>()).x();
    p.first_x = std::isnan(p.first_x) ? x : std::min(p.first_x, x);
    p.last_x = std::isnan(p.last_x) ? x : std::max(p.last_x, x);
    p.max_weight = std::max(p.max_weight, static_cast<int>(lip(v, u)));
  }
  return p;
}

constexpr double kNoise = 1e-4;  // depth sigma per m^2: a fine stereo rig

TEST(HiddenDrops, ACliffsLipIsMarkedWhetherItsFloorIsSeenOrNot) {
  VehicleOptions vehicle;  // max step 0.2 m, step radius 0.2 m, max slope 25 deg
  Eigen::Isometry3d world_T;
  // A 1 m cliff at x = 1.5 m, seen from 0.8 m up: the ray over the lip descends at 28 deg,
  // more steeply than the 25 deg limit, and lands on the floor farther on.
  const Image3f seen = Render(0.8, 30.0, [](double x) { return x < 1.5 ? 0.0 : -1.0; }, &world_T);
  LipProfile p = Profile(seen, FindHiddenDrops(seen, world_T, kNoise, vehicle, 20.0, 1), world_T);
  EXPECT_NEAR(p.last_x, 1.5, 0.02);   // the edge
  EXPECT_NEAR(p.first_x, 1.3, 0.03);  // a step radius before it
  EXPECT_EQ(p.max_weight, 255);
  // A 30 m deep cliff: the floor is out of range, the rays over the lip land on nothing.
  const Image3f hidden = Render(0.8, 30.0, [](double x) { return x < 1.5 ? 0.0 : -30.0; }, &world_T);
  p = Profile(hidden, FindHiddenDrops(hidden, world_T, kNoise, vehicle, 20.0, 1), world_T);
  EXPECT_NEAR(p.last_x, 1.5, 0.02);
  EXPECT_EQ(p.max_weight, 255);
  // Seen from 6 m, the ray over the lip descends at 7.6 deg: it could hide a drivable slope,
  // so the lip is only suspected, by tan(7.6) / tan(25) of a full vote.
  const Image3f far = Render(0.8, 8.0, [](double x) { return x < 6.0 ? 0.0 : -1.0; }, &world_T);
  p = Profile(far, FindHiddenDrops(far, world_T, kNoise, vehicle, 20.0, 1), world_T);
  EXPECT_NEAR(p.last_x, 6.0, 0.12);  // an image row spans 0.11 m of ground at 6 m
  EXPECT_NEAR(p.max_weight, 255.0 * (0.8 / 6.0) / std::tan(DegToRad(25.0)), 4.0);
}

TEST(HiddenDrops, AFramesOwnSearchMarksTheLipsTheMapsDoesWithinTheSameRange) {
  // The frame's labels search in the frame levelled by its own up vector, from the camera: the
  // same lips as the map's search in the world (which takes the frame's), whether a floor lies
  // beyond the edge or nothing does. Without a range, a column with nothing beyond its last
  // point marks nothing.
  VehicleOptions vehicle;
  Eigen::Isometry3d world_T;
  const auto count = [](const ImageU8& a, const ImageU8& b, int* marked, int* differ) {
    *marked = *differ = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      *marked += a[i] != 0;
      *differ += a[i] != b[i];
    }
  };
  int marked = 0, differ = 0;
  for (const double floor : {-1.0, -30.0}) {
    const Image3f cloud = Render(0.8, 30.0, [floor](double x) { return x < 1.5 ? 0.0 : floor; }, &world_T);
    const Eigen::Vector3d up_camera = world_T.linear().transpose() * Eigen::Vector3d::UnitZ();
    count(FindHiddenDrops(cloud, world_T, kNoise, vehicle, 20.0, 1),
          FindFramesHiddenDrops(cloud, up_camera, kNoise, vehicle, 20.0), &marked, &differ);
    EXPECT_GT(marked, 500) << "floor " << floor;  // the band across the image: 800 pixels
    EXPECT_EQ(differ, 0) << "floor " << floor;
    const LipProfile none = Profile(cloud, FindFramesHiddenDrops(cloud, up_camera, kNoise, vehicle, 0.0), world_T);
    EXPECT_EQ(std::isnan(none.last_x), floor < -20.0) << "floor " << floor;
  }
}

TEST(HiddenDrops, APitsRimIsMarkedWhereItsFarWallHidesTheFloor) {
  VehicleOptions vehicle;  // semi step 0.1 m, max step 0.2 m, max slope 25 deg
  Eigen::Isometry3d world_T;
  // A pit 0.3 m deep over x in [3.0, 3.5), seen from 1.1 m up: the ray over its near edge
  // descends at tan 1.1 / 3 and meets the far wall 0.18 m down, less than the vehicle may step,
  // with the floor hidden below it. The pit is at least 0.18 m deep and no view from here says
  // how much more: its rim is a lip, suspected by tan(ray) / tan(25 deg), a step radius deep
  // on both sides: the far wall rises back to the near side's height, down from which it
  // stands on the same hidden floor.
  const auto pit = [](double depth) {
    return [depth](double x) { return x >= 3.0 && x < 3.5 ? -depth : 0.0; };
  };
  const Image3f hidden = Render(1.1, 20.0, pit(0.3), &world_T);
  const ImageU8 lip = FindHiddenDrops(hidden, world_T, kNoise, vehicle, 20.0, 1);
  const LipProfile p = Profile(hidden, lip, world_T);
  EXPECT_NEAR(p.first_x, 2.8, 0.04);  // a step radius before the near edge
  EXPECT_NEAR(p.last_x, 3.7, 0.04);   // a step radius beyond the far edge
  EXPECT_NEAR(p.max_weight, 255.0 * (1.1 / 3.0) / std::tan(DegToRad(25.0)), 4.0);
  // Between the two bands nothing is marked: no ground beyond the near band up to the wall,
  // and on the far side only the rim's 0.2 m.
  int marked_between = 0;
  for (int v = 0; v < hidden.height(); ++v) {
    const Eigen::Vector3d q = world_T * hidden(v, 16).cast<double>();
    if (std::isfinite(q.x()) && ((q.x() > 2.0 && q.x() < 2.77) || q.x() > 3.75)) marked_between += lip(v, 16) != 0;
  }
  EXPECT_EQ(marked_between, 0);
  // The same pit whose far side rises only to 0.12 m below the near side: the ray over the near
  // edge lands on the far wall 0.18 m down, and that wall rises 0.06 m into view. Its rim stands
  // lower than the near one by more than the noise, so the floor's depth below it is not known
  // to match the near side's (0.18 m there: a step the vehicle may take): only the near edge is
  // a lip.
  const Image3f lower = Render(
      1.1, 20.0, [](double x) { return x < 3.0 ? 0.0 : (x < 3.5 ? -0.3 : -0.12); }, &world_T);
  const LipProfile near_only = Profile(lower, FindHiddenDrops(lower, world_T, kNoise, vehicle, 20.0, 1), world_T);
  EXPECT_NEAR(near_only.first_x, 2.8, 0.04);
  EXPECT_NEAR(near_only.last_x, 3.0, 0.03);
  // 0.15 m deep, the same pit shows its floor before the far wall: the view lands on a floor
  // 0.15 m down, a step the vehicle may take, and nothing is marked.
  const Image3f shallow = Render(1.1, 20.0, pit(0.15), &world_T);
  EXPECT_TRUE(std::isnan(Profile(shallow, FindHiddenDrops(shallow, world_T, kNoise, vehicle, 20.0, 1), world_T).last_x));
}

TEST(HiddenDrops, ALipReachesAStepRadiusFromAnEdgeTheColumnsCrossObliquely) {
  VehicleOptions vehicle;  // step radius 0.2 m
  Eigen::Isometry3d world_T;
  // A 1 m cliff whose edge x + 2 y = 2 runs at 63 deg to the view: along a column (world x)
  // a step radius from the edge is 0.2 sqrt(5) = 0.45 m, not 0.2 m. Every point within the
  // step radius of the edge is lip, as the vehicle's rule measures it; none farther.
  const auto cliff = [](double x, double y) { return x + 2.0 * y < 2.0 ? 0.0 : -1.0; };
  const Image3f cloud = Render(0.8, 30.0, cliff, &world_T, 160);
  const ImageU8 lip = FindHiddenDrops(cloud, world_T, kNoise, vehicle, 20.0, 1);
  int inside = 0, inside_marked = 0, outside_marked = 0;
  for (int v = 0; v < cloud.height(); ++v) {
    for (int u = 20; u < 140; ++u) {  // away from the image's sides, where the edge runs out
      if (!cloud(v, u).allFinite()) continue;
      const Eigen::Vector3d q = world_T * cloud(v, u).cast<double>();
      if (q.z() < -0.5) continue;  // the floor below
      const double distance = (2.0 - q.x() - 2.0 * q.y()) / std::sqrt(5.0);
      if (distance < 0.19) {
        ++inside;
        inside_marked += lip(v, u) != 0;
      } else if (distance > 0.22) {
        outside_marked += lip(v, u) != 0;
      }
    }
  }
  ASSERT_GT(inside, 500);
  EXPECT_GT(inside_marked, 0.95 * inside);
  EXPECT_EQ(outside_marked, 0);
}

TEST(HiddenDrops, ARampsCrestWhoseFarSideIsSeenAndADitchsFarEdgeAreNot) {
  VehicleOptions vehicle;
  Eigen::Isometry3d world_T;
  // A plateau at 0.5 m whose far side descends at 15 deg from x = 2 m, seen from 0.8 m above
  // the plateau: the rays over the crest descend at 22 deg, more steeply than the slope, so
  // they see it: no lip.
  const auto ramp = [](double x) { return x < 2.0 ? 0.5 : std::max(-1.0, 0.5 - (x - 2.0) * std::tan(DegToRad(15.0))); };
  const Image3f crest = Render(1.3, 30.0, ramp, &world_T);
  EXPECT_TRUE(std::isnan(Profile(crest, FindHiddenDrops(crest, world_T, kNoise, vehicle, 20.0, 1), world_T).last_x));
  // A ditch 0.6 m deep over x in [1.6, 2.4): its near edge is a lip, its far edge (a wall that
  // faces the camera) is not.
  const auto ditch = [](double x) { return x >= 1.6 && x < 2.4 ? -0.6 : 0.0; };
  const Image3f cut = Render(0.8, 30.0, ditch, &world_T);
  const LipProfile p = Profile(cut, FindHiddenDrops(cut, world_T, kNoise, vehicle, 20.0, 1), world_T);
  EXPECT_NEAR(p.last_x, 1.6, 0.02);
  EXPECT_NEAR(p.first_x, 1.4, 0.03);
  // A level floor has no lip anywhere, and neither has noise: the same floor with 5 cm of
  // height noise at 10 m (sigma per m^2 0.0005 at f 400 px) stays unmarked.
  const Image3f flat = Render(0.8, 20.0, [](double) { return 0.0; }, &world_T);
  const ImageU8 none = FindHiddenDrops(flat, world_T, 5e-4, vehicle, 20.0, 1);
  int marked = 0;
  for (int v = 0; v < none.height(); ++v) {
    for (int u = 0; u < none.width(); ++u) marked += none(v, u) != 0;
  }
  EXPECT_EQ(marked, 0);
}

TEST(HiddenDrops, AHumpsCrestWhoseViewLandsAtACratesFootIsNot) {
  VehicleOptions vehicle;  // semi step 0.1 m, step radius 0.2 m
  Eigen::Isometry3d world_T;
  // A hump 0.1 m high rising and falling at 15 deg from x = 4 m, seen from 0.8 m: the view over
  // its crest (x 4.37 m) descends at 9 deg, hides the far side and lands at the foot of a
  // 0.5 m crate at x = 5 m, 0.1 m lower than the crest. The hidden ground between lies less
  // than a semi step below the crest, and the crate's face is no pit's far wall: the crest is
  // no lip. Ground within a step radius of the crate's foot may be marked (it is beside an
  // obstacle), but nothing nearer the hump.
  const auto hump_and_crate = [](double x) {
    if (x >= 5.0 && x < 5.5) return 0.5;
    const double tan15 = std::tan(DegToRad(15.0));
    return std::max(0.0, std::min(0.1, (x - 4.0) * tan15) - std::max(0.0, (x - 4.0 - 0.1 / tan15) * tan15));
  };
  const Image3f cloud = Render(0.8, 15.0, hump_and_crate, &world_T);
  const LipProfile p = Profile(cloud, FindHiddenDrops(cloud, world_T, kNoise, vehicle, 20.0, 1), world_T);
  EXPECT_FALSE(p.first_x < 4.75) << "marked from x = " << p.first_x;
  // The crest's view does land at the crate's foot, 0.1 m below the crest, as the test means.
  const int u = cloud.width() / 2;
  double crest_z = -1.0;
  double after_crest_x = NAN;
  for (int v = cloud.height() - 1; v >= 0; --v) {
    if (!cloud(v, u).allFinite()) continue;
    const Eigen::Vector3d q = world_T * cloud(v, u).cast<double>();
    if (q.x() < 4.5) crest_z = std::max(crest_z, q.z());
    if (q.x() > 4.5 && std::isnan(after_crest_x)) after_crest_x = q.x();
  }
  EXPECT_NEAR(crest_z, 0.1, 0.01);
  EXPECT_NEAR(after_crest_x, 5.0, 0.01);
}

}  // namespace
}  // namespace ssta
