#include "plants/hover.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace ftc::sim::detail {

double hold_margin(const Eigen::Ref<const Eigen::MatrixXd>& A, double weight,
                   std::span<const bool> stuck, std::span<const double> stuck_at,
                   std::span<const double> lost, std::span<const double> floor_of,
                   std::span<const double> cap_of, double scale) {
  constexpr double kInfeasible = -std::numeric_limits<double>::infinity();
  const double Tmax = scale;
  const int eqs = weight > 0.0 ? 4 : 3;  // zero torque, and the weight when there is one
  // The actuators that still act, their limits, and what the others leave to them:
  // E T = c with E = [A; 1 … 1] (or A) over the acting ones, c = (0, 0, 0, m g) less the others.
  std::vector<int> acting;
  std::vector<double> floor, cap;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(eqs);
  if (eqs == 4) c[3] = weight;
  for (std::size_t j = 0; j < static_cast<std::size_t>(A.cols()); ++j) {
    double fixed = 0.0;
    if (stuck[j]) {
      fixed = std::clamp(stuck_at[j], floor_of[j], cap_of[j]);
    } else if (lost[j] < 1.0) {
      acting.push_back(static_cast<int>(j));
      const double keep = 1.0 - lost[j];
      // What it delivers, (1 − ρ) times its limited output, limited again (a rotor's floor of
      // 0 stays; a wheel's −max shrinks with its cap).
      floor.push_back(std::clamp(keep * floor_of[j], floor_of[j], cap_of[j]));
      cap.push_back(std::clamp(keep * cap_of[j], floor_of[j], cap_of[j]));
      continue;
    }
    c.head<3>() -= A.col(static_cast<Eigen::Index>(j)) * fixed;
    if (eqs == 4) c[3] -= fixed;
  }
  const int k = static_cast<int>(acting.size());
  if (k == 0) return kInfeasible;
  Eigen::MatrixXd E(eqs, k);
  for (int i = 0; i < k; ++i) {
    E.block<3, 1>(0, i) = A.col(acting[i]);
    if (eqs == 4) E(3, i) = 1.0;
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(E);
  lu.setThreshold(1e-12);
  const Eigen::VectorXd Tp = lu.solve(c);
  if ((E * Tp - c).norm() > 1e-9 * (1.0 + c.norm())) return kInfeasible;
  const int d = k - static_cast<int>(lu.rank());
  // The thrusts Tp + Z z; maximise t subject to floor_i + t ≤ T_i ≤ cap_i − t: rows
  // a·(z, t) ≤ b.
  const Eigen::MatrixXd Z = d > 0 ? Eigen::MatrixXd(lu.kernel()) : Eigen::MatrixXd(k, 0);
  // Only finite bounds make rows; with none, any margin holds.
  std::vector<std::pair<int, bool>> bounds;  // (actuator, upper)
  // (The plants limit every actuator or none, so a free direction cannot make t unbounded.)
  for (int i = 0; i < k; ++i)
    if (std::isfinite(floor[static_cast<std::size_t>(i)])) bounds.emplace_back(i, false);
  for (int i = 0; i < k; ++i)
    if (std::isfinite(cap[static_cast<std::size_t>(i)])) bounds.emplace_back(i, true);
  if (bounds.empty()) return std::numeric_limits<double>::infinity();
  const int rows = static_cast<int>(bounds.size()), vars = d + 1;
  Eigen::MatrixXd a(rows, vars);
  Eigen::VectorXd b(rows);
  for (int r = 0; r < rows; ++r) {
    const auto [i, upper] = bounds[static_cast<std::size_t>(r)];
    // With no free direction (d = 0) Z has no columns, and no row of it may be taken: an empty
    // Eigen matrix has no storage, and a row of it offsets a null pointer.
    if (d > 0) {
      if (upper)
        a.block(r, 0, 1, d) = Z.row(i);
      else
        a.block(r, 0, 1, d) = -Z.row(i);
    }
    a(r, d) = 1.0;
    const auto u = static_cast<std::size_t>(i);
    b[r] = upper ? cap[u] - Tp[i] : Tp[i] - floor[u];
  }
  // The optimum lies at a vertex: vars of the rows active. Few enough to try them all.
  double best = kInfeasible;
  std::vector<int> pick(static_cast<std::size_t>(vars));
  const auto visit = [&](const auto& self, int from, int depth) -> void {
    if (depth == vars) {
      Eigen::MatrixXd S(vars, vars);
      Eigen::VectorXd s(vars);
      for (int r = 0; r < vars; ++r) {
        S.row(r) = a.row(pick[static_cast<std::size_t>(r)]);
        s[r] = b[pick[static_cast<std::size_t>(r)]];
      }
      Eigen::FullPivLU<Eigen::MatrixXd> slu(S);
      if (!slu.isInvertible()) return;
      const Eigen::VectorXd y = slu.solve(s);
      if (((a * y - b).array() > 1e-9 * Tmax).any()) return;
      best = std::max(best, y[d]);
      return;
    }
    for (int r = from; r < rows; ++r) {
      pick[static_cast<std::size_t>(depth)] = r;
      self(self, r + 1, depth + 1);
    }
  };
  visit(visit, 0, 0);
  return best;
}

}  // namespace ftc::sim::detail
