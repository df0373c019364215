#pragma once
// Bad user input (job files, controller parameters, gains files) is reported as an InputError
// that carries every problem found, each tied to the JSON path of the offending field.
#include <stdexcept>
#include <string>
#include <vector>

namespace ftc {

struct FieldError {
  std::string path;     // JSON pointer of the field, e.g. "/controller/Kp" ("" = whole document)
  std::string message;  // what is wrong with it
};

// Formats one error as "path: message" (or just the message when there is no path).
std::string to_string(const FieldError& e);

class InputError : public std::runtime_error {
 public:
  // `source` names the input (a file name, "controller", ...); may be empty.
  InputError(std::string source, std::vector<FieldError> errors);
  InputError(std::string source, std::string path, std::string message);

  const std::string& source() const noexcept { return source_; }
  const std::vector<FieldError>& errors() const noexcept { return errors_; }

 private:
  std::string source_;
  std::vector<FieldError> errors_;
};

// Throws InputError(source, errors) when `errors` is not empty.
void throw_if_errors(const std::string& source, std::vector<FieldError> errors);

}  // namespace ftc
