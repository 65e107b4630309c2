// The disparity scorer (D1, end-point error, density, the noise of good matches, depth edges)
// on a constructed truth and estimate whose scores are known exactly, through the library and
// the `ssta eval disparity` / `eval stereo` commands.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <utility>
#include <string>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "eval_test_helpers.h"
#include "ssta/bench/stereo_bench.h"
#include "ssta/core/error.h"
#include "ssta/eval/disparity_evaluator.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "stereo/synthetic_pair.h"

namespace ssta {
namespace {

using test::TempDir;
using testing::RunResult;
using testing::RunSsta;

// A 4x2 truth and estimate, one pixel per case of the rule (3 px AND 5 %):
//   t 10,  e 10     exact                          good, error 0
//   t 10,  e 13     off by exactly 3 px            good, error 3
//   t 10,  e 13.5   off by 3.5 px (35 %)           bad,  error 3.5
//   t 100, e 104    off by 4 px but only 4 %       good, error 4
//   t 100, e 106    off by 6 px and 6 %            bad,  error 6
//   t 40,  e 0      no estimate                    bad (D1 over all), not matched
//   t 0,   e 50     no truth                       not scored
//   t 20,  e 0      no estimate                    bad (D1 over all), not matched
// Truth pixels 7, matched 5, bad among matched 2: D1 all 4/7, D1 matched 2/5, EPE 16.5/5 =
// 3.3 px, density 5/7.
ImageF Truth() {
  ImageF t(4, 2, 0.0f);
  const float values[] = {10, 10, 10, 100, 100, 40, 0, 20};
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = values[i];
  return t;
}

ImageF Estimate() {
  ImageF e(4, 2, 0.0f);
  const float values[] = {10, 13, 13.5f, 104, 106, 0, 50, 0};
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = values[i];
  return e;
}

// KITTI's 16-bit convention: disparity * 256, 0 = none.
void WriteDisparity(const std::string& path, const ImageF& disparity) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  ImageU16 fixed(disparity.width(), disparity.height(), 0);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    fixed[i] = static_cast<std::uint16_t>(std::lround(disparity[i] * 256.0f));
  }
  WriteImage(fixed, path);
}

void ExpectConstructedScores(const DisparityEvalSummary& s, int pairs) {
  EXPECT_EQ(s.pairs, pairs);
  EXPECT_EQ(s.truth_pixels, 7 * pairs);
  EXPECT_EQ(s.matched_pixels, 5 * pairs);
  EXPECT_EQ(s.bad_matched_pixels, 2 * pairs);
  EXPECT_NEAR(s.D1All(), 4.0 / 7.0, 1e-12);
  EXPECT_NEAR(s.D1Matched(), 2.0 / 5.0, 1e-12);
  EXPECT_NEAR(s.EndPointErrorPx(), 3.3, 1e-9);
  EXPECT_NEAR(s.Density(), 5.0 / 7.0, 1e-12);
  // Every pixel lies within the edge radius of every other: the three 10s, the 40 and the 20
  // have a nearer truth (100) by a bad error, the two 100s, the 40 and the 20 a farther one
  // (10). Fattened: the 10 given 13.5; eroded: none (the 100s' errors are nearer).
  EXPECT_EQ(s.behind_edge_pixels, 5 * pairs);
  EXPECT_EQ(s.fattened_pixels, 1 * pairs);
  EXPECT_EQ(s.front_edge_pixels, 4 * pairs);
  EXPECT_EQ(s.eroded_pixels, 0);
}

TEST(eval_Disparity, ScoresTheRuleOfThreePixelsAndFivePercentAndMissingPixels) {
  ExpectConstructedScores(ScoreDisparity(Truth(), Estimate()), 1);
}

TEST(eval_Disparity, RuleIsConfigurable) {
  // 1 px and 1 %: also the 3 px and the 4 px (4 %) pixels are bad.
  DisparityEvalOptions strict;
  strict.max_error_px = 1.0;
  strict.max_error_ratio = 0.01;
  const DisparityEvalSummary s = ScoreDisparity(Truth(), Estimate(), strict);
  EXPECT_EQ(s.bad_matched_pixels, 4);
  EXPECT_NEAR(s.D1All(), 6.0 / 7.0, 1e-12);
  DisparityEvalOptions bad;
  bad.max_error_ratio = -0.1;
  std::string error;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_EQ(error.rfind("max_error_ratio:", 0), 0u) << error;
}

