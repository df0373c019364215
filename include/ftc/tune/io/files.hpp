#pragma once
// Reading and writing whole files. Output files are written to a temporary file in the same
// directory and renamed into place, so a reader never sees a half-written file and a crash
// leaves the previous version intact.
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

using json_io::read_file;

// An output that could not be written whole: a target that is not a regular file, a figure
// gnuplot failed on or left incomplete. The CLI reports it on one line and exits 2.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws OutputError when `path` exists and is not a regular file (a symbolic link, a device
// node, a FIFO, a socket, a directory): an output replaces only a file of its own kind, never
// /dev/full or whatever a link points to.
void refuse_non_regular_target(const std::filesystem::path& path);

// Creates parent directories as needed. The content goes to a temporary file in the same
// directory; the file and then its directory are synced, so after a crash the name holds the old
// or the whole new content. A target that is not a regular file is refused (OutputError). Throws std::filesystem::
// filesystem_error naming the step, the file and the errno (e.g. "No space left on device").
void write_file_atomic(const std::filesystem::path& path, std::string_view content);
// The same for content produced piece by piece (a large file never held in memory whole):
// `produce` hands each chunk to the sink it is given.
using ChunkSink = std::function<void(std::string_view)>;
void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const ChunkSink&)>& produce);

// Puts `written` (a complete file another program wrote, on the same file system) in place of
// `target` as write_file_atomic would: refuses a target that is not a regular file, syncs the
// file, renames it and syncs the directory; on failure `written` is removed and the target is
// as it was. The sync and the rename count as I/O steps for inject_io_failure.
void commit_file(const std::filesystem::path& written, const std::filesystem::path& target);

// Syncs a directory, so that the entries renamed into it survive a crash.
void sync_directory(const std::filesystem::path& dir);
// Renames each of `names` (files or directories) from `staging` into `dir`, in the order given,
// then syncs `dir`: how a set of files written and synced elsewhere on the same file system
// takes its place at once. A name already in `dir` is replaced (a directory only when empty).
void move_into(const std::filesystem::path& staging, const std::filesystem::path& dir,
               const std::vector<std::string>& names);

// A test seam for I/O failures that needs no root and no full disk: the next `after`-th write,
// fsync or rename of write_file_atomic or move_into (counting from 1, over all three) fails with
// `error` (ENOSPC by default), once. 0 turns it off. Also set from the environment variable
// FTCTUNE_FAIL_IO=N[:errno] when the first file is written, so that CLI tests can use it.
void inject_io_failure(int after, int error = 28 /* ENOSPC */);

}  // namespace ftc::tune
