#pragma once
// Reading and writing whole files. Output files are written to a temporary file in the same
// directory and renamed into place, so a reader never sees a half-written file and a crash
// leaves the previous version intact.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "ftc/runtime/json_reader.hpp"

namespace ftc::tune {

using json_io::read_file;

// Creates parent directories as needed. Throws std::runtime_error on I/O failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace ftc::tune