// The good matches' noise, and how alike the errors of vertical neighbours are, on a 40x40
// truth of 20 px. Errors of (u - 19.5) 0.02 px along each row (-0.39 to 0.39, median 0, median
// absolute deviation 0.2 px) are the same down every column: their neighbours do not differ.
// With the sign flipped on every other row, neighbours differ by twice the error, which is
// sqrt(2) times what independent errors would.
TEST(eval_Disparity, MeasuresTheNoiseOfGoodMatchesAndOfNeighbourDifferences) {
  const ImageF truth(40, 40, 20.0f);
  ImageF alike(40, 40), flipped(40, 40);
  for (int v = 0; v < 40; ++v) {
    for (int u = 0; u < 40; ++u) {
      const double error = (u - 19.5) * 0.02;
      alike(v, u) = static_cast<float>(20.0 + error);
      flipped(v, u) = static_cast<float>(20.0 + (v % 2 == 0 ? error : -error));
    }
  }
  constexpr double kBin = 1.0 / 256.0;  // the histogram's resolution
  const DisparityEvalSummary same = ScoreDisparity(truth, alike);
  EXPECT_NEAR(same.GoodErrorMedianPx(), 0.0, 0.01 + kBin);  // the middle two errors: -0.01, +0.01
  EXPECT_NEAR(same.GoodErrorSigmaPx(), 1.4826 * 0.2, 2.0 * kBin);
  EXPECT_NEAR(same.NeighbourDifferenceSigmaPx(), 0.0, 2.0 * kBin);
  EXPECT_NEAR(same.NeighbourDifferenceRatio(), 0.0, 0.02);
  const DisparityEvalSummary opposite = ScoreDisparity(truth, flipped);
  EXPECT_NEAR(opposite.GoodErrorSigmaPx(), 1.4826 * 0.2, 2.0 * kBin);
  EXPECT_NEAR(opposite.NeighbourDifferenceSigmaPx(), 1.4826 * 0.4, 2.0 * kBin);
  EXPECT_NEAR(opposite.NeighbourDifferenceRatio(), std::sqrt(2.0), 0.02);
  // A bias moves the median and leaves the sigma and the neighbours' differences.
  ImageF biased = alike;
  for (std::size_t i = 0; i < biased.size(); ++i) biased.data()[i] += 0.125f;
  const DisparityEvalSummary shifted = ScoreDisparity(truth, biased);
  EXPECT_NEAR(shifted.GoodErrorMedianPx(), 0.125, 0.01 + kBin);
  EXPECT_NEAR(shifted.GoodErrorSigmaPx(), 1.4826 * 0.2, 2.0 * kBin);
  EXPECT_NEAR(shifted.NeighbourDifferenceSigmaPx(), 0.0, 2.0 * kBin);
  EXPECT_NE(shifted.ToJson().find("\"good_error_median_px\": 0.1"), std::string::npos) << shifted.ToJson();
  // Pooled, the two pairs' good errors are the same set twice: the same sigma.
  DisparityEvalSummary both = same;
  both.Add(opposite);
  EXPECT_NEAR(both.GoodErrorSigmaPx(), 1.4826 * 0.2, 2.0 * kBin);
  // Bad matches and missing pixels are left out: the constructed pair's good errors are 0, 3
  // and 4 px (median 3, absolute deviations 3, 0 and 1: median 1), and none lies above another.
  const DisparityEvalSummary constructed = ScoreDisparity(Truth(), Estimate());
  EXPECT_NEAR(constructed.GoodErrorSigmaPx(), 1.4826, 2.0 * kBin);
  EXPECT_TRUE(std::isnan(constructed.NeighbourDifferenceSigmaPx()));
  EXPECT_TRUE(std::isnan(ScoreDisparity(ImageF(3, 3, 0.0f), ImageF(3, 3, 5.0f)).GoodErrorSigmaPx()));
}

