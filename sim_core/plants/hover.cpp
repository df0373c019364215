#include "plants/hover.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <limits>
#include <vector>

namespace ftc::sim::detail {

double hover_margin(const Eigen::Ref<const Eigen::MatrixXd>& A, double weight,
                    std::span<const bool> stuck, std::span<const double> stuck_at,
                    std::span<const double> lost, std::span<const double> floor_of,
                    std::span<const double> cap_of, double scale) {
  constexpr double kInfeasible = -std::numeric_limits<double>::infinity();
  const double Tmax = scale;
  // The rotors that still act, their upper limits, and what the others leave to them:
  // E T = c with E = [A; 1 … 1] over the acting rotors, c = (0, 0, 0, m g) less the others.
  std::vector<int> acting;
  std::vector<double> floor, cap;
  Eigen::Vector4d c(0.0, 0.0, 0.0, weight);
  for (std::size_t j = 0; j < static_cast<std::size_t>(A.cols()); ++j) {
    double fixed = 0.0;
    if (stuck[j]) {
      fixed = std::clamp(stuck_at[j], floor_of[j], cap_of[j]);
    } else if (lost[j] < 1.0) {
      acting.push_back(static_cast<int>(j));
      floor.push_back(floor_of[j]);
      cap.push_back(std::max(floor_of[j], (1.0 - lost[j]) * cap_of[j]));
      continue;
    }
    c.head<3>() -= A.col(static_cast<Eigen::Index>(j)) * fixed;
    c[3] -= fixed;
  }
  const int k = static_cast<int>(acting.size());
  if (k == 0) return kInfeasible;
  Eigen::MatrixXd E(4, k);
  for (int i = 0; i < k; ++i) {
    E.block<3, 1>(0, i) = A.col(acting[i]);
    E(3, i) = 1.0;
  }
  Eigen::FullPivLU<Eigen::MatrixXd> lu(E);
  lu.setThreshold(1e-12);
  const Eigen::VectorXd Tp = lu.solve(c);
  if ((E * Tp - c).norm() > 1e-9 * (1.0 + c.norm())) return kInfeasible;
  const int d = k - static_cast<int>(lu.rank());
  // The thrusts Tp + Z z; maximise t subject to floor_i + t ≤ T_i ≤ cap_i − t: rows
  // a·(z, t) ≤ b.
  const Eigen::MatrixXd Z = d > 0 ? Eigen::MatrixXd(lu.kernel()) : Eigen::MatrixXd(k, 0);
  const int rows = 2 * k, vars = d + 1;
  Eigen::MatrixXd a(rows, vars);
  Eigen::VectorXd b(rows);
  for (int i = 0; i < k; ++i) {
    // With no free direction (d = 0) Z has no columns, and no row of it may be taken: an empty
    // Eigen matrix has no storage, and a row of it offsets a null pointer.
    if (d > 0) {
      a.block(i, 0, 1, d) = -Z.row(i);
      a.block(k + i, 0, 1, d) = Z.row(i);
    }
    a(i, d) = 1.0;
    b[i] = Tp[i] - floor[static_cast<std::size_t>(i)];
    a(k + i, d) = 1.0;
    b[k + i] = cap[static_cast<std::size_t>(i)] - Tp[i];
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
