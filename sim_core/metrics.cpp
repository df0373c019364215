#include "ftc/sim/metrics.hpp"

#include <cmath>

#include "ftc/sim/metrics_record.hpp"

namespace ftc::sim {

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
