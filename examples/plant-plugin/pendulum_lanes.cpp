// The pendulum's dynamics as lane code for ftctune's closed loop: compiled by ftctune_add_plant
// once per instruction set, T a SIMD batch of doubles (or double in the scalar copy). Per lane:
// a, c, g1, g2 of the simulated pendulum (PackSetup::truth) and of the controller's model
// (PackSetup::model), as Pendulum::f_constants() gives them.
#include "lanes/closed_loop.hpp"
#include "pendulum.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

template <>
struct PlantLanes<pendulum::Pendulum> {
  static constexpr int N = 1, M = 2;

  template <class T>
  class Lanes {
   public:
    static constexpr bool kTrimmed = false;
    static constexpr bool kConstantInput = false;

    explicit Lanes(const PackSetup<N, M>& su)
        : a_(row(su.truth[0])),
          c_(row(su.truth[1])),
          g1_(row(su.truth[2])),
          g2_(row(su.truth[3])),
          ma_(row(su.model[0])),
          mc_(row(su.model[1])),
          mg1_(row(su.model[2])),
          mg2_(row(su.model[3])) {}

    // f(X) = a sin θ − c θ̇, of the truth and of the model, from one sine.
    FTC_HOT_INLINE void drift(const std::array<T, 2>& x, std::array<T, 1>& f,
                              std::array<T, 1>* f_model) {
      T s, co;
      trig_.eval(x[0], s, co);
      f[0] = a_ * s - c_ * x[1];
      if (f_model) (*f_model)[0] = ma_ * s - mc_ * x[1];
    }

    // G u = g1 u1 + g2 u2, the simulated plant's G.
    FTC_HOT_INLINE void input(const std::array<T, 2>& u, std::array<T, 1>& Gu) const {
      Gu[0] = g1_ * u[0] + g2_ * u[1];
    }

    // The model's G⁺, as Pendulum::G_pinv forms it.
    FTC_HOT_INLINE void pinv(const std::array<T, 2>&, T* out) const {
      pendulum::pinv<T>(mg1_, mg2_, out);
    }

   private:
    static T row(const double* r) { return lane::load_lanes<T>(r); }
    T a_, c_, g1_, g2_, ma_, mc_, mg1_, mg2_;
    AngleTracker<T> trig_;
  };
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

FTC_PLANT_KERNEL(pendulum::Pendulum)
