// The command line on ROS bags: inspect, convert, and the topic options of the commands that
// take --sequence.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli_runner.h"
#include "bags/support/bag_content.h"
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
  EXPECT_EQ(r.output, "ssta: error: " + bag +
                          ": --left-topic /cam/left: no such topic in the bag (image topics: /stereo/left/image_raw, "
                          "/stereo/right/image_raw)\n");
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

/// The last line of `text` (without its newline).
std::string LastLine(const std::string& text) {
  std::string t = text;
  while (!t.empty() && t.back() == '\n') t.pop_back();
  return t.substr(t.rfind('\n') == std::string::npos ? 0 : t.rfind('\n') + 1);
}

// inspect's exit status says whether the recording can be used: 0 when it can, 2 (with the
// reason as its last line) when it cannot.
TEST(BagCli, InspectExitsTwoWhenTheRecordingCannotBeUsed) {
  testing::TempDir dir;
  const std::string bag = YardBag(dir);
  EXPECT_EQ(RunSsta("inspect --sequence " + bag).exit_code, 0);
  // A left topic that is not there: said, with the image topics there are.
  auto r = RunSsta("inspect --sequence " + bag + " --left-topic /cam/left/image_raw");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("ros1 bag, 7 topics"), std::string::npos) << r.output;  // the topics, still
  EXPECT_EQ(LastLine(r.output), "ssta: error: " + bag +
                                    ": --left-topic /cam/left/image_raw: no such topic in the bag (image topics: "
                                    "/stereo/left/image_raw, /stereo/right/image_raw)");
  // A bag without cameras: said, and no advice to give topics it does not have.
  const std::string imu_only = std::string(SSTA_TEST_DATA_DIR) + "/bags/robot_localization/test1.bag";
  r = RunSsta("inspect --sequence " + imu_only);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(LastLine(r.output), "ssta: error: " + imu_only +
                                    ": the bag has no image topics (sensor_msgs/Image or CompressedImage): it holds "
                                    "no camera recording");
  EXPECT_EQ(r.output.find("--left-topic"), std::string::npos) << r.output;
}

// On a folder, inspect lists why frames were skipped, and exits 2 when no frame pairs up.
TEST(BagCli, InspectListsAFoldersSkippedFrames) {
  testing::TempDir dir;
  const std::string seq = dir / "seq";
  ASSERT_EQ(RunSsta("synth --scene yard --frames 4 --width 160 --height 120 --focal 105 --out " + seq).exit_code, 0);
  const Sequence whole = Sequence::Open(seq);
  const std::string left_file = whole.frames()[1].left_path;
  std::filesystem::remove(left_file);
  auto r = RunSsta("inspect --sequence " + seq);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frames: 3 paired, 1 skipped"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  skipped 1 (first at " + std::to_string(whole.frames()[1].timestamp_ns) +
                          " ns): cam0 image missing: " + left_file + "\n"),
            std::string::npos)
      << r.output;
  // No right image listed at all: every left frame is skipped for one reason, and nothing is usable.
  const std::string csv = seq + "/cam1/data.csv";
  std::ifstream in(csv);
  std::string header;
  std::getline(in, header);
  in.close();
  std::ofstream(csv) << header << "\n";
  r = RunSsta("inspect --sequence " + seq);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("  skipped 4 (first at " + std::to_string(whole.frames()[0].timestamp_ns) +
                          " ns): no cam1 frame within 1 ms\n"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(LastLine(r.output), "ssta: error: " + Sequence::Open(seq).root() +
                                    ": no left and right images pair up: no frame to use");
}

// A truncated MCAP (cut mid-chunk, as `head -c` leaves it) is refused by every command, naming
// the file; --allow-truncated maps its complete frames, with the warning in the run's summary
// and the map's notes.
TEST(BagCli, ATruncatedMcapIsRefusedUnlessAllowed) {
  testing::TempDir dir;
  const std::string seq = dir / "seq";
  ASSERT_EQ(RunSsta("synth --scene yard --frames 6 --width 320 --height 240 --focal 210 --out " + seq).exit_code, 0);
  testing::Ros2BagWriterOptions options;
  options.chunk_bytes = 50 * 1024;
  const auto chunks = testing::WriteRos2Bag(testing::ContentFromSequence(Sequence::Open(seq)), dir / "bag", options);
  ASSERT_GE(chunks.size(), 8u);
  const std::string mcap = chunks[7].file;
  std::filesystem::resize_file(mcap, chunks[7].offset + chunks[7].length / 2);
  char last[32];
  std::snprintf(last, sizeof(last), "%lld.%09lld", static_cast<long long>(chunks[6].last_log_time_ns / 1000000000),
                static_cast<long long>(chunks[6].last_log_time_ns % 1000000000));
  const std::string truncated = mcap + ": truncated: the file ends inside a Chunk record at offset " +
                                std::to_string(chunks[7].offset) +
                                ", before the Data End record, the summary and the footer (the recording did not "
                                "finish); the last complete message was logged at " + last + " s";
  const std::string refused = "ssta: error: " + truncated + "; --allow-truncated reads the complete messages\n";
  auto r = RunSsta("build-map --sequence " + mcap + " --map " + (dir / "m.ot"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, refused);
  EXPECT_FALSE(std::filesystem::exists(dir / "m.ot"));
  r = RunSsta("inspect --sequence " + mcap);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(LastLine(r.output) + "\n", refused);
  r = RunSsta("inspect --sequence " + (dir / "bag"));  // the rosbag2 folder holding it
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(LastLine(r.output) + "\n", refused);

  r = RunSsta("build-map --sequence " + mcap + " --allow-truncated --map " + (dir / "m.ot"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string warning = truncated + ": only the complete messages were read (--allow-truncated)";
  EXPECT_NE(r.output.find("warning: " + warning + "\n"), std::string::npos) << r.output;
  const Sequence readable = [&] {
    BagTopics t;
    t.allow_truncated = true;
    return Sequence::Open(mcap, t);
  }();
  EXPECT_LT(readable.frames().size(), 6u);
  const TraversabilityMap map = TraversabilityMap::Load(dir / "m.ot");
  EXPECT_EQ(map.frames_inserted(), readable.frames().size());
  ASSERT_EQ(map.metadata().notes.size(), 1u);
  EXPECT_EQ(map.metadata().notes[0], std::filesystem::path(mcap).filename().string() + ": " + warning);
  r = RunSsta("inspect --sequence " + mcap + " --allow-truncated");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("  warning: " + warning + "\n"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace ssta
