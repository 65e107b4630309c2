// Maps that lose nothing: one writer per map (build-map, --resume and merge-maps against a map
// another process writes, and two runs at once), and no recording fused twice (the same
// recording under another name, every second frame of it, a bag of it), through the real
// binary on small rendered sequences.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "bags/support/bag_content.h"
#include "lock_holder.h"
#include "ssta/files/file_util.h"
#include "ssta/io/sequence.h"
#include "ssta/mapping/traversability_map.h"
#include "temp_dir.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

using testing::RunSsta;
using testing::TempDir;

/// A rendered yard of 6 frames at 160 x 120 (the same frame times for every seed).
std::string Render(const TempDir& dir, const std::string& name, int seed) {
  const std::string seq = dir / name;
  const auto r = RunSsta("synth --scene yard --frames 6 --width 160 --height 120 --focal 105 --seed " +
                         std::to_string(seed) + " --out " + seq);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return seq;
}

testing::RunResult Build(const std::string& seq, const std::string& map, const std::string& extra = "") {
  return RunSsta("build-map -q --sequence " + seq + " --map " + map + (extra.empty() ? "" : " " + extra));
}

std::vector<std::string> Sequences(const std::string& map) { return TraversabilityMap::Load(map).metadata().sequences; }

TEST(MapWriters, ASecondWriterFailsAtOnceNamingTheMapAndTheHolder) {
  TempDir dir;
  const std::string seq = Render(dir, "seq", 1), seq2 = Render(dir, "seq2", 2);
  const std::string map = dir / "r.ot";
  ASSERT_EQ(Build(seq, map).exit_code, 0);
  const std::string saved = ReadTextFile(map);
  {
    testing::LockHolder holder(map);
    ASSERT_TRUE(holder.held());
    const std::string refusal = "ssta: error: " + map + ": another process is writing this map (pid " +
                                std::to_string(holder.pid()) + ": ";
    for (const std::string& writer : {"build-map -q --sequence " + seq2 + " --map " + map + " --resume",
                                      "build-map -q --sequence " + seq2 + " --map " + map,
                                      "merge-maps -q " + map + " --out " + map}) {
      const auto r = RunSsta(writer);
      EXPECT_EQ(r.exit_code, 2) << writer << "\n" << r.output;
      EXPECT_EQ(r.output.rfind(refusal, 0), 0u) << writer << "\n" << r.output;
      EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    }
    // Readers take no lock: they read the last complete save, which no writer touched.
    const auto r = RunSsta("query --map " + map + " --at 0.5,0");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(ReadTextFile(map), saved);
    holder.Kill();  // the holder dies without releasing: its lock file stays
    EXPECT_TRUE(fs::exists(MapWriteLock::LockPath(map)));
  }
  const auto r = Build(seq2, map, "--resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Sequences(map), (std::vector<std::string>{"seq", "seq2"}));
  EXPECT_FALSE(fs::exists(MapWriteLock::LockPath(map))) << "build-map releases its lock";
}

// The scenario: two resumed runs on one map at once. Whichever order the processes
// run in, no run may succeed and lose its frames: each ends with its sequence in the map, or
// fails naming the other writer.
TEST(MapWriters, TwoRunsAtOnceLoseNoRunSilently) {
  TempDir dir;
  const std::string seq = Render(dir, "seq", 1), seq2 = Render(dir, "seq2", 2), seq3 = Render(dir, "seq3", 3);
  const std::string map = dir / "r.ot";
  ASSERT_EQ(Build(seq, map).exit_code, 0);
  testing::RunResult second, third;
  std::thread a([&] { second = Build(seq2, map, "--resume"); });
  std::thread b([&] { third = Build(seq3, map, "--resume"); });
  a.join();
  b.join();
  std::vector<std::string> expected{"seq"};
  for (const auto& [run, name] : {std::pair{&second, "seq2"}, std::pair{&third, "seq3"}}) {
    if (run->exit_code == 0) {
      expected.push_back(name);
    } else {
      EXPECT_EQ(run->exit_code, 2) << run->output;
      EXPECT_NE(run->output.find(map + ": another process is writing this map (pid "), std::string::npos)
          << run->output;
    }
  }
  EXPECT_GE(expected.size(), 2u) << "one of the two runs must have written the map";
  std::vector<std::string> held = Sequences(map);
  std::sort(held.begin(), held.end());
  EXPECT_EQ(held, expected) << second.output << third.output;
}

TEST(RecordingOverlap, AFolderAndABagOfOneRecordingHaveOneFingerprint) {
  TempDir dir;
  const std::string seq = Render(dir, "seq", 1);
  const std::string bag = dir / "seq.bag";
  testing::WriteRos1Bag(testing::ContentFromSequence(Sequence::Open(seq)), bag);
  ASSERT_EQ(Build(seq, dir / "folder.ot").exit_code, 0);
  const auto r = Build(bag, dir / "bag.ot", "--imu-topic none --config " + seq + "/vehicle.yaml");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto folder = TraversabilityMap::Load(dir / "folder.ot").metadata().recordings;
  const auto from_bag = TraversabilityMap::Load(dir / "bag.ot").metadata().recordings;
  ASSERT_EQ(folder.size(), 1u);
  ASSERT_EQ(from_bag.size(), 1u);
  EXPECT_GE(folder[0].frames(), 4u);
  EXPECT_EQ(folder[0].stamps_ns, from_bag[0].stamps_ns);
  EXPECT_EQ(folder[0].Digest(), from_bag[0].Digest());
  const auto merge = RunSsta("merge-maps -q " + (dir / "folder.ot") + " " + (dir / "bag.ot") + " --out " + (dir / "m.ot"));
  EXPECT_EQ(merge.exit_code, 2);
  EXPECT_NE(merge.output.find((dir / "folder.ot") + " and " + (dir / "bag.ot") +
                              " hold frames of one recording: 'seq' (" + std::to_string(folder[0].frames()) +
                              " frames) and 'seq.bag'"),
            std::string::npos)
      << merge.output;
}

TEST(RecordingOverlap, MergeRefusesTheSameRecordingTwiceUnlessAllowed) {
  TempDir dir;
  const std::string seq = Render(dir, "h1", 1), other = Render(dir, "h2", 2);
  fs::copy(seq, dir / "h1_again", fs::copy_options::recursive);
  ASSERT_EQ(Build(seq, dir / "h1.ot").exit_code, 0);
  ASSERT_EQ(Build(seq, dir / "h1_every2.ot", "--every 2").exit_code, 0);
  ASSERT_EQ(Build(dir / "h1_again", dir / "again.ot").exit_code, 0);
  ASSERT_EQ(Build(other, dir / "h2.ot").exit_code, 0);
  const auto h1 = TraversabilityMap::Load(dir / "h1.ot").metadata().recordings.at(0);
  const auto h2 = TraversabilityMap::Load(dir / "h2.ot").metadata().recordings.at(0);
  ASSERT_EQ(h1.stamps_ns, h2.stamps_ns) << "the renders share their frame times: only the images tell them apart";
  auto merge = [&](const std::string& inputs) { return RunSsta("merge-maps -q " + inputs + " --out " + (dir / "m.ot")); };
  auto r = merge((dir / "h1.ot") + " " + (dir / "again.ot"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("'h1' (" + std::to_string(h1.frames()) + " frames) and 'h1_again' (" +
                          std::to_string(h1.frames()) + " frames) share " + std::to_string(h1.frames())),
            std::string::npos)
      << r.output;
  r = merge((dir / "h1.ot") + " " + (dir / "h1_every2.ot"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find((dir / "h1.ot") + " and " + (dir / "h1_every2.ot") + " hold frames of one recording"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("--allow-overlap merges them anyway"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "m.ot"));
  r = merge((dir / "h1.ot") + " " + (dir / "h1_every2.ot") + " --allow-overlap");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Sequences(dir / "m.ot"), (std::vector<std::string>{"h1", "h1"}));
  r = merge((dir / "h1.ot") + " " + (dir / "h2.ot"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(TraversabilityMap::Load(dir / "m.ot").metadata().recordings.size(), 2u);
}

TEST(RecordingOverlap, ResumeRefusesARecordingTheMapHoldsFromAFolderOrABag) {
  TempDir dir;
  const std::string seq = Render(dir, "seq", 1), other = Render(dir, "seq2", 2);
  fs::copy(seq, dir / "again", fs::copy_options::recursive);
  const std::string bag = dir / "seq.bag";
  testing::WriteRos1Bag(testing::ContentFromSequence(Sequence::Open(seq)), bag);
  const std::string bag_args = "--resume --imu-topic none --config " + seq + "/vehicle.yaml";
  const std::string map = dir / "r.ot", every2 = dir / "every2.ot";
  ASSERT_EQ(Build(seq, map).exit_code, 0);
  ASSERT_EQ(Build(seq, every2, "--every 2").exit_code, 0);
  const std::string before = ReadTextFile(map);
  for (const auto& [input, args, target] :
       {std::tuple{std::string(dir / "again"), std::string("--resume"), map}, std::tuple{bag, bag_args, map},
        std::tuple{std::string(dir / "again"), std::string("--resume"), every2}}) {
    const auto r = Build(input, target, args);
    EXPECT_EQ(r.exit_code, 2) << input << "\n" << r.output;
    const std::string name = fs::path(input).filename().string();
    EXPECT_EQ(r.output.rfind("ssta: error: " + target + ": already holds the recording 'seq' (", 0), 0u) << r.output;
    EXPECT_NE(r.output.find("and '" + name + "' shares its frame at 1600000000100000000 ns (same time, same image)"),
              std::string::npos)
        << r.output;
  }
  EXPECT_EQ(ReadTextFile(map), before) << "a refused run changes nothing";
  // Allowed: fused, and both recordings are listed.
  auto r = Build(bag, map, bag_args + " --allow-overlap");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Sequences(map), (std::vector<std::string>{"seq", "seq.bag"}));
  // Another recording at the same times resumes.
  r = Build(other, map, "--resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto recordings = TraversabilityMap::Load(map).metadata().recordings;
  ASSERT_EQ(recordings.size(), 3u);
  EXPECT_EQ(recordings[2].sequence, "seq2");
  // Continuing an interrupted run of the map's last recording is no overlap.
  r = Build(other, map, "--resume");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(TraversabilityMap::Load(map).metadata().recordings.size(), 3u);
}

}  // namespace
}  // namespace ssta
