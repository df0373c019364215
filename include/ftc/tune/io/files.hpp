#pragma once
// Reading and writing whole files. Output files are written to a temporary file in the same
// directory and renamed into place, so a reader never sees a half-written file and a crash
// leaves the previous version intact.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

using json_io::read_file;

// Creates parent directories as needed. The file and then its directory are synced, so after
// a crash the name holds the old or the whole new content. Throws std::filesystem::
// filesystem_error naming the step, the file and the errno (e.g. "No space left on device").
void write_file_atomic(const std::filesystem::path& path, std::string_view content);
// The same for content produced piece by piece (a large file never held in memory whole):
// `produce` hands each chunk to the sink it is given.
using ChunkSink = std::function<void(std::string_view)>;
void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const ChunkSink&)>& produce);

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
