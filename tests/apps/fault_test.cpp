// Faults around `ssta build-map`, through the real binary on a small rendered sequence:
// SIGKILL at several points (the map or last checkpoint on disk loads, and --resume finishes
// the job as one uninterrupted run would), SIGTERM, a full disk while saving (the previous map
// stays), and an IMU whose reading at rest is not gravity.
//
// The kill points are partly time based, but no assertion depends on timing: each must hold
// wherever the kill lands.

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

extern char** environ;

namespace fs = std::filesystem;

namespace ssta {
namespace {

using testing::RunSsta;
using testing::TempDir;

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

bool HasTemporaryFile(const fs::path& dir, const std::string& name) {
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename().string().rfind(name + ".tmp", 0) == 0) return true;
  }
  return false;
}

/// The map as CSV text (every voxel, ExportCsv), to compare two maps exactly.
std::string MapCsv(const std::string& map, const TempDir& dir, const std::string& name) {
  ExportCsv(TraversabilityMap::Load(map), dir / name);
  return Slurp(dir / name);
}

/// A small rendered yard (12 frames, 320 x 240) and a config that checkpoints every frame.
class BuildMapFaults : public ::testing::Test {
 protected:
  void SetUp() override {
    auto r = RunSsta("synth --scene yard --frames 12 --width 320 --height 240 --focal 260 --out " + seq_);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::ofstream(config_) << "map:\n  checkpoint_every_frames: 1\n";
  }

  std::string BuildMapArgs(const std::string& map) const {
    return "build-map -q --sequence " + seq_ + " --config " + config_ + " --map " + map;
  }

  /// The map of one uninterrupted run, as CSV, and its frame count.
  void Reference(std::string* csv, std::uint64_t* frames) {
    const std::string map = dir_ / "reference.ot";
    const auto r = RunSsta(BuildMapArgs(map));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    *frames = TraversabilityMap::Load(map).frames_inserted();
    *csv = MapCsv(map, dir_, "reference.csv");
    ASSERT_GT(*frames, 6u) << "the rendered sequence should give a usable map";
  }

  /// Starts build-map on `map` (no shell), its output in a file.
  pid_t Start(const std::string& map) {
    const std::vector<std::string> args = {SSTA_BINARY, "build-map", "-q", "--sequence", seq_,
                                           "--config",  config_,     "--map", map};
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string log = dir_ / "killed.log";
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, SSTA_BINARY, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    EXPECT_EQ(rc, 0);
    return pid;
  }

  /// Waits until `ready()` or the process has ended; true when it is still running.
  static bool WaitUntil(pid_t pid, const std::function<bool()>& ready, int* status) {
    for (;;) {
      if (::waitpid(pid, status, WNOHANG) == pid) return false;
      if (ready()) return true;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }

  /// Kills build-map with `signal` once `ready()` holds (or lets it finish), then checks what a
  /// user relies on: whatever map is on disk loads, and build-map --resume (or a new run when
  /// nothing was saved) completes it into exactly the map one uninterrupted run gives.
  void KillThenResume(int signal, const std::function<bool()>& ready) {
    std::string reference_csv;
    std::uint64_t reference_frames = 0;
    Reference(&reference_csv, &reference_frames);
    if (HasFailure()) return;

    const pid_t pid = Start(map_);
    ASSERT_GT(pid, 0);
    int status = 0;
    const bool killed = WaitUntil(pid, ready, &status);
    if (killed) {
      ::kill(pid, signal);
      ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    }
    // Where the kill landed, for the record (the assertions below hold wherever it lands).
    RecordProperty("killed_while_running", killed ? "yes" : "no");
    RecordProperty("temporary_file_left", HasTemporaryFile(dir_.path(), "m.ot") ? "yes" : "no");
    SCOPED_TRACE(Slurp(dir_ / "killed.log"));
    if (signal == SIGTERM && WIFEXITED(status)) {
      // A clean stop: the one-line message, exit status 2 unless it had finished already.
      const std::string log = Slurp(dir_ / "killed.log");
      EXPECT_TRUE(WEXITSTATUS(status) == 0 || log.find("ssta: error: interrupted") != std::string::npos) << log;
    }

    std::string resume = " --resume";
    if (fs::exists(map_)) {
      std::uint64_t frames = 0;
      ASSERT_NO_THROW(frames = TraversabilityMap::Load(map_).frames_inserted()) << "the map on disk must load";
      RecordProperty("frames_on_disk_after_kill", std::to_string(frames));
      EXPECT_LE(frames, reference_frames);
    } else {
      resume = "";  // killed before the first checkpoint: nothing to resume
    }
    const auto r = RunSsta(BuildMapArgs(map_) + resume);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const TraversabilityMap done = TraversabilityMap::Load(map_);
    EXPECT_EQ(done.frames_inserted(), reference_frames) << "no frame lost, none fused twice";
    EXPECT_EQ(done.metadata().sequences.size(), 1u);
    EXPECT_EQ(MapCsv(map_, dir_, "resumed.csv"), reference_csv);
    // A kill inside a save leaves its temporary file; the finishing run's saves remove it.
    EXPECT_FALSE(HasTemporaryFile(dir_.path(), "m.ot"));
  }

  /// Kill after `ms` milliseconds.
  void KillAfter(int ms) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    KillThenResume(SIGKILL, [deadline] { return std::chrono::steady_clock::now() >= deadline; });
  }

