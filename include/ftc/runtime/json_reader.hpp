#pragma once
// Strict reading of JSON objects for the file loaders (job, gains and scenario files): every
// accessor records a FieldError (with the JSON path) instead of throwing, and finish() reports
// keys nobody asked for.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "ftc/sim/input_error.hpp"

namespace ftc::json_io {

std::string json_type_name(const nlohmann::json& j);
// A number for messages: `significant` digits (17 = exact round trip).
std::string number_text(double v, int significant = 10);
std::string pointer_escape(const std::string& key);
// `; did you mean "Kp"?` when one candidate is a near miss of `name` (at most two edits, case
// ignored), "" otherwise: for messages about unknown keys and parameters.
std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates);

class ObjectReader {
 public:
  // Records an error when `j` is not an object; all reads then do nothing.
  ObjectReader(const nlohmann::json& j, std::string path, std::vector<FieldError>& errors);

  bool ok() const { return obj_ != nullptr; }
  std::string path(const char* key) const { return path_ + "/" + pointer_escape(key); }

  // Each returns true when the key was present with the right type (out is then set).
  bool number(const char* key, double& out, bool required = false);
  bool integer(const char* key, int& out, bool required = false);
  bool uint64(const char* key, std::uint64_t& out, bool required = false);
  bool string(const char* key, std::string& out, bool required = false);
  // Fixed-length array of numbers.
  bool numbers(const char* key, double* out, std::size_t n, bool required = false);
  // Array of numbers of any length.
  bool number_list(const char* key, std::vector<double>& out, bool required = false);
  // The raw child (marked as read); nullptr when absent (an error if required).
  const nlohmann::json* child(const char* key, bool required = false);

  // Marks a key as handled by the caller (so finish() does not report it).
  void mark_seen(const std::string& key) { seen_.insert(key); }
  // Keys of the object in document order.
  std::vector<std::string> keys() const;

  // Unknown keys become errors listing the allowed ones.
  void finish();

 private:
  const nlohmann::json* get(const char* key, bool required);
  void type_error(const char* key, const char* expected, const nlohmann::json& v);

  const nlohmann::json* obj_;
  std::string path_;
  std::vector<FieldError>& errors_;
  std::set<std::string> seen_;
};

// Parses JSON text strictly; every problem is an InputError(source): a syntax error or text
// that is not UTF-8 ("invalid JSON: ... at line L, column C"), a number beyond the range of a
// double and a key that appears twice in an object (each with its JSON path), nesting deeper
// than 256 levels.
nlohmann::json parse_json_text(const std::string& text, const std::string& source);

// Offset of the first byte that is not part of well-formed UTF-8, nullopt when all are.
std::optional<std::size_t> invalid_utf8(std::string_view text);
// `text` with every byte that is not well-formed UTF-8 written as \xHH: safe to quote.
std::string printable(std::string_view text);

// The most bytes an input file (a job, a scenarios file, gains, a checkpoint) may hold.
inline constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t{256} << 20;
// A checkpoint holds an objective per scenario for every trial, so a run the memory budget
// accepts can write one far larger than a job: it is read with this limit instead.
inline constexpr std::uint64_t kMaxCheckpointBytes = std::uint64_t{16} << 30;

// The whole file, or nullopt when it cannot be opened (callers word the error for their input).
// Throws InputError when it is not a regular file (a directory, a FIFO, which is not waited
// for, a device such as /dev/zero, through a link or not) or holds more than
// max_bytes (kMaxInputFileBytes unless the caller reads a larger kind of file, such as a
// checkpoint, whose size the run itself chose).
std::optional<std::string> read_file(const std::filesystem::path& path,
                                     std::uint64_t max_bytes = kMaxInputFileBytes);

// Reads a JSON file as parse_json_text reads text (the same checks, the same messages), without
// holding its text, and without holding the elements of the array under `streamed_key` in the
// root object: each is given to `element` (its index and value) as soon as it is complete and
// then dropped, so the document returned holds that array empty and the memory the reading
// takes does not grow with the array's length (beyond what `element` keeps). nullopt when the
// file cannot be opened or read; InputError as read_file (not a regular file, larger than
// max_bytes) and parse_json_text, and "changed while it was read" when the bytes the parser
// reads are not those a first pass checked. Any exception `element` throws passes through.
std::optional<nlohmann::json> parse_json_file(
    const std::filesystem::path& path, const std::string& source, const std::string& streamed_key,
    const std::function<void(std::size_t, nlohmann::json&&)>& element,
    std::uint64_t max_bytes = kMaxInputFileBytes);

// Numbers in output JSON: non-finite values (a diverged run's +inf) are written as null, and
// read back as `if_null`.
nlohmann::json json_number(double v);
double json_number_or(const nlohmann::json& j, double if_null);

// Integral check for JSON numbers: 3 and 3.0 are integers, 3.5 is not.
bool json_to_int(const nlohmann::json& v, long long& out);

}  // namespace ftc::json_io
