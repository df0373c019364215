#pragma once
// Numbers in human-readable output (comparison.md, report.html, gnuplot scripts).
#include <cmath>
#include <cstdio>
#include <string>

namespace ftc::tune::detail {

// printf-formatted; "inf" for a diverged run's integrals, "–" for a value that does not exist.
inline std::string format_number(double v, const char* format = "%.4g") {
  if (std::isnan(v)) return "–";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[48];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

}  // namespace ftc::tune::detail
