#pragma once

#include <functional>
#include <string>

namespace ssta {

/// Writes a file atomically: `write` fills a temporary file beside `path`, which is flushed and
/// renamed over `path` only when `write` returns normally. On any failure the temporary file is
/// removed, `path` keeps its previous content, and ssta::Error names the file. The temporary
/// file is `<path>.tmp<pid>-<hex>`. With `remove_stale`, a successful write then removes such
/// files of `path` whose writer process no longer exists (killed while writing): meant for
/// files written again and again (maps and their checkpoints), as it reads the whole folder.
void WriteFileAtomically(const std::string& path, const std::function<void(const std::string& tmp_path)>& write,
                         bool remove_stale = false);

/// Writes `text` to `path` atomically.
void WriteTextAtomically(const std::string& path, const std::string& text);

/// Reads a whole text file; throws ssta::Error naming it when it cannot be read.
std::string ReadTextFile(const std::string& path);

/// Creates a directory and its parents; throws ssta::Error naming it on failure.
void MakeDirectories(const std::string& path);

}  // namespace ssta
