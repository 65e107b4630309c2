// Atomic writes: a write that fails (full disk, unwritable path) names the file and leaves the
// previous file as it was, with no temporary file left behind.

#include "ssta/files/file_util.h"

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "lock_holder.h"
#include "ssta/core/error.h"
#include "temp_dir.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

int EntriesIn(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++n;
  }
  return n;
}

/// Sets SSTA_TEST_WRITE_FAULT_AFTER_BYTES for one scope.
class WriteFault {
 public:
  explicit WriteFault(const std::string& bytes) { ::setenv("SSTA_TEST_WRITE_FAULT_AFTER_BYTES", bytes.c_str(), 1); }
  ~WriteFault() { ::unsetenv("SSTA_TEST_WRITE_FAULT_AFTER_BYTES"); }
};

TEST(WriteTextAtomically, FullDiskFailsNamingTheFileAndKeepsThePreviousContent) {
  testing::TempDir dir;
  const std::string path = dir / "report.json";
  WriteTextAtomically(path, "previous content\n");
  {
    const WriteFault fault("10");
    try {
      WriteTextAtomically(path, std::string(1000, 'x'));
      FAIL() << "the write should have failed";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
      EXPECT_NE(message.find("No space left on device"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
  EXPECT_EQ(Slurp(path), "previous content\n");
  EXPECT_EQ(EntriesIn(dir.path()), 1) << "the temporary file must be removed";
}

TEST(WriteTextAtomically, WritesBelowTheInjectedLimitSucceed) {
  testing::TempDir dir;
  const std::string path = dir / "small.txt";
  const WriteFault fault("10");
  WriteTextAtomically(path, "0123456789");
  EXPECT_EQ(Slurp(path), "0123456789");
}

TEST(WriteTextAtomically, AFileInPlaceOfTheFolderIsAClearError) {
  // Works as root too (chmod does not stop root): the "folder" is a regular file.
  testing::TempDir dir;
  const std::string not_a_dir = dir / "plain_file";
  WriteTextAtomically(not_a_dir, "x");
  try {
    WriteTextAtomically(not_a_dir + "/out.txt", "y");
    FAIL() << "the write should have failed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(not_a_dir + "/out.txt: "), std::string::npos) << e.what();
  }
  EXPECT_EQ(Slurp(not_a_dir), "x");
}

TEST(WriteTextAtomically, AFolderInPlaceOfTheFileIsAClearErrorAndStaysAsItWas) {
  testing::TempDir dir;
  const std::string target = dir / "map.ot";
  fs::create_directory(target);
  WriteTextAtomically(target + "/keep.txt", "kept");
  try {
    WriteTextAtomically(target, "y");
    FAIL() << "the write should have failed";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(target + ": ", 0), 0u) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(target));
  EXPECT_EQ(Slurp(target + "/keep.txt"), "kept");
  EXPECT_EQ(EntriesIn(dir.path()), 1) << "the temporary file must be removed";
}

TEST(WriteTextAtomically, AMissingFolderIsAClearError) {
  testing::TempDir dir;
  const std::string path = dir / "no/such/folder/out.txt";
  try {
    WriteTextAtomically(path, "y");
    FAIL() << "the write should have failed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_EQ(EntriesIn(dir.path()), 0);
}

TEST(WriteFileAtomically, AWriterKilledMidWriteLeavesItsTemporaryForTheNextMapSaveToRemove) {
  testing::TempDir dir;
  const std::string path = dir / "map.ot";
  WriteTextAtomically(path, "first\n");
  // A child process starts to replace the file and is killed (SIGKILL) halfway through.
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    WriteFileAtomically(path, [](const std::string& tmp) {
      std::ofstream(tmp) << "half of a ";
      ::raise(SIGKILL);
    });
    ::_exit(1);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  const std::string leftover = path + ".tmp" + std::to_string(child);
  std::vector<std::string> leftovers;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    if (e.path().string().rfind(leftover + "-", 0) == 0) leftovers.push_back(e.path().string());
  }
  ASSERT_EQ(leftovers.size(), 1u);  // the killed writer's file, named with its pid
  EXPECT_EQ(Slurp(leftovers[0]), "half of a ");
  EXPECT_EQ(Slurp(path), "first\n");  // the map itself is untouched
  // Files that must stay: a live process's write in progress (this process's parent stands
  // in for one), another file's leftovers, and names that only resemble the pattern.
  const std::vector<std::string> keep = {
      path + ".tmp" + std::to_string(::getppid()) + "-1a2b",
      std::string(dir / "other.ot.tmp") + std::to_string(child) + "-1a2b",
      path + ".tmp" + std::to_string(child) + "-notHex",
      path + ".tmp" + std::to_string(child),
      path + ".tmpabc",
  };
  for (const std::string& k : keep) std::ofstream(k) << "x";
  // A write without remove_stale leaves them all; one with it removes the killed writer's.
  WriteTextAtomically(path, "second\n");
  EXPECT_TRUE(fs::exists(leftovers[0]));
  WriteFileAtomically(path, [](const std::string& tmp) { std::ofstream(tmp) << "third\n"; }, /*remove_stale=*/true);
  EXPECT_EQ(Slurp(path), "third\n");
  EXPECT_FALSE(fs::exists(leftovers[0])) << leftovers[0] << " should have been removed";
  for (const std::string& k : keep) EXPECT_TRUE(fs::exists(k)) << k;
  EXPECT_EQ(EntriesIn(dir.path()), 1 + static_cast<int>(keep.size()));
}

TEST(RemoveFrameFiles, RemovesOnlyFilesNamedByATimestampWithTheExtension) {
  testing::TempDir dir;
  const fs::path d = dir.path();
  for (const char* name : {"1600000000100000000.png", "17.png", "1600000000100000000.json", "a17.png", "17a.png",
                           "notes.txt", ".png"}) {
    std::ofstream(d / name) << "x";
  }
  fs::create_directory(d / "18.png");  // a folder of that name is not a frame file
  EXPECT_EQ(RemoveFrameFiles(d.string(), ".png"), 2);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(d)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{".png", "1600000000100000000.json", "17a.png", "18.png", "a17.png",
                                            "notes.txt"}));
  EXPECT_EQ(RemoveFrameFiles((d / "missing").string(), ".png"), 0);
}

/// The message a MapWriteLock on `map` fails with ("" when it is taken).
std::string LockRefusal(const std::string& map) {
  try {
    const MapWriteLock lock(map);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MapWriteLock, ASecondWriterFailsNamingTheMapAndTheHolder) {
  testing::TempDir dir;
  const std::string map = dir / "r.ot";
  {
    const MapWriteLock first(map);
    EXPECT_TRUE(fs::exists(MapWriteLock::LockPath(map)));
    // In the same process too (another thread of a Python program): one writer per map.
    const std::string refusal = LockRefusal(map);
    EXPECT_EQ(refusal.rfind(map + ": another process is writing this map (pid " + std::to_string(::getpid()) + ": ", 0),
              0u)
        << refusal;
    EXPECT_NE(refusal.find("files_test"), std::string::npos) << "the holder's command: " << refusal;
    EXPECT_EQ(refusal.find('\n'), std::string::npos) << refusal;
  }
  EXPECT_FALSE(fs::exists(MapWriteLock::LockPath(map))) << "a released lock leaves its file";
  EXPECT_EQ(LockRefusal(map), "");
  // Another map is another lock.
  const MapWriteLock first(map);
  EXPECT_EQ(LockRefusal(dir / "other.ot"), "");
}

TEST(MapWriteLock, AnotherProcessHoldsItUntilKilledAndLeavesNoLockThatBlocks) {
  testing::TempDir dir;
  const std::string map = dir / "r.ot";
  testing::LockHolder holder(map);
  ASSERT_TRUE(holder.held());
  const std::string refusal = LockRefusal(map);
  EXPECT_EQ(refusal.rfind(map + ": another process is writing this map (pid " + std::to_string(holder.pid()) + ": ", 0),
            0u)
      << refusal;
  holder.Kill();
  EXPECT_TRUE(fs::exists(MapWriteLock::LockPath(map))) << "SIGKILL removes nothing";
  EXPECT_EQ(LockRefusal(map), "") << "the lock of a killed writer blocks the next one";
  EXPECT_FALSE(fs::exists(MapWriteLock::LockPath(map)));
}

TEST(MapWriteLock, AMissingFolderIsNamed) {
  testing::TempDir dir;
  EXPECT_EQ(LockRefusal(dir / "missing/r.ot"), (dir / "missing/r.ot") + ": the folder " + (dir / "missing") +
                                                   " does not exist");
}

}  // namespace
}  // namespace ssta