  /// True once `n` checkpoints have replaced the map file (each save renames a new file over
  /// it: a new inode). Polled, so a save can be missed when frames are faster than the poll;
  /// then it fires later, which is just another kill point.
  std::function<bool()> CheckpointsSaved(int n) {
    return [this, n, seen = 0, inode = ino_t{0}]() mutable {
      struct stat st {};
      if (::stat(map_.c_str(), &st) == 0 && st.st_ino != inode) {
        inode = st.st_ino;
        ++seen;
      }
      return seen >= n;
    };
  }

  TempDir dir_;
  const std::string seq_ = dir_ / "seq";
  const std::string config_ = dir_ / "small.yaml";
  const std::string map_ = dir_ / "m.ot";
};

TEST_F(BuildMapFaults, SigkillRightAtTheStart) { KillAfter(0); }
TEST_F(BuildMapFaults, SigkillAfter400Ms) { KillAfter(400); }
TEST_F(BuildMapFaults, SigkillAfter800Ms) { KillAfter(800); }

TEST_F(BuildMapFaults, SigkillAsSoonAsTheFirstCheckpointExists) {
  KillThenResume(SIGKILL, CheckpointsSaved(1));
}

TEST_F(BuildMapFaults, SigkillAfterTheFourthCheckpoint) { KillThenResume(SIGKILL, CheckpointsSaved(4)); }

TEST_F(BuildMapFaults, SigkillAfterTheNinthCheckpoint) { KillThenResume(SIGKILL, CheckpointsSaved(9)); }

TEST_F(BuildMapFaults, SigkillWhileTheFirstCheckpointIsBeingWritten) {
  // The temporary file of a save exists from its open to the rename: killed inside a write.
  KillThenResume(SIGKILL, [this] { return HasTemporaryFile(dir_.path(), "m.ot"); });
}

TEST_F(BuildMapFaults, SigkillWhileALaterCheckpointIsBeingWritten) {
  auto five = CheckpointsSaved(5);
  bool after_five = false;
  KillThenResume(SIGKILL, [&] {
    after_five = after_five || five();
    return after_five && HasTemporaryFile(dir_.path(), "m.ot");
  });
}

TEST_F(BuildMapFaults, SigtermStopsCleanlyAfterSaving) { KillThenResume(SIGTERM, CheckpointsSaved(3)); }

TEST_F(BuildMapFaults, AFullDiskFailsTheSaveAndKeepsThePreviousMap) {
  auto r = RunSsta(BuildMapArgs(map_));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string before = Slurp(map_);
  ::setenv("SSTA_TEST_WRITE_FAULT_AFTER_BYTES", "4096", 1);
  r = RunSsta(BuildMapArgs(map_));
  ::unsetenv("SSTA_TEST_WRITE_FAULT_AFTER_BYTES");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, "ssta: error: " + map_ + ": write failed: No space left on device\n");
  EXPECT_EQ(Slurp(map_), before) << "the previous map must stay as it was";
  EXPECT_FALSE(HasTemporaryFile(dir_.path(), "m.ot"));
  EXPECT_NO_THROW(TraversabilityMap::Load(map_));
}

TEST_F(BuildMapFaults, AnUnwritableMapPathFailsWithAOneLineError) {
  // A regular file where the folder should be (chmod would not stop root).
  std::ofstream(dir_ / "file") << "x";
  const std::string map = dir_ / "file/m.ot";
  const auto r = RunSsta(BuildMapArgs(map));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // Refused while the command line is parsed, before any frame is classified.
  EXPECT_EQ(r.output, "ssta: error: --map: " + map + ": " + (dir_ / "file") + " is a file, not a folder\n");
}

TEST_F(BuildMapFaults, AnImuAtRestReadingGIsRejectedNamingTheFile) {
  // Rewrite the accelerometer columns in g (a common unit mix-up).
  const std::string csv = seq_ + "/imu0/data.csv";
  std::istringstream in(Slurp(csv));
  std::ostringstream out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') {
      out << line << "\n";
      continue;
    }
    std::istringstream fields(line);
    std::string f;
    for (int c = 0; std::getline(fields, f, ','); ++c) {
      out << (c ? "," : "") << (c >= 4 ? std::to_string(std::stod(f) / 9.81) : f);
    }
    out << "\n";
  }
  std::ofstream(csv) << out.str();
  const auto r = RunSsta(BuildMapArgs(map_));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output.rfind("ssta: error: " + csv + ": the IMU at rest reads 1", 0), 0u) << r.output;
  EXPECT_NE(r.output.find("max_rest_gravity_error_mps2"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(map_));
  // The threshold is a config key: raised far enough, the run goes on.
  std::ofstream(config_, std::ios::app) << "attitude:\n  max_rest_gravity_error_mps2: 9\n";
  EXPECT_EQ(RunSsta(BuildMapArgs(map_)).exit_code, 0);
}

}  // namespace
}  // namespace ssta
