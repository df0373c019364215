#include "checks.hpp"

#include <cstdio>

namespace ftc::sim::detail {

std::string fmt_num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

bool check_finite(std::vector<FieldError>& errs, const std::string& path, double v) {
  if (std::isfinite(v)) return true;
  errs.push_back({path, "must be a finite number"});
  return false;
}

void check_positive(std::vector<FieldError>& errs, const std::string& path, double v) {
  if (check_finite(errs, path, v) && !(v > 0.0))
    errs.push_back({path, "must be > 0 (got " + fmt_num(v) + ")"});
}

void check_non_negative(std::vector<FieldError>& errs, const std::string& path, double v) {
  if (check_finite(errs, path, v) && v < 0.0)
    errs.push_back({path, "must be >= 0 (got " + fmt_num(v) + ")"});
}

void check_int_range(std::vector<FieldError>& errs, const std::string& path, int v, int lo,
                     int hi) {
  if (v < lo || v > hi)
    errs.push_back({path, "must be an integer in " + std::to_string(lo) + ".." +
                              std::to_string(hi) + " (got " + std::to_string(v) + ")"});
}

}  // namespace ftc::sim::detail
