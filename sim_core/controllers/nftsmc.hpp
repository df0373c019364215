#pragma once
// Nonsingular fast terminal sliding-mode controller (paper Appendix C, corrected as in SPEC §5).
//
//   s    = X1 + σ1 sig^α(X1) + σ2 sig^{p/q}(X2)
//   ueq  = f(X) + (q/p) σ2⁻¹ (1 + α σ1 |X1|^{α-1}) ⊙ sig^{2-p/q}(X2)
//   u_d  = -G⁺ (ueq + K sigm(s))
//
// Units (spacecraft): X1 rad, X2 rad/s, ueq and K rad/s². p, q positive odd integers with
// 1 < p/q < 2 and α > p/q. Memoryless: reset() has nothing to clear. Model-based (uses f, G⁺).
// The law itself is law::Nftsmc (controllers/laws.hpp), shared with the batch simulator.
#include "checks.hpp"
#include "controllers/laws.hpp"
#include "controllers/plant_model.hpp"

namespace ftc::sim {

template <int N, int M>
class Nftsmc final : public detail::LawController<N, M, law::Nftsmc, true> {
 public:
  using detail::LawController<N, M, law::Nftsmc, true>::LawController;
};

namespace detail {
template <>
struct ControllerClass<ControllerType::nftsmc> {
  template <int N, int M>
  using type = Nftsmc<N, M>;
};
}  // namespace detail

}  // namespace ftc::sim