// A depth edge across the image, in either direction (a post's side along the rows, a pit's
// rim along the columns): disparity 10 on one side, 30 on the other, 20 px apart. The 4 px
// on the far side of the edge lie behind it, the 4 px on the near side in front of it. The
// estimate carries the near side 2 px over the edge (2 of the 4 far-side pixels fattened) and
// the far side 1 px back over it (1 of the 4 near-side pixels eroded); a bridge of 20 px in
// between is as bad for the far side as a whole jump.
TEST(eval_Disparity, CountsFattenedAndErodedPixelsBesideDepthEdges) {
  constexpr int kLength = 12, kAcross = 20, kEdge = 10;  // the near side starts at index kEdge
  for (const bool along_rows : {true, false}) {
    SCOPED_TRACE(along_rows ? "edge between columns" : "edge between rows");
    const int w = along_rows ? kAcross : kLength, h = along_rows ? kLength : kAcross;
    ImageF truth(w, h), fattened(w, h), bridged(w, h);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const int across = along_rows ? u : v;
        truth(v, u) = across < kEdge ? 10.0f : 30.0f;
        fattened(v, u) = across < kEdge - 2 || across == kEdge ? 10.0f : 30.0f;
        bridged(v, u) = across == kEdge - 1 ? 20.0f : truth(v, u);
      }
    }
    const DisparityEvalSummary s = ScoreDisparity(truth, fattened);
    EXPECT_EQ(s.behind_edge_pixels, DisparityEvalSummary::kEdgeRadiusPx * kLength);
    EXPECT_EQ(s.front_edge_pixels, DisparityEvalSummary::kEdgeRadiusPx * kLength);
    EXPECT_EQ(s.fattened_pixels, 2 * kLength);
    EXPECT_EQ(s.eroded_pixels, kLength);
    EXPECT_NEAR(s.FattenedShare(), 0.5, 1e-12);
    EXPECT_NEAR(s.ErodedShare(), 0.25, 1e-12);
    const DisparityEvalSummary b = ScoreDisparity(truth, bridged);
    EXPECT_EQ(b.fattened_pixels, kLength);
    EXPECT_EQ(b.eroded_pixels, 0);
    const DisparityEvalSummary exact = ScoreDisparity(truth, truth);
    EXPECT_EQ(exact.fattened_pixels + exact.eroded_pixels, 0);
    // A jump within the rule (3 px and 5 %) is no depth edge.
    ImageF gentle = truth;
    for (std::size_t i = 0; i < gentle.size(); ++i) gentle.data()[i] = gentle.data()[i] > 20.0f ? 12.5f : 10.0f;
    EXPECT_EQ(ScoreDisparity(gentle, gentle).behind_edge_pixels, 0);
  }
  // Without a depth edge the shares are undefined, and pooling adds the counts.
  EXPECT_TRUE(std::isnan(ScoreDisparity(ImageF(5, 5, 20.0f), ImageF(5, 5, 20.0f)).FattenedShare()));
  DisparityEvalSummary pooled = ScoreDisparity(Truth(), Estimate());
  pooled.Add(ScoreDisparity(Truth(), Estimate()));
  EXPECT_NEAR(pooled.FattenedShare(), 0.2, 1e-12);
  EXPECT_NEAR(pooled.ErodedShare(), 0.0, 1e-12);
}

TEST(eval_Disparity, NoTruthGivesNoScoreAndSizesMustAgree) {
  const DisparityEvalSummary empty = ScoreDisparity(ImageF(3, 3, 0.0f), ImageF(3, 3, 5.0f));
  EXPECT_EQ(empty.truth_pixels, 0);
  EXPECT_TRUE(std::isnan(empty.D1All()));
  EXPECT_TRUE(std::isnan(empty.Density()));
  try {
    ScoreDisparity(Truth(), ImageF(3, 2, 0.0f));
    FAIL() << "sizes that differ were accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("3x2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("4x2"), std::string::npos) << e.what();
  }
}

TEST(eval_Disparity, FoldersArePairedByNameAndPooled) {
  TempDir dir;
  // Two frames; the estimate folder as `classify --disparity` writes it (OUT/disparity/).
  for (const char* name : {"a.png", "b.png"}) {
    WriteDisparity(dir / (std::string("gt/") + name), Truth());
    WriteDisparity(dir / (std::string("out/disparity/") + name), Estimate());
  }
  const DisparityEvalSummary s = EvaluateDisparityFiles(dir / "out", dir / "gt");
  ExpectConstructedScores(s, 2);
  ExpectConstructedScores(EvaluateDisparityFiles(dir / "out/disparity/a.png", dir / "gt/a.png"), 1);
}

