#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ssta/core/error.h"
#include "ssta/eval/footprint_evaluator.h"

namespace ssta {
namespace {

constexpr double kTol = 1e-12;

// 40 x 40 cells of 0.1 m from (0, 0), traversable except: a 2 x 2 non-traversable block at
// columns 20-21, rows 20-21 from the bottom; one semi-traversable cell at column 30, row 10;
// one don't-care cell at column 5, row 5.
ClassGrid Truth() {
  ClassGrid grid;
  grid.classes = ImageU8(40, 40, 1);
  grid.resolution_m = 0.1;
  grid.source = "truth.png";
  auto set = [&](int col, int bottom, int value) {
    grid.classes(39 - bottom, col) = static_cast<std::uint8_t>(value);
  };
  for (int c = 20; c <= 21; ++c) {
    for (int b = 20; b <= 21; ++b) set(c, b, 3);
  }
  set(30, 10, 2);
  set(5, 5, 255);
  return grid;
}

FootprintAnswer Always(std::uint8_t cls, double known) { return {cls, known}; }

/// 0.3 x 0.3 m squares at yaw 0 on every cell centre: each covers its cell and its 8 neighbours.
FootprintEvalOptions SquaresOnEveryCell() {
  FootprintEvalOptions options;
  options.length_m = options.width_m = 0.3;
  options.step_m = 0.1;
  options.yaws_deg = {0.0};
  return options;
}

/// A path along y = -1 m, under the grid: a pose's distance from it is its centre's y + 1.
const std::vector<Eigen::Vector2d> kPathBelow = {{0.0, -1.0}, {4.0, -1.0}};

TEST(eval_Footprints, SquareFootprintsCoverTheirThreeByThreeCells) {
  // 0.3 x 0.3 m at yaw 0 on every cell centre: the cell and its 8 neighbours.
  const FootprintEvalOptions options = SquaresOnEveryCell();
  int asked = 0;
  const FootprintEvalSummary s = ScoreFootprints(Truth(), options, [&](const FootprintPose& pose) {
    ++asked;
    EXPECT_EQ(pose.yaw_rad, 0.0);
    return Always(1, 1.0);
  });
  EXPECT_EQ(s.poses, 1599);  // every cell but the don't-care one
  // The border ring (156 poses reach outside the grid) and the don't-care cell's 8 neighbours.
  EXPECT_EQ(s.partly_unseen, 156 + 8);
  EXPECT_EQ(s.matrix.Scored(), 1599 - 164);
  EXPECT_EQ(asked, 1599 - 164);
  // Truly non-traversable: the 4 x 4 centres around the block; semi: the 3 x 3 around its cell.
  EXPECT_EQ(s.matrix.Count(3, 1), 16);
  EXPECT_EQ(s.matrix.Count(2, 1), 9);
  EXPECT_EQ(s.matrix.Count(1, 1), 1435 - 25);
  EXPECT_EQ(s.unsafe, 16);
  EXPECT_EQ(s.falsely_blocked, 0);
  EXPECT_EQ(s.partly_known, 0);
  EXPECT_NEAR(s.mean_fraction_known, 1.0, kTol);
  EXPECT_NEAR(s.matrix.Accuracy(), 1410.0 / 1435.0, kTol);

  EXPECT_NEAR(s.matrix.UnsafeRate(), 1.0, kTol);
  EXPECT_NEAR(s.matrix.Recall(TravClass::kNonTraversable), 0.0, kTol);

  // Blocking everything, half known: every truly free (traversable or semi) footprint is
  // falsely blocked.
  const FootprintEvalSummary b = ScoreFootprints(Truth(), options, [](const FootprintPose&) { return Always(3, 0.5); });
  EXPECT_EQ(b.falsely_blocked, 1410 + 9);
  EXPECT_NEAR(b.matrix.FalselyBlockedRate(), 1.0, kTol);
  EXPECT_EQ(b.unsafe, 0);
  EXPECT_EQ(b.partly_known, 1435);
  EXPECT_NEAR(b.mean_fraction_known, 0.5, kTol);
  // Knowing nothing: no verdict, so neither unsafe nor blocked, and no coverage.
  const FootprintEvalSummary u = ScoreFootprints(Truth(), options, [](const FootprintPose&) { return Always(0, 0.0); });
  EXPECT_EQ(u.unsafe + u.falsely_blocked, 0);
  EXPECT_NEAR(u.matrix.Coverage(), 0.0, kTol);
  // Undecided everywhere (a map that sees surfaces it cannot judge): neither unsafe nor blocked,
  // each class's recall 0, every footprint counted in the undecided column.
  const FootprintEvalSummary d = ScoreFootprints(Truth(), options, [](const FootprintPose&) { return Always(4, 1.0); });
  EXPECT_EQ(d.unsafe + d.falsely_blocked, 0);
  EXPECT_EQ(d.matrix.Count(3, 4), 16);
  EXPECT_EQ(d.matrix.Count(1, 4) + d.matrix.Count(2, 4), 1410 + 9);
  EXPECT_NEAR(d.matrix.Recall(TravClass::kTraversable), 0.0, kTol);
  EXPECT_NEAR(d.matrix.Recall(TravClass::kNonTraversable), 0.0, kTol);
}

TEST(eval_Footprints, SplitsPosesByTheirDistanceFromThePath) {
  // The path runs along y = -1 m: a pose's distance is its centre's y + 1, so the first band
  // (under 2 m) holds the centres with y < 1 m: bottom rows 1..9 (row 0 reaches outside the
  // grid), columns 1..38, less the don't-care cell and its 8 neighbours.
  const FootprintEvalOptions options = SquaresOnEveryCell();
  const std::vector<Eigen::Vector2d>& path = kPathBelow;
  const FootprintEvalSummary s =
      ScoreFootprints(Truth(), options, [](const FootprintPose&) { return Always(1, 1.0); }, path);
  ASSERT_EQ(s.by_distance.size(), 3u);  // centres up to y = 3.85: distances below 6 m
  EXPECT_EQ(s.by_distance[0].matrix.Scored(), 9 * 38 - 1 - 8);
  // Row 9 holds the three poses whose 3 x 3 cells reach the semi-traversable cell (row 10).
  EXPECT_EQ(s.by_distance[0].matrix.Count(2, 1), 3);
  std::int64_t scored = 0, unsafe = 0;
  for (const DistanceBand& band : s.by_distance) {
    scored += band.matrix.Scored();
    unsafe += band.matrix.Unsafe();
  }
  EXPECT_EQ(scored, s.matrix.Scored());
  EXPECT_EQ(unsafe, s.unsafe);
  EXPECT_EQ(s.by_distance.back().matrix_within.Scored(), s.matrix.Scored());
  EXPECT_NEAR(s.by_distance.back().accuracy_within, s.matrix.Accuracy(), kTol);
  EXPECT_NE(s.ToJson().find("\"by_distance_from_path\""), std::string::npos);
}

TEST(eval_Footprints, ListsEachUnsafeAndFalselyBlockedPoseNearestThePathFirst) {
  // 0.3 m squares on every cell, the path along y = -1 m. The oracle blocks the poses whose
  // centre lies in column 10 and calls everything else traversable: the 16 centres around the
  // block are unsafe, and column 10's scored centres (bottom rows 1..38, all truly
  // traversable) falsely blocked.
  const FootprintEvalOptions options = SquaresOnEveryCell();
  const std::vector<Eigen::Vector2d>& path = kPathBelow;
  // A blocked answer names the cell to the pose's right as its non-traversable one.
  FootprintEvalSummary s = ScoreFootprints(
      Truth(), options,
      [](const FootprintPose& pose) {
        if (std::abs(pose.x_m - 1.05) > 1e-9) return Always(1, 1.0);
        FootprintAnswer blocked = Always(3, 1.0);
        blocked.worst_x_m = pose.x_m + 0.1;
        blocked.worst_y_m = pose.y_m;
        return blocked;
      },
      path);
  EXPECT_EQ(s.unsafe, 16);
  EXPECT_EQ(s.falsely_blocked, 38);
  ASSERT_EQ(s.misses.size(), 16u + 38u);
  for (std::size_t i = 0; i < s.misses.size(); ++i) {
    const FootprintMiss& m = s.misses[i];
    EXPECT_EQ(m.unsafe, i < 16) << i;
    EXPECT_EQ(m.truth, m.unsafe ? 3 : 1) << i;
    EXPECT_EQ(m.answer, m.unsafe ? 1 : 3) << i;
    EXPECT_NEAR(m.distance_from_path_m, m.pose.y_m + 1.0, 1e-9) << i;  // the centre's y + 1
    if (i > 0 && m.unsafe == s.misses[i - 1].unsafe) {
      EXPECT_GE(m.distance_from_path_m, s.misses[i - 1].distance_from_path_m) << i;
    }
  }
  // The block's 4 x 4 centres: columns and bottom rows 19..22, nearest row first.
  EXPECT_NEAR(s.misses.front().pose.y_m, 1.95, 1e-9);
  EXPECT_NEAR(s.misses[15].pose.y_m, 2.25, 1e-9);
  EXPECT_NEAR(s.misses[16].pose.x_m, 1.05, 1e-9);
  EXPECT_NEAR(s.misses[16].pose.y_m, 0.15, 1e-9);  // bottom row 1: row 0 reaches outside

  // Each miss's cell: an unsafe pose's nearest truly blocked cell, a falsely blocked pose's
  // the one the answer named, with the truth there. Pose (1.95, 1.95) covers the block's cell
  // (2.05, 2.05) alone; pose (2.05, 1.95) covers (2.05, 2.05) and (2.15, 2.05), 0.1 and 0.14 m off.
  EXPECT_NEAR(s.misses[0].pose.x_m, 1.95, 1e-9);
  EXPECT_NEAR(s.misses[1].pose.x_m, 2.05, 1e-9);
  for (const int i : {0, 1}) {
    EXPECT_NEAR(s.misses[i].cell_x_m, 2.05, 1e-9) << i;
    EXPECT_NEAR(s.misses[i].cell_y_m, 2.05, 1e-9) << i;
    EXPECT_EQ(s.misses[i].cell_truth, 3) << i;
  }
  EXPECT_NEAR(s.misses[16].cell_x_m, 1.15, 1e-9);
  EXPECT_NEAR(s.misses[16].cell_y_m, 0.15, 1e-9);
  EXPECT_EQ(s.misses[16].cell_truth, 1);

  const std::string csv = s.MissesCsv();
  EXPECT_EQ(csv.rfind("kind,x_m,y_m,yaw_deg,truth,answer,fraction_known,distance_from_path_m,cell_x_m,cell_y_m,"
                      "cell_truth,cell_class,cell_rule\n",
                      0),
            0u)
      << csv;
  EXPECT_NE(csv.find("\nfalsely_blocked,1.050,0.150,0.0,1,3,1.000,1.15,1.150,0.150,1,,\n"), std::string::npos) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 16 + 38);

