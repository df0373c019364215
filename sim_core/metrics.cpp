#include "ftc/sim/metrics.hpp"

#include <cmath>
#include <utility>

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

MetricsAccumulator::MetricsAccumulator(double sample_time, Window window,
                                       std::vector<Window> extra_windows,
                                       std::vector<double> fault_onsets)
    : Ts_(sample_time) {
  m_.window = window;
  m_.extra.assign(extra_windows.size(), ErrorIntegrals{});
  m_.extra_windows = std::move(extra_windows);
  m_.peak_error_after_fault.assign(fault_onsets.size(), std::numeric_limits<double>::quiet_NaN());
  m_.fault_onsets = std::move(fault_onsets);
}

namespace {
void add(ErrorIntegrals& acc, double ts, double t, double e2, double e1) {
  acc.ise += ts * e2;
  acc.iae += ts * e1;
  acc.itae += ts * t * e1;
}
}  // namespace

void MetricsAccumulator::sample(double t, const State& x, const Vec4& u_d) {
  const Vec3 e = x.head<kAxes>();
  const double e2 = e.squaredNorm();
  const double e1 = e.cwiseAbs().sum();
  if (m_.window.contains(t)) add(m_.errors, Ts_, t, e2, e1);
  for (std::size_t i = 0; i < m_.extra.size(); ++i)
    if (m_.extra_windows[i].contains(t)) add(m_.extra[i], Ts_, t, e2, e1);

  m_.max_abs_u = std::max(m_.max_abs_u, u_d.cwiseAbs().maxCoeff());
  if (has_prev_) m_.control_tv += (u_d - u_prev_).norm();
  u_prev_ = u_d;
  has_prev_ = true;

  const double en = std::sqrt(e2);
  for (std::size_t i = 0; i < m_.fault_onsets.size(); ++i)
    if (t >= m_.fault_onsets[i] && !(m_.peak_error_after_fault[i] >= en))
      m_.peak_error_after_fault[i] = en;
}

void MetricsAccumulator::mark_diverged(double t) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  m_.diverged = true;
  m_.diverged_at = t;
  m_.errors = {inf, inf, inf};
  for (ErrorIntegrals& e : m_.extra) e = {inf, inf, inf};
}

}  // namespace ftc::sim
