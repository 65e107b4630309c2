// End to end through the built `ssta` binary.

#include <string>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "eval_test_helpers.h"
#include "ssta/files/file_util.h"

namespace ssta {
namespace {

using test::GridYaml;
using test::MakeLabels;
using test::TempDir;
using test::WriteLabels;
using test::WriteText;

using testing::RunResult;
using testing::RunSsta;

class eval_Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    WriteLabels(dir_ / "seq/gt/labels/100.png", MakeLabels({{1, 1}, {2, 3}}));
    WriteLabels(dir_ / "out/labels/100.png", MakeLabels({{1, 1}, {2, 1}}));
    WriteLabels(dir_ / "seq/gt/grid_classes.png", MakeLabels({{1, 2}, {3, 3}}));
    WriteText(dir_ / "seq/gt/grid.yaml", GridYaml("grid_classes.png", 1.0, 0.0, 0.0));
  }
  TempDir dir_;
};

TEST_F(eval_Cli, LabelsPrintsReportAndWritesJsonAndPictures) {
  const RunResult r = RunSsta("eval labels --pred " + (dir_ / "out") + " --gt " + (dir_ / "seq") +
                              " --json " + (dir_ / "s.json") + " --pictures " + (dir_ / "pics"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accuracy 0.7500"), std::string::npos) << r.output;
  const std::string json = ReadTextFile(dir_ / "s.json");
  EXPECT_NE(json.find("\"accuracy\": 0.75"), std::string::npos) << json;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "pics/100.png"));
}

