// Atomic writes: a write that fails (full disk, unwritable path) names the file and leaves the
// previous file as it was, with no temporary file left behind.

#include "ssta/io/file_util.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace ssta
