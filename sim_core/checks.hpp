#pragma once
// Internal helpers for validate(): each appends a FieldError when the value is out of range.
#include <cmath>
#include <string>
#include <vector>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/range.hpp"

namespace ftc::sim::detail {

inline std::string join(const std::string& path, const std::string& field) {
  return path + "/" + field;
}

std::string fmt_num(double v);

// Returns true when v is finite; otherwise records "must be a finite number".
bool check_finite(std::vector<FieldError>& errs, const std::string& path, double v);
void check_positive(std::vector<FieldError>& errs, const std::string& path, double v);
void check_non_negative(std::vector<FieldError>& errs, const std::string& path, double v);
void check_int_range(std::vector<FieldError>& errs, const std::string& path, int v, int lo, int hi);
// Records r's message when v is outside r.
inline void check_range(std::vector<FieldError>& errs, const std::string& path, const Range& r,
                        double v) {
  if (std::string msg = r.check(v); !msg.empty()) errs.push_back({path, std::move(msg)});
}

}  // namespace ftc::sim::detail

namespace ftc::sim {
struct ControllerConfig;
namespace detail {
// Validates a controller configuration (InputError naming every bad field) and returns it with
// α1 resolved.
ControllerConfig checked_config(const ControllerConfig& config, double sample_time);
}  // namespace detail
}  // namespace ftc::sim