  // Counted by the rule the caller names for each cell, most misses first; none named: unknown.
  for (std::size_t i = 0; i < s.misses.size(); ++i) {
    FootprintMiss& m = s.misses[i];
    m.cell_class = m.unsafe ? "1" : "3";
    m.cell_rule = m.unsafe ? "ring" : (i % 2 == 1 ? "noise" : "");
  }
  const std::vector<FootprintEvalSummary::RuleCount> rules = s.MissesByRule();
  ASSERT_EQ(rules.size(), 3u);
  EXPECT_EQ(rules[0].rule, "unknown");  // 19 falsely blocked, met before "noise" and as many
  EXPECT_EQ(rules[0].falsely_blocked, 19);
  EXPECT_EQ(rules[1].rule, "noise");
  EXPECT_EQ(rules[1].unsafe, 0);
  EXPECT_EQ(rules[1].falsely_blocked, 19);
  EXPECT_EQ(rules[2].rule, "ring");
  EXPECT_EQ(rules[2].unsafe, 16);
  EXPECT_EQ(rules[2].falsely_blocked, 0);
  // Every falsely blocked pose's cell is truly traversable here: none blocked by a true obstacle.
  for (const auto& r : rules) EXPECT_EQ(r.falsely_blocked_by_a_true_obstacle, 0) << r.rule;
  EXPECT_NE(s.MissesCsv().find("\nfalsely_blocked,1.050,0.150,0.0,1,3,1.000,1.15,1.150,0.150,1,3,\n"),
            std::string::npos);
  EXPECT_NE(s.BriefReport().find("misses by what decided their cell (unsafe / falsely blocked): unknown 0 / 19; "
                                 "noise 0 / 19; ring 16 / 0\n"),
            std::string::npos)
      << s.BriefReport();
  const std::string json = s.ToJson();
  const std::size_t ring = json.find("\"rule\": \"ring\"");
  ASSERT_NE(ring, std::string::npos) << json;
  EXPECT_GT(ring, json.find("\"misses_by_rule\""));
  EXPECT_EQ(json.find("\"unsafe\": 16", ring), json.find("\"unsafe\"", ring)) << json;
}

TEST(eval_Footprints, APlannersConfidenceBarTurnsUnsureDrivableAnswersUndecided) {
  // Every footprint answered traversable; the ones whose centre lies left of x = 2 m (columns
  // 0-19) with confidence 0.55, the others with 0.97. The block's 16 truly non-traversable
  // centres are columns 19-22: 4 of them on the unsure side.
  const FootprintEvalOptions options = SquaresOnEveryCell();
  const auto oracle = [](const FootprintPose& pose) {
    FootprintAnswer a = Always(1, 1.0);
    a.confidence = pose.x_m < 2.0 ? 0.55 : 0.97;
    return a;
  };
  const FootprintEvalSummary all = ScoreFootprints(Truth(), options, oracle);
  EXPECT_EQ(all.unsafe, 16);
  // Scored centres per column: rows 1..38, less the don't-care cell's 3 x 3 (columns 4-6).
  const std::int64_t left_free = 19 * 38 - 9 - 4, right_free = 19 * 38 - 12;  // columns 1-19, 20-38
  ASSERT_EQ(left_free + right_free, 1410 + 9);
  ASSERT_EQ(all.by_min_confidence.size(), std::size(FootprintEvalSummary::kConfidenceBars));
  for (const FootprintEvalSummary::ConfidenceBar& bar : all.by_min_confidence) {
    const bool left_counts = bar.min_confidence <= 0.55, right_counts = bar.min_confidence <= 0.97;
    EXPECT_EQ(bar.unsafe, (left_counts ? 4 : 0) + (right_counts ? 12 : 0)) << bar.min_confidence;
    EXPECT_EQ(bar.free_drivable, (left_counts ? left_free : 0) + (right_counts ? right_free : 0)) << bar.min_confidence;
    EXPECT_NEAR(bar.unsafe_rate, bar.unsafe / 16.0, kTol);
    EXPECT_NEAR(bar.free_drivable_rate, bar.free_drivable / 1419.0, kTol);
  }
  // A planner with a bar of 0.6 drives only on the right: the left's answers are undecided.
  FootprintEvalOptions barred = options;
  barred.min_confidence = 0.6;
  const FootprintEvalSummary b = ScoreFootprints(Truth(), barred, oracle);
  EXPECT_EQ(b.unsafe, 12);
  EXPECT_EQ(b.matrix.Count(3, 4), 4);
  EXPECT_EQ(b.matrix.Count(1, 4) + b.matrix.Count(2, 4), left_free);
  EXPECT_EQ(b.falsely_blocked, 0);
  EXPECT_NE(b.ToJson().find("\"by_min_confidence\""), std::string::npos);
  // A blocked answer stays blocked whatever its confidence; no confidence counts as sure.
  const FootprintEvalSummary blocked = ScoreFootprints(Truth(), barred, [](const FootprintPose&) {
    FootprintAnswer a = Always(3, 1.0);
    a.confidence = 0.1;
    return a;
  });
  EXPECT_EQ(blocked.falsely_blocked, 1419);
  const FootprintEvalSummary unsaid = ScoreFootprints(Truth(), barred, [](const FootprintPose&) { return Always(1, 1.0); });
  EXPECT_EQ(unsaid.unsafe, 16);
}

TEST(eval_Footprints, DiagonalFootprintsCoverTheirDiagonalCells) {
  // 0.3 x 0.1 m at 45 degrees: the centre and the two cells along the diagonal (0.141 m along,
  // 0 across); the orthogonal neighbours lie 0.071 m across, outside the 0.05 m half width.
  FootprintEvalOptions options;
  options.length_m = 0.3;
  options.width_m = 0.1;
  options.step_m = 0.1;
  for (const double yaw : {45.0, 135.0}) {
    SCOPED_TRACE(yaw);
    options.yaws_deg = {yaw};
    const FootprintEvalSummary s = ScoreFootprints(Truth(), options, [&](const FootprintPose& pose) {
      EXPECT_NEAR(pose.yaw_rad, yaw * M_PI / 180.0, 1e-12);
      return Always(2, 1.0);
    });
    // Border poses reach outside along the diagonal; the don't-care cell has 2 diagonal poses.
    EXPECT_EQ(s.partly_unseen, 156 + 2);
    // The block, and the poses one diagonal step before and after it: 4 + 4 + 4 - 2 overlaps.
    EXPECT_EQ(s.unsafe, 10);
    EXPECT_EQ(s.matrix.Count(3, 2), 10);
    EXPECT_EQ(s.matrix.Count(2, 2), 3);  // the semi cell and its two diagonal poses
  }
}

TEST(eval_Footprints, LatticeStepIsAWholeNumberOfCells) {
  FootprintEvalOptions options;
  options.length_m = options.width_m = 0.1;  // one cell each
  options.yaws_deg = {0.0, 90.0};
  options.step_m = 0.5;  // every 5th cell from the 3rd: 8 x 8 centres
  const FootprintEvalSummary s = ScoreFootprints(Truth(), options, [](const FootprintPose&) { return Always(1, 1.0); });
  EXPECT_EQ(s.poses, 2 * 64);
  EXPECT_EQ(s.partly_unseen, 0);
  // Centres at columns / rows 2, 7, ..., 37: the block's cells (20, 21) and the semi cell
  // (30, 10) are not among them.
  EXPECT_EQ(s.matrix.Count(1, 1), 2 * 64);
  const std::string json = s.ToJson();
  EXPECT_NE(json.find("\"kind\": \"footprints\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"poses\": 128"), std::string::npos) << json;
}

TEST(eval_Footprints, BadOptionsAndTruthAreNamed) {
  auto error_of = [](const FootprintEvalOptions& options, const ClassGrid& truth) -> std::string {
    try {
      ScoreFootprints(truth, options, [](const FootprintPose&) { return FootprintAnswer{}; });
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  FootprintEvalOptions bad;
  bad.length_m = 0.0;
  EXPECT_NE(error_of(bad, Truth()).find("length_m"), std::string::npos);
  bad = FootprintEvalOptions{};
  bad.width_m = std::nan("");
  EXPECT_NE(error_of(bad, Truth()).find("width_m"), std::string::npos);
  bad = FootprintEvalOptions{};
  bad.step_m = -1.0;
  EXPECT_NE(error_of(bad, Truth()).find("step_m"), std::string::npos);
  bad = FootprintEvalOptions{};
  bad.yaws_deg = {0.0, std::nan("")};
  EXPECT_NE(error_of(bad, Truth()).find("yaws_deg"), std::string::npos);
  bad.yaws_deg.clear();
  EXPECT_NE(error_of(bad, Truth()).find("yaws_deg"), std::string::npos);
  bad = FootprintEvalOptions{};
  bad.min_confidence = 1.5;
  EXPECT_NE(error_of(bad, Truth()).find("min_confidence"), std::string::npos);
  ClassGrid truth = Truth();
  truth.classes(0, 0) = 7;
  EXPECT_NE(error_of(FootprintEvalOptions{}, truth).find("truth.png"), std::string::npos);
}

}  // namespace
}  // namespace ssta
