#pragma once
// Reading and writing whole files. Output files are written to a temporary file in the same
// directory and renamed into place, so a reader never sees a half-written file and a crash
// leaves the previous version intact.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace ftc::tune {

// The whole file, or nullopt when it cannot be opened (callers word the error for their input).
std::optional<std::string> read_file(const std::filesystem::path& path);

// Creates parent directories as needed. Throws std::runtime_error on I/O failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

}  // namespace ftc::tune
