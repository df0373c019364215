#pragma once
// Reading and writing whole files. Output files are written to a temporary file in the same
// directory and renamed into place, so a reader never sees a half-written file and a crash
// leaves the previous version intact.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

using json_io::read_file;

// Creates parent directories as needed. Throws std::runtime_error on I/O failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);
// The same for content produced piece by piece (a large file never held in memory whole):
// `produce` hands each chunk to the sink it is given.
using ChunkSink = std::function<void(std::string_view)>;
void write_file_atomic(const std::filesystem::path& path,
                       const std::function<void(const ChunkSink&)>& produce);

}  // namespace ftc::tune