TEST_F(eval_Cli, GridAndQueryRun) {
  WriteLabels(dir_ / "map_classes.png", MakeLabels({{1, 2}, {3, 0}}));
  WriteText(dir_ / "map.yaml", GridYaml("map.pgm", 1.0, 0.0, 0.0));
  RunResult r = RunSsta("eval grid --pred " + (dir_ / "map") + " --gt " + (dir_ / "seq") +
                        " --json " + (dir_ / "g.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accuracy 0.7500"), std::string::npos) << r.output;
  EXPECT_NE(ReadTextFile(dir_ / "g.json").find("\"coverage\": 0.75"), std::string::npos);

  WriteText(dir_ / "q.csv",
            "x,y,z,class,cost,probability,slope_deg,step_m,observations\n"
            "0.5,1.5,0,1,0,1,0,0,1\n");
  r = RunSsta("eval query --pred " + (dir_ / "q.csv") + " --gt " + (dir_ / "seq"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accuracy 1.0000"), std::string::npos) << r.output;
}

TEST_F(eval_Cli, QueryWarnsOnceAboutATruthGridWithoutTheSeenKeyAndStillScoresIt) {
  // eval query reads the truth grid once, warns about it, then scores against that same grid.
  WriteText(dir_ / "q.csv",
            "x,y,z,class,cost,probability,slope_deg,step_m,observations\n"
            "0.5,1.5,0,1,0,1,0,0,1\n");
  const std::string command = "eval query --pred " + (dir_ / "q.csv") + " --gt " + (dir_ / "seq");
  const std::string warning = "warning: " + (dir_ / "seq/gt/grid.yaml") + ": no 'seen: both_cameras'";
  RunResult r = RunSsta(command);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::size_t first = r.output.find(warning);
  ASSERT_NE(first, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(warning, first + 1), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("accuracy 1.0000"), std::string::npos) << r.output;

  WriteText(dir_ / "seq/gt/grid.yaml", GridYaml("grid_classes.png", 1.0, 0.0, 0.0) + "seen: both_cameras\n");
  r = RunSsta(command);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("warning:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("accuracy 1.0000"), std::string::npos) << r.output;
}

TEST_F(eval_Cli, BadInputExitsNonZeroNamingTheFile) {
  WriteText(dir_ / "bad.csv", "x,y,z,class\n0.5,1.5,0,9\n");
  const RunResult r = RunSsta("eval query --pred " + (dir_ / "bad.csv") + " --gt " + (dir_ / "seq"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("bad.csv:2"), std::string::npos) << r.output;
}

TEST_F(eval_Cli, ConfigMustNameTheVehicleTheTruthWasClassedFor) {
  // The truth is classed for the sequence's vehicle.yaml; a config for another vehicle would
  // score one vehicle's classes against another's.
  WriteText(dir_ / "seq/vehicle.yaml", "vehicle:\n  max_slope_deg: 25\n  max_step_m: 0.2\n");
  WriteLabels(dir_ / "map_classes.png", MakeLabels({{1, 2}, {3, 0}}));
  WriteText(dir_ / "map.yaml", GridYaml("map.pgm", 1.0, 0.0, 0.0));
  WriteText(dir_ / "q.csv", "x,y,z,class,cost,probability,slope_deg,step_m,observations\n0.5,1.5,0,1,0,1,0,0,1\n");
  WriteText(dir_ / "same.yaml", "vehicle:\n  max_slope_deg: 25\nstereo:\n  block_size: 7\n");
  WriteText(dir_ / "steeper.yaml", "vehicle:\n  max_slope_deg: 30\n");
  WriteText(dir_ / "broken.yaml", "vehicle:\n  max_step_m: -1\n");
  const std::string gt = " --gt " + (dir_ / "seq");
  for (const std::string& command : {"eval labels --pred " + (dir_ / "out") + gt, "eval grid --pred " + (dir_ / "map") + gt,
                                    "eval query --pred " + (dir_ / "q.csv") + gt}) {
    SCOPED_TRACE(command);
    const RunResult plain = RunSsta(command, false);
    ASSERT_EQ(plain.exit_code, 0) << plain.output;
    const RunResult same = RunSsta(command + " --config " + (dir_ / "same.yaml"), false);
    EXPECT_EQ(same.exit_code, 0) << same.output;
    EXPECT_EQ(same.output, plain.output);
    const RunResult other = RunSsta(command + " --config " + (dir_ / "steeper.yaml"));
    EXPECT_EQ(other.exit_code, 2);
    EXPECT_NE(other.output.find("steeper.yaml: gives vehicle.max_slope_deg 30, but the truth in"), std::string::npos)
        << other.output;
    EXPECT_NE(other.output.find("was classed for 25 (" + (dir_ / "seq/vehicle.yaml") + ")"), std::string::npos)
        << other.output;
    // A later file that sets it back wins.
    const RunResult back = RunSsta(command + " --config " + (dir_ / "steeper.yaml") + " --config " + (dir_ / "same.yaml"), false);
    EXPECT_EQ(back.exit_code, 0) << back.output;
    const RunResult broken = RunSsta(command + " --config " + (dir_ / "broken.yaml"));
    EXPECT_EQ(broken.exit_code, 2);
    EXPECT_NE(broken.output.find("broken.yaml: vehicle.max_step_m"), std::string::npos) << broken.output;
  }
}

TEST_F(eval_Cli, LabelsMadeForAnotherVehicleAreNotScored) {
  // `ssta classify` writes config.yaml beside labels/: eval labels reads its vehicle.
  WriteText(dir_ / "seq/vehicle.yaml", "vehicle:\n  max_slope_deg: 25\n");
  WriteText(dir_ / "out/config.yaml", "vehicle:\n  max_slope_deg: 25\n");
  for (const std::string pred : {"out", "out/labels", "out/labels/"}) {
    const RunResult r = RunSsta("eval labels --pred " + (dir_ / pred) + " --gt " + (dir_ / "seq"));
    EXPECT_EQ(r.exit_code, 0) << pred << ": " << r.output;
    EXPECT_NE(r.output.find("accuracy 0.7500"), std::string::npos) << r.output;
  }
  WriteText(dir_ / "out/config.yaml", "vehicle:\n  max_slope_deg: 20\n");
  for (const std::string pred : {"out", "out/labels"}) {
    const RunResult r = RunSsta("eval labels --pred " + (dir_ / pred) + " --gt " + (dir_ / "seq"));
    EXPECT_EQ(r.exit_code, 2) << pred;
    EXPECT_NE(r.output.find((dir_ / "out/config.yaml") + ": gives vehicle.max_slope_deg 20, but the truth"),
              std::string::npos)
        << r.output;
  }
}

TEST_F(eval_Cli, HelpListsTheSubCommands) {
  const RunResult r = RunSsta("eval --help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* name : {"labels", "grid", "query"}) {
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace ssta
