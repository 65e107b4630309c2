// The command line on ROS bags: inspect, convert, and the topic options of the commands that
// take --sequence.

#include <gtest/gtest.h>

#include <filesystem>

#include "cli_runner.h"
#include "io/support/bag_content.h"
#include "ssta/io/sequence.h"
#include "ssta/mapping/traversability_map.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::RunSsta;

/// A rendered yard of 4 small frames, written as a ROS 1 bag; returns the bag's path.
std::string YardBag(const testing::TempDir& dir) {
  const std::string seq = dir / "seq";
  const auto r = RunSsta("synth --scene yard --frames 4 --width 320 --height 240 --focal 210 --out " + seq);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const std::string bag = dir / "yard.bag";
  testing::WriteRos1Bag(testing::ContentFromSequence(Sequence::Open(seq)), bag, testing::Ros1Compression::kLz4);
  return bag;
}

TEST(BagCli, InspectConvertAndMapABag) {
  testing::TempDir dir;
  const std::string bag = YardBag(dir);
  auto r = RunSsta("inspect --sequence " + bag);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string& expected : std::vector<std::string>{"ros1 bag, 7 topics", "/stereo/left/image_raw", "sensor_msgs/Image", "as a stereo sequence:",
                               "left   /stereo/left/image_raw (calibration /stereo/left/camera_info)", "imu    /imu/data",
                               "poses  " + bag + ":/odom", "frames: 4 paired, 0 skipped"}) {
    EXPECT_NE(r.output.find(expected), std::string::npos) << expected << "\n" << r.output;
  }
  r = RunSsta("convert -q --sequence " + bag + " --out " + (dir / "asl"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Sequence::Open(dir / "asl").frames().size(), 4u);
  r = RunSsta("build-map -q --sequence " + bag + " --imu-topic none --map " + (dir / "m.ot"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(TraversabilityMap::Load(dir / "m.ot").frames_inserted(), 4u);
}

TEST(BagCli, BadBagsAndTopicsAreOneLineNamingThem) {
  testing::TempDir dir;
  const std::string bag = YardBag(dir);
  auto r = RunSsta("classify --sequence " + bag + " --left-topic /cam/left --out " + (dir / "o"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "ssta: error: " + bag + ": --left-topic /cam/left: no such topic in the bag\n");
  r = RunSsta("inspect --sequence " + (dir / "missing.bag"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "ssta: error: " + (dir / "missing.bag") + ": bag not found\n");
  r = RunSsta("build-map --sequence " + bag + " --pose-topic none --map " + (dir / "m.ot"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("has no poses"), std::string::npos) << r.output;
}

TEST(BagCli, InspectDescribesAFolderSequenceToo) {
  const std::string euroc = std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini";
  const auto r = RunSsta("inspect --sequence " + euroc);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* expected : {"asl sequence", "752x480 px", "raw (rectified on read)", "frames: 3 paired, 0 skipped",
                               "imu: ", "poses: "}) {
    EXPECT_NE(r.output.find(expected), std::string::npos) << expected << "\n" << r.output;
  }
}

}  // namespace
}  // namespace ssta
