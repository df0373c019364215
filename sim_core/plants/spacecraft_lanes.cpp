// The spacecraft's dynamics as lane code for the closed loop (lanes/closed_loop.hpp). Compiled
// once per instruction set (ftc_plant_kernels() in sim_core/CMakeLists.txt), never on its own.
//
// Per lane: kx, ky, kz, ω0 of the simulated plant and of the controller's model
// (Spacecraft::f_constants()); G is constant, so the loop reads it and G⁺ from the PackSetup.
// f(X) of the truth and of the model come from one set of sines, from an angle tracker per
// attitude angle, in the operations of Spacecraft::f(x, ws) (plants/spacecraft_dynamics.hpp).
#include "lanes/closed_loop.hpp"
#include "plants/spacecraft_dynamics.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

template <>
struct PlantLanes<Spacecraft> {
  static constexpr int N = 3, M = 4;

  template <class T>
  class Lanes {
   public:
    static constexpr bool kTrimmed = false;
    static constexpr bool kConstantInput = true;

    explicit Lanes(const PackSetup<N, M>& su)
        : kx_(row(su.truth[0])),
          ky_(row(su.truth[1])),
          kz_(row(su.truth[2])),
          w_(row(su.truth[3])),
          mkx_(row(su.model[0])),
          mky_(row(su.model[1])),
          mkz_(row(su.model[2])),
          mw_(row(su.model[3])) {}

    FTC_HOT_INLINE void drift(const std::array<T, 6>& x, std::array<T, 3>& f,
                              std::array<T, 3>* f_model) {
      T s[3], c[3];
      for (int i = 0; i < 3; ++i) trig_[i].eval(x[i], s[i], c[i]);
      T out[3];
      spacecraft_f<T>(kx_, ky_, kz_, w_, x[3], x[4], x[5], s, c, out);
      f = {out[0], out[1], out[2]};
      if (f_model) {
        spacecraft_f<T>(mkx_, mky_, mkz_, mw_, x[3], x[4], x[5], s, c, out);
        *f_model = {out[0], out[1], out[2]};
      }
    }

   private:
    static T row(const double* r) { return lane::load_lanes<T>(r); }
    T kx_, ky_, kz_, w_, mkx_, mky_, mkz_, mw_;
    std::array<AngleTracker<T>, 3> trig_;
  };
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

FTC_PLANT_KERNEL(ftc::sim::Spacecraft)
