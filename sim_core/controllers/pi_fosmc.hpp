#pragma once
// PI full-order sliding-mode controller (paper eqs. 7, 11–13; SPEC §5).
//
//   sF   = a + C(X)                     full-order surface (eq. 8)
//   sPI  = Kp sF + Ki I,   I = ∫ sF dt  PI surface (eq. 7)
//   u_d  = -G⁺ (f(X) + C(X) + (Ki/Kp) I + ur)     (eq. 11 with eq. 12 divided through by Kp)
//   I   += Ts · sF
//   ur  += Ts · K · sigm(sPI)           (eq. 13 with the sigmoid for sign)
//
// Units (spacecraft): sF rad/s², I rad/s, ur rad/s², K = Π+ζ rad/s³, Kp dimensionless, Ki 1/s.
// With Kp = 1, Ki = 0 it issues exactly the commands of FOSMC. Model-based. The law itself is
// law::PiFosmc (controllers/laws.hpp), shared with the batch simulator.
#include "checks.hpp"
#include "controllers/laws.hpp"
#include "controllers/plant_model.hpp"

namespace ftc::sim {

template <int N, int M>
class PiFosmc final : public detail::LawController<N, M, law::PiFosmc, true> {
 public:
  using detail::LawController<N, M, law::PiFosmc, true>::LawController;
};

namespace detail {
template <>
struct ControllerClass<ControllerType::pi_fosmc> {
  template <int N, int M>
  using type = PiFosmc<N, M>;
};
}  // namespace detail

}  // namespace ftc::sim
