#pragma once
// Full-order sliding-mode controller (paper Appendix D; the sign of D.4 corrected, SPEC §5).
//
//   sF   = a + C(X),   C(X) = c2 sig^α2(X2) + c1 sig^α1(X1)
//   u_d  = -G⁺ (f(X) + C(X) + ur)
//   ur  += Ts · K · sigm(sF)           (ur(0) = 0; D.4 prints -K, which diverges)
//
// Units (spacecraft): a rad/s², sF rad/s², ur rad/s², K = Π+ζ in rad/s³. Model-based. The law
// itself is law::Fosmc (controllers/laws.hpp), shared with the batch simulator.
#include "checks.hpp"
#include "controllers/laws.hpp"
#include "controllers/plant_model.hpp"

namespace ftc::sim {

template <int N, int M>
class Fosmc final : public detail::LawController<N, M, law::Fosmc, true> {
 public:
  using detail::LawController<N, M, law::Fosmc, true>::LawController;
};

namespace detail {
template <>
struct ControllerClass<ControllerType::fosmc> {
  template <int N, int M>
  using type = Fosmc<N, M>;
};
}  // namespace detail

}  // namespace ftc::sim
