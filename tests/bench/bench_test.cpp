#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "cli_runner.h"
#include "ssta/files/file_util.h"
#include "ssta/bench/pipeline_bench.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

TEST(Bench, QuantileInterpolatesBetweenTheNearestRanks) {
  // Sorted: 1 2 3 4; rank 0.5 * 3 = 1.5 -> 2.5; rank 0.9 * 3 = 2.7 -> 3.7.
  EXPECT_DOUBLE_EQ(Quantile({4, 1, 3, 2}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(Quantile({4, 1, 3, 2}, 0.9), 3.7);
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 3}, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 3}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 3}, 1.0), 5.0);
  EXPECT_DOUBLE_EQ(Quantile({7}, 0.9), 7.0);
  EXPECT_TRUE(std::isnan(Quantile({}, 0.5)));
  EXPECT_THROW(Quantile({1, 2}, 1.5), InternalError);
}

TEST(Bench, SummarizeGivesMedianP90MeanAndExtremes) {
  // 1..10: median 5.5, p90 at rank 8.1 -> 9.1, mean 5.5.
  std::vector<double> samples;
  for (int i = 10; i >= 1; --i) samples.push_back(i);
  const SampleStats s = Summarize(samples);
  EXPECT_EQ(s.count, 10);
  EXPECT_DOUBLE_EQ(s.median, 5.5);
  EXPECT_NEAR(s.p90, 9.1, 1e-12);
  EXPECT_DOUBLE_EQ(s.mean, 5.5);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 10.0);
  const SampleStats none = Summarize({});
  EXPECT_EQ(none.count, 0);
  EXPECT_TRUE(std::isnan(none.median));
}

BenchReport KnownReport() {
  BenchReport r;
  r.source = "test";
  r.width = 640;
  r.height = 480;
  r.matcher = "sgbm";
  r.warmup_frames = 1;
  r.threads = 2;
  r.rows.push_back({"match", {10, 20, 30, 40}, {}});
  r.rows.push_back({"map update", {4, 5, 6, 5}, {8, 10, 12, 10}});
  r.with_map = true;
  r.series = {{0, 4, 100, 1000, 50}, {1, 5, 100, 1300, 51}, {2, 6, 100, 1500, 52}, {3, 5, 100, 1900, 52.5}};
  r.peak_rss_mib = 123.45;
  r.whole_run_frames = 4;
  r.whole_run_wall_ms = 160.0;
  r.whole_run_cpu_ms = 250.0;
  return r;
}

