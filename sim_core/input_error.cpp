#include "ftc/sim/input_error.hpp"

#include <utility>

namespace ftc {
namespace {

std::string summary(const std::string& source, const std::vector<FieldError>& errors) {
  std::string s = source.empty() ? std::string() : source + ": ";
  if (errors.empty()) return s + "invalid input";
  s += to_string(errors.front());
  if (errors.size() > 1) s += " (and " + std::to_string(errors.size() - 1) + " more)";
  return s;
}

}  // namespace

std::string to_string(const FieldError& e) {
  return e.path.empty() ? e.message : e.path + ": " + e.message;
}

InputError::InputError(std::string source, std::vector<FieldError> errors)
    : std::runtime_error(summary(source, errors)),
      source_(std::move(source)),
      errors_(std::move(errors)) {}

InputError::InputError(std::string source, std::string path, std::string message)
    : InputError(std::move(source),
                 std::vector<FieldError>{{std::move(path), std::move(message)}}) {}

void throw_if_errors(const std::string& source, std::vector<FieldError> errors) {
  if (!errors.empty()) throw InputError(source, std::move(errors));
}

}  // namespace ftc