TEST(eval_Disparity, BadInputNamesTheFile) {
  TempDir dir;
  WriteDisparity(dir / "gt/a.png", Truth());
  WriteDisparity(dir / "gt/b.png", Truth());
  WriteDisparity(dir / "out/a.png", Estimate());
  const auto message = [](const std::function<void()>& run) {
    try {
      run();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // A truth frame without its estimate.
  EXPECT_NE(message([&] { EvaluateDisparityFiles(dir / "out", dir / "gt"); }).find("out/b.png"), std::string::npos);
  // A missing file.
  EXPECT_NE(message([&] { EvaluateDisparityFiles(dir / "out/c.png", dir / "gt/a.png"); }).find("out/c.png"),
            std::string::npos);
  // Another size than the truth.
  WriteDisparity(dir / "small.png", ImageF(3, 2, 1.0f));
  const std::string size_error = message([&] { EvaluateDisparityFiles(dir / "small.png", dir / "gt/a.png"); });
  EXPECT_NE(size_error.find("small.png: size 3x2 differs from the truth"), std::string::npos) << size_error;
  // An 8-bit PNG is not a disparity.
  test::WriteLabels(dir / "labels.png", ImageU8(4, 2, 1));
  EXPECT_NE(message([&] { EvaluateDisparityFiles(dir / "labels.png", dir / "gt/a.png"); }).find("labels.png"),
            std::string::npos);
}

TEST(eval_Disparity, CommandPrintsTheScoresAndWritesJson) {
  TempDir dir;
  WriteDisparity(dir / "gt/a.png", Truth());
  WriteDisparity(dir / "out/a.png", Estimate());
  const RunResult r = RunSsta("eval disparity --pred " + (dir / "out") + " --gt " + (dir / "gt") + " --json " +
                              (dir / "d.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("57.14 % of truth pixels, 40.00 % of matched pixels"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("end-point error (matched): 3.300 px, density: 71.43 %"), std::string::npos) << r.output;
  const std::string json = ReadTextFile(dir / "d.json");
  EXPECT_NE(json.find("\"d1_matched\": 0.4"), std::string::npos) << json;
  EXPECT_NE(json.find("\"epe_px\": 3.3"), std::string::npos) << json;
  EXPECT_NE(r.output.find("behind one 5, 20.00 % fattened"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("in front of one 4, 0.00 % eroded"), std::string::npos) << r.output;
  EXPECT_NE(json.find("\"fattened_share\": 0.2"), std::string::npos) << json;
  EXPECT_NE(json.find("\"front_edge_pixels\": 4"), std::string::npos) << json;
}

TEST(eval_Disparity, CommandBadInputIsOneLineNamingTheFileAndExitTwo) {
  TempDir dir;
  WriteDisparity(dir / "gt/a.png", Truth());
  WriteDisparity(dir / "wrong.png", ImageF(5, 2, 1.0f));
  for (const auto& [arguments, named] :
       {std::pair<std::string, std::string>{"--pred " + (dir / "missing.png") + " --gt " + (dir / "gt/a.png"),
                                            "missing.png"},
        {"--pred " + (dir / "wrong.png") + " --gt " + (dir / "gt/a.png"), "wrong.png: size 5x2"}}) {
    const RunResult r = RunSsta("eval disparity " + arguments);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(r.output.rfind("ssta: error: ", 0), 0u) << r.output;
    EXPECT_NE(r.output.find(named), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << r.output;
  }
}

TEST(eval_Disparity, StereoBenchScoresTheMatcherOnARenderedPair) {
  // A textured plane at 20 px and a square at 36 px: SGBM gets nearly all of it within 3 px.
  TempDir dir;
  const ssta::testing::SyntheticPair pair = ssta::testing::MakePair(200, 120, 20, 36, 90, 30, 50, 8, 72);
  ImageF truth(pair.truth.width(), pair.truth.height(), 0.0f);
  std::int64_t truth_pixels = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    truth[i] = pair.evaluate[i] ? pair.truth[i] : 0.0f;
    truth_pixels += pair.evaluate[i] ? 1 : 0;
  }
  for (const char* name : {"p1.png", "p2.png"}) {
    test::WriteLabels(dir / (std::string("data/left/") + name), pair.left);
    test::WriteLabels(dir / (std::string("data/right/") + name), pair.right);
    WriteDisparity(dir / (std::string("data/gt/") + name), truth);
  }
  StereoMatcherOptions matcher;
  matcher.num_disparities = 48;
  matcher.block_size = 7;
  StereoBenchOptions options;
  options.max_pairs = 1;
  const StereoBenchReport report = RunStereoBench(dir / "data", matcher, options);
  EXPECT_EQ(report.score.pairs, 1);
  EXPECT_EQ(report.match_ms.size(), 1u);
  EXPECT_EQ(report.match_cpu_ms.size(), 1u);
  EXPECT_EQ(report.width, 200);
  EXPECT_EQ(report.score.truth_pixels, truth_pixels);
  EXPECT_LT(report.score.D1All(), 0.05);
  EXPECT_GT(report.score.Density(), 0.95);
  EXPECT_LT(report.score.EndPointErrorPx(), 0.5);

  // Through the command, a config's stereo section; a missing right image is named.
  test::WriteText(dir / "m.yaml", "stereo:\n  num_disparities: 48\n  block_size: 7\n");
  RunResult r = RunSsta("eval stereo --data " + (dir / "data") + " --config " + (dir / "m.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pairs: 2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("median"), std::string::npos) << r.output;
  std::filesystem::remove(dir / "data/right/p2.png");
  r = RunSsta("eval stereo --data " + (dir / "data") + " --config " + (dir / "m.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("right/p2.png: file not found"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ssta
