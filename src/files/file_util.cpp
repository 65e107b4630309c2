#include "ssta/files/file_util.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <system_error>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ssta/core/error.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

/// `<path>.tmp<pid>-<random hex>`: the writer's process id lets a later write tell the
/// leftovers of a killed writer (SIGKILL, power loss) from a live one's file in progress.
std::string TemporaryName(const std::string& path) {
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::ostringstream name;
  name << path << ".tmp" << ::getpid() << '-' << std::hex << (rng() & 0xffffffu);
  return name.str();
}

/// Removes the temporary files of `path` (named as TemporaryName names them) whose writer
/// process no longer exists. Best effort: any error leaves the file alone.
void RemoveStaleTemporaries(const fs::path& target) {
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string prefix = target.filename().string() + ".tmp";
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    // The rest must be <decimal pid>-<hex>.
    const std::string rest = name.substr(prefix.size());
    const std::size_t dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || dash + 1 == rest.size()) continue;
    if (rest.find_first_not_of("0123456789") != dash) continue;
    if (rest.find_first_not_of("0123456789abcdef", dash + 1) != std::string::npos) continue;
    const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or unknown
    std::error_code ignored;
    fs::remove(it->path(), ignored);
  }
}

void SyncFile(const std::string& path, const std::string& tmp) {
  const int fd = ::open(tmp.c_str(), O_RDONLY);
  if (fd < 0) throw Error(path + ": cannot reopen " + tmp + " to flush it to disk: " + std::strerror(errno));
  const int rc = ::fsync(fd);
  const int fsync_errno = errno;
  ::close(fd);
  if (rc != 0) throw Error(path + ": flushing to disk failed: " + std::strerror(fsync_errno));
}

/// Test seam for full disks: with SSTA_TEST_WRITE_FAULT_AFTER_BYTES=K in the environment, a
/// temporary file that holds more than K bytes is cut to K bytes and the write fails the way a
/// full disk fails it (ENOSPC), before anything is renamed. The tests of "a failed write leaves
/// the previous file intact" use it (a tmpfs needs root, chmod does not stop root).
void InjectedWriteFault(const std::string& path, const std::string& tmp) {
  const char* limit_text = std::getenv("SSTA_TEST_WRITE_FAULT_AFTER_BYTES");
  if (limit_text == nullptr || *limit_text == '\0') return;
  char* end = nullptr;
  const unsigned long long limit = std::strtoull(limit_text, &end, 10);
  if (*end != '\0') throw Error(std::string("SSTA_TEST_WRITE_FAULT_AFTER_BYTES: not a byte count: '") + limit_text + "'");
  std::error_code ec;
  const auto size = fs::file_size(tmp, ec);
  if (ec || size <= limit) return;
  fs::resize_file(tmp, limit, ec);
  throw Error(path + ": write failed: " + std::strerror(ENOSPC));
}

/// This process's command line, its arguments joined by blanks, cut to `max_chars`.
std::string OwnCommandLine(std::size_t max_chars) {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!text.empty() && text.back() == '\0') text.pop_back();
  std::replace(text.begin(), text.end(), '\0', ' ');
  std::replace(text.begin(), text.end(), '\n', ' ');
  if (text.size() > max_chars) text = text.substr(0, max_chars) + "...";
  return text;
}

/// What the holder of a lock wrote into its lock file ("pid 4242: ssta build-map ..."). A
/// holder writes it right after taking the lock: an empty file is read again for up to 0.2 s.
std::string HolderOf(int fd) {
  std::string text;
  for (int attempt = 0; attempt < 20; ++attempt) {
    char buffer[512];
    const ssize_t n = ::pread(fd, buffer, sizeof(buffer) - 1, 0);
    text.assign(buffer, n > 0 ? static_cast<std::size_t>(n) : 0);
    if (!text.empty() && text.back() == '\n') break;
    ::usleep(10000);
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text.empty() ? "a process that has not yet written its pid" : text;
}

}  // namespace

std::string MapWriteLock::LockPath(const std::string& path) { return path + ".lock"; }