TEST(Bench, TablePrintsOneFixedWidthLinePerRow) {
  const std::string table = KnownReport().Table();
  // match: median 25, p90 at rank 2.7 -> 37, no CPU, 1000 / 25 = 40 frames/s.
  EXPECT_NE(table.find("match                        25.00        37.00              -       40.0\n"),
            std::string::npos)
      << table;
  // map update: median 5, p90 at rank 2.7 -> 5.7, CPU median 10, 200 frames/s.
  EXPECT_NE(table.find("map update                    5.00         5.70          10.00      200.0\n"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("640x480, sgbm, 4 frames measured (1 warm-up not counted), 2 hardware threads"),
            std::string::npos);
  // 4 frames in 160 ms: 25 frames/s, 40 ms each.
  EXPECT_NE(table.find("whole run (images read, classified, fused as build-map does): 4 frames in 160.0 ms "
                       "(CPU 250.0 ms): 25.0 frames/s, 40.00 ms per frame\n"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("peak memory (max RSS): 123.5 MiB; resident 50.0 MiB after the first measured frame, "
                       "52.5 MiB after the last\n"),
            std::string::npos)
      << table;
  // 1000 -> 1900 nodes over 3 steps: 300 per frame; halves {4, 5} and {6, 5}.
  EXPECT_NE(table.find("map: 1000 nodes after the first measured frame, 1900 after the last (300 per frame); "
                       "update median 4.50 ms in the first half, 5.50 ms in the second"),
            std::string::npos)
      << table;
}

TEST(Bench, JsonHoldsTheStatisticsOfEveryRow) {
  const std::string json = KnownReport().Json();
  EXPECT_NE(json.find("\"name\": \"match\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"median\": 25"), std::string::npos) << json;
  EXPECT_NE(json.find("\"p90\": 37"), std::string::npos) << json;
  EXPECT_NE(json.find("\"frames_per_s\": 40"), std::string::npos) << json;
  EXPECT_NE(json.find("\"cpu_ms\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("[3, 5, 100, 1900, 52.5]"), std::string::npos) << json;
  EXPECT_NE(json.find("\"frames\": 4"), std::string::npos) << json;
  EXPECT_NE(json.find("\"whole_run\": {\n    \"frames\": 4,\n    \"wall_ms\": 160,\n    \"cpu_ms\": 250,\n    "
                      "\"frames_per_s\": 25\n  }"),
            std::string::npos)
      << json;
}

TEST(Bench, WholeRunFramesPerSecondIsFramesOverWallTime) {
  BenchReport r;
  EXPECT_TRUE(std::isnan(r.WholeRunFramesPerSecond()));
  EXPECT_EQ(r.Table().find("whole run"), std::string::npos);
  r.whole_run_frames = 3;
  r.whole_run_wall_ms = 120.0;
  EXPECT_DOUBLE_EQ(r.WholeRunFramesPerSecond(), 25.0);
}

TEST(Bench, OptionsNameTheBadKey) {
  PipelineBenchOptions o;
  std::string error;
  EXPECT_TRUE(o.IsValid(&error));
  o.warmup_frames = -1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error.rfind("warmup:", 0), 0u) << error;
}

TEST(Bench, CommandRendersFramesAndReportsEveryStageWithTheMap) {
  testing::TempDir dir;
  const testing::RunResult r = testing::RunSsta(
      "bench --frames 2 --warmup 1 --width 320 --height 240 --focal 210 --map --json " + dir / "bench.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* row : {"read images", "rectify", "match", "triangulate", "normals", "segment", "analyze", "frame (Process)",
                          "map update", "end to end", "pipelined interval", "pipelined latency",
                          "whole run (images read, classified, fused as build-map does): 2 frames in ",
                          "peak memory", "map: "}) {
    EXPECT_NE(r.output.find(row), std::string::npos) << row << "\n" << r.output;
  }
  const std::string json = ReadTextFile(dir / "bench.json");
  EXPECT_NE(json.find("\"frames\": 2"), std::string::npos) << json;
  EXPECT_NE(json.find("\"name\": \"end to end\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"name\": \"pipelined interval\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"name\": \"read images\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"whole_run\": {\n    \"frames\": 2,"), std::string::npos) << json;
}

TEST(Bench, CommandRunsOnARecordedSequenceWithoutTheMap) {
  const testing::RunResult r = testing::RunSsta(std::string("bench --sequence ") + SSTA_TEST_DATA_DIR +
                                                "/kitti-street-pair --warmup 0 --frames 1 --config " +
                                                SSTA_CONFIG_DIR + "/sensors/kitti.yaml");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("kitti-street-pair: 1241x376, sgbm, 1 frames measured"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame (Process)"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("map update"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("whole run (images read, classified, fused as build-map does): 1 frames in "),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("refine (online)"), std::string::npos) << r.output;
}

TEST(Bench, RefineAddsTheOnlineRefinementRow) {
  const testing::RunResult r = testing::RunSsta(std::string("bench --sequence ") + SSTA_TEST_DATA_DIR +
                                                "/euroc-v1-01-mini --warmup 0 --frames 3 --refine --config " +
                                                SSTA_CONFIG_DIR + "/sensors/euroc.yaml");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("refine (online)"), std::string::npos) << r.output;
}

TEST(Bench, CommandRejectsTooFewFramesByName) {
  const testing::RunResult r = testing::RunSsta("bench --frames 0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--frames"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ssta
