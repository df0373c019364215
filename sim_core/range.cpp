#include "ftc/sim/range.hpp"

#include <cmath>
#include <cstdio>

namespace ftc {
namespace {
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}
}  // namespace

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  if (min_open ? !(v > min) : !(v >= min)) return false;
  if (max_open ? !(v < max) : !(v <= max)) return false;
  return true;
}

std::string Range::describe() const {
  const bool lo = std::isfinite(min), hi = std::isfinite(max);
  if (lo && hi) {
    if (min_open && max_open) return "in the open interval (" + num(min) + ", " + num(max) + ")";
    return std::string("in ") + (min_open ? "(" : "[") + num(min) + ", " + num(max) +
           (max_open ? ")" : "]");
  }
  if (lo) return std::string(min_open ? "> " : ">= ") + num(min);
  if (hi) return std::string(max_open ? "< " : "<= ") + num(max);
  return "a finite number";
}

std::string Range::check(double v) const {
  if (!std::isfinite(v)) return "must be a finite number";
  if (contains(v)) return "";
  return "must be " + describe() + " (got " + num(v) + ")";
}

}  // namespace ftc
