// The two-link arm's dynamics as lane code for the closed loop (lanes/closed_loop.hpp). Compiled
// once per instruction set (ftc_plant_kernels() in sim_core/CMakeLists.txt), never on its own.
//
// Per lane: a1, a2, a3, b1, b2 of the simulated arm and of the controller's model
// (Manipulator::f_constants()). G(X) = M(q)⁻¹ B depends on q2: drift() keeps the simulated
// arm's M⁻¹ at the state it was given, for input(). f and G come from one angle tracker per joint,
// in the operations of Manipulator::f(x, ws) and G(x, ws) (plants/manipulator_dynamics.hpp), and
// the controller's G⁺ = B⁺ M(q) from the model's constants and cos q2 by lane::sincos, in the
// operations of Manipulator::G_pinv(x).
#include "lanes/closed_loop.hpp"
#include "plants/manipulator_dynamics.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

template <>
struct PlantLanes<Manipulator> {
  static constexpr int N = 2, M = 3;

  template <class T>
  class Lanes {
   public:
    static constexpr bool kTrimmed = false;
    static constexpr bool kConstantInput = false;

    explicit Lanes(const PackSetup<N, M>& su)
        : a1_(row(su.truth[0])),
          a2_(row(su.truth[1])),
          a3_(row(su.truth[2])),
          b1_(row(su.truth[3])),
          b2_(row(su.truth[4])),
          ma1_(row(su.model[0])),
          ma2_(row(su.model[1])),
          ma3_(row(su.model[2])),
          mb1_(row(su.model[3])),
          mb2_(row(su.model[4])) {}

    FTC_HOT_INLINE void drift(const std::array<T, 4>& x, std::array<T, 2>& f,
                              std::array<T, 2>* f_model) {
      T s1, c1, s2, c2;
      trig_[0].eval(x[0], s1, c1);
      trig_[1].eval(x[1], s2, c2);
      Mi_ = arm_inverse_mass<T>(a1_, a2_, a3_, c2);
      T out[2];
      arm_f<T>(a2_, b1_, b2_, Mi_, s1, c1, s2, c2, x[2], x[3], out);
      f = {out[0], out[1]};
      if (f_model) {
        arm_f<T>(ma2_, mb1_, mb2_, arm_inverse_mass<T>(ma1_, ma2_, ma3_, c2), s1, c1, s2, c2, x[2],
                 x[3], out);
        *f_model = {out[0], out[1]};
      }
    }

    // G(X) u with G = [[d11, d12, d11 + d12], [d12, d22, d12 + d22]] (as Manipulator::G forms it).
    FTC_HOT_INLINE void input(const std::array<T, 3>& u, std::array<T, 2>& Gu) const {
      const T g[2][3] = {{Mi_.d11, Mi_.d12, Mi_.d11 + Mi_.d12},
                         {Mi_.d12, Mi_.d22, Mi_.d12 + Mi_.d22}};
      for (int i = 0; i < 2; ++i) {
        T v = g[i][0] * u[0];
        for (int j = 1; j < 3; ++j) v = v + g[i][j] * u[j];
        Gu[i] = v;
      }
    }

    FTC_HOT_INLINE void pinv(const std::array<T, 4>& x, T* out) const {
      T s2, c2;
      lane::sincos(x[1], s2, c2);
      arm_pinv<T>(ma1_, ma2_, ma3_, c2, out);
    }

   private:
    static T row(const double* r) { return lane::load_lanes<T>(r); }
    T a1_, a2_, a3_, b1_, b2_, ma1_, ma2_, ma3_, mb1_, mb2_;
    std::array<AngleTracker<T>, 2> trig_;
    ArmInverseMass<T> Mi_{T(0.0), T(0.0), T(0.0)};
  };
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

FTC_PLANT_KERNEL(ftc::sim::Manipulator)
