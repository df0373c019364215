#include "ftc/sim/metrics.hpp"

#include <cmath>

#include "ftc/sim/metrics_record.hpp"

namespace ftc::sim {

const char* to_string(Metric m) {
  switch (m) {
    case Metric::ise:
      return "ise";
    case Metric::iae:
      return "iae";
    case Metric::itae:
      return "itae";
  }
  return "?";
}

std::optional<Metric> metric_from_string(std::string_view s) {
  for (Metric m : {Metric::ise, Metric::iae, Metric::itae})
    if (s == to_string(m)) return m;
  return std::nullopt;
}

double ErrorIntegrals::get(Metric m) const {
  switch (m) {
    case Metric::ise:
      return ise;
    case Metric::iae:
      return iae;
    case Metric::itae:
      return itae;
  }
  return ise;
}

void Metrics::mark_diverged(double t) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  diverged = true;
  diverged_at = t;
  for (const MetricField& f : kMetricFields) {
    if (f.scope != MetricScope::window) continue;
    errors.*f.in_window = inf;
    for (ErrorIntegrals& e : extra) e.*f.in_window = inf;
  }
}

}  // namespace ftc::sim
