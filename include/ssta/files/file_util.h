#pragma once

#include <functional>
#include <string>
#include <vector>

namespace ssta {

/// Writes a file atomically: `write` fills a temporary file beside `path`, which is flushed and
/// renamed over `path` only when `write` returns normally. On any failure the temporary file is
/// removed, `path` keeps its previous content, and ssta::Error names the file. The temporary
/// file is `<path>.tmp<pid>-<hex>`. With `remove_stale`, a successful write then removes such
/// files of `path` whose writer process no longer exists (killed while writing): meant for
/// files written again and again (maps and their checkpoints), as it reads the whole folder.
void WriteFileAtomically(const std::string& path, const std::function<void(const std::string& tmp_path)>& write,
                         bool remove_stale = false);

/// Writes `bytes` to `path` with WriteFileAtomically; ssta::Error names the file when it cannot
/// be opened or written in full (a full disk).
void WriteFileBytes(const std::vector<unsigned char>& bytes, const std::string& path);

/// What keeps a file from being written at `path` for lack of a folder: "the folder F does not
/// exist" or "F is a file, not a folder" (F its parent); "" when the parent is a folder or
/// `path` has none.
std::string ParentFolderProblem(const std::string& path);

/// Whether `path` names a folder: empty, ending in '/', or an existing folder.
bool NamesAFolder(const std::string& path);

/// What keeps a file from being written at `path`: "is a folder; give a file name" when it
/// names a folder (NamesAFolder), else ParentFolderProblem; "" when it can be written. The
/// check `--map FILE` and Python's map paths make before any work.
std::string OutputFileProblem(const std::string& path);

/// The one writer of the file at `path` (a map): an exclusive lock held from construction to
/// destruction. Writers of a map (`build-map`, `merge-maps --out`, Python's `build_map`) hold
/// it for their whole run; readers never take it and read the last complete save (saves are
/// atomic renames). The lock is flock(2) on the sidecar file `<path>.lock`, which holds the
/// holder's pid and command line for the message of the next writer; the kernel drops the
/// lock when the holder's process ends in any way (SIGKILL included), so a killed writer
/// leaves at most a lock file that blocks no one. A normal release removes the file. Locks of
/// one process conflict too (one open file description per lock), so two threads cannot both
/// write one map. Works on local file systems and on NFS (where Linux maps flock to fcntl
/// locks); a file system without locks fails with ssta::Error naming the lock file.
class MapWriteLock {
 public:
  /// Takes the lock without waiting. Throws ssta::Error when another writer holds it, in one
  /// line naming `path` and the holder's pid and command ("r.ot: another process is writing
  /// this map (pid 4242: ssta build-map ...)"), or when the lock file cannot be made (its
  /// folder is missing or read-only), naming it.
  explicit MapWriteLock(const std::string& path);
  ~MapWriteLock();
  MapWriteLock(const MapWriteLock&) = delete;
  MapWriteLock& operator=(const MapWriteLock&) = delete;

  /// The lock file of the map at `path`: `<path>.lock`.
  static std::string LockPath(const std::string& path);

 private:
  std::string lock_path_;
  int fd_ = -1;
};

/// Writes `text` to `path` atomically.
void WriteTextAtomically(const std::string& path, const std::string& text);

/// Reads a whole text file; throws ssta::Error naming it when it cannot be read.
std::string ReadTextFile(const std::string& path);

/// Creates a directory and its parents; throws ssta::Error naming it on failure.
void MakeDirectories(const std::string& path);

/// Removes the per-frame files of an earlier run from `dir`: regular files named
/// `<digits><extension>` (e.g. `1600000000100000000.png`), nothing else. Returns how many were
/// removed; a missing folder removes none. Throws ssta::Error naming a file it cannot remove.
/// Commands that write one file per frame into folders of their own call it first, so that a
/// shorter run into the same folder does not leave the frames of a longer one to be scored.
int RemoveFrameFiles(const std::string& dir, const std::string& extension);

}  // namespace ssta