MapWriteLock::MapWriteLock(const std::string& path) : lock_path_(LockPath(path)) {
  if (path.empty()) throw Error("map: a map file is required");
  if (const std::string problem = ParentFolderProblem(path); !problem.empty()) throw Error(path + ": " + problem);
  // A releasing holder removes the file while it still holds the lock: a lock taken on a file
  // that is no longer at lock_path_ is taken again on the one that is.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(lock_path_ + ": cannot create the map's lock file: " + std::strerror(errno));
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int lock_errno = errno;
      if (lock_errno == EWOULDBLOCK || lock_errno == EINTR) {
        const std::string holder = HolderOf(fd);
        ::close(fd);
        throw Error(path + ": another process is writing this map (" + holder +
                    "); one writer at a time: wait for it to end, or write another map");
      }
      ::close(fd);
      throw Error(lock_path_ + ": cannot lock the map's lock file: " + std::strerror(lock_errno));
    }
    struct stat held {}, named {};
    if (::fstat(fd, &held) != 0 || ::stat(lock_path_.c_str(), &named) != 0 || held.st_ino != named.st_ino ||
        held.st_dev != named.st_dev) {
      ::close(fd);
      continue;
    }
    const std::string holder = "pid " + std::to_string(::getpid()) + ": " + OwnCommandLine(200) + "\n";
    if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, holder.data(), holder.size(), 0) != static_cast<ssize_t>(holder.size())) {
      const int write_errno = errno;
      ::close(fd);
      throw Error(lock_path_ + ": cannot write the map's lock file: " + std::strerror(write_errno));
    }
    fd_ = fd;
    return;
  }
  throw Error(lock_path_ + ": the map's lock file keeps being replaced; is another writer starting and stopping?");
}

MapWriteLock::~MapWriteLock() {
  if (fd_ < 0) return;
  ::unlink(lock_path_.c_str());  // while still held: a waiting writer sees the file is gone
  ::close(fd_);
}

std::string ParentFolderProblem(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (parent.empty() || fs::is_directory(parent, ec)) return "";
  return fs::exists(parent, ec) ? parent.string() + " is a file, not a folder"
                                : "the folder " + parent.string() + " does not exist";
}

bool NamesAFolder(const std::string& path) {
  std::error_code ec;
  return path.empty() || path.back() == '/' || fs::is_directory(path, ec);
}

std::string OutputFileProblem(const std::string& path) {
  if (NamesAFolder(path)) return "is a folder; give a file name";
  return ParentFolderProblem(path);
}

void WriteFileBytes(const std::vector<unsigned char>& bytes, const std::string& path) {
  WriteFileAtomically(path, [&](const std::string& tmp) {
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw Error(path + ": cannot open for writing");
    const std::size_t n = std::fwrite(bytes.data(), 1, bytes.size(), f);
    const int rc = std::fclose(f);
    if (n != bytes.size() || rc != 0) throw Error(path + ": write failed (disk full?)");
  });
}

void WriteFileAtomically(const std::string& path, const std::function<void(const std::string& tmp_path)>& write,
                         bool remove_stale) {
  const fs::path target(path);
  if (const std::string problem = ParentFolderProblem(path); !problem.empty()) throw Error(path + ": " + problem);
  const std::string tmp = TemporaryName(path);
  try {
    write(tmp);
    InjectedWriteFault(path, tmp);
    SyncFile(path, tmp);
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) throw Error(path + ": cannot replace the file: " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
  if (remove_stale) RemoveStaleTemporaries(target);
}

void WriteTextAtomically(const std::string& path, const std::string& text) {
  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(path + ": cannot open for writing");
    out << text;
    out.flush();
    if (!out) throw Error(path + ": write failed (disk full?)");
  });
}

std::string ReadTextFile(const std::string& path) {
  if (!fs::exists(path)) throw Error(path + ": file not found");
  if (fs::is_directory(path)) throw Error(path + ": is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open for reading");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void MakeDirectories(const std::string& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec || !fs::is_directory(path)) {
    throw Error(path + ": cannot create directory" + (ec ? ": " + ec.message() : ""));
  }
}

int RemoveFrameFiles(const std::string& dir, const std::string& extension) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return 0;
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file() || entry.path().extension().string() != extension) continue;
    const std::string stem = entry.path().stem().string();
    const bool digits = !stem.empty() && std::all_of(stem.begin(), stem.end(), [](unsigned char c) {
      return std::isdigit(c) != 0;
    });
    if (digits) stale.push_back(entry.path());
  }
  if (ec) throw Error(dir + ": cannot list folder: " + ec.message());
  for (const fs::path& file : stale) {
    if (!fs::remove(file, ec) || ec) {
      throw Error(file.string() + ": cannot remove a file of an earlier run" + (ec ? ": " + ec.message() : ""));
    }
  }
  return static_cast<int>(stale.size());
}

}  // namespace ssta
