// The hexarotor's dynamics as lane code for the closed loop (lanes/closed_loop.hpp). Compiled
// once per instruction set (ftc_plant_kernels() in sim_core/CMakeLists.txt), never on its own.
//
// Per lane: Ix, Iy, Iz, l, κ of the simulated hexarotor and of the controller's model
// (Hexarotor::f_constants()). G = J⁻¹ A does not depend on X but does on the inertia, which
// may differ lane by lane (model mismatch), so each lane's G of the truth and G⁺ of the model
// are formed once per pack, in the operations of Hexarotor's constructor. The rotors work about
// their hover thrust (kTrimmed: PackSetup::u0, lo, hi).
#include "lanes/closed_loop.hpp"
#include "plants/hexarotor_dynamics.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

template <>
struct PlantLanes<Hexarotor> {
  static constexpr int N = 3, M = 6;

  template <class T>
  class Lanes {
   public:
    static constexpr bool kTrimmed = true;
    static constexpr bool kConstantInput = false;

    explicit Lanes(const PackSetup<N, M>& su) {
      const T I[3] = {row(su.truth[0]), row(su.truth[1]), row(su.truth[2])};
      const T mI[3] = {row(su.model[0]), row(su.model[1]), row(su.model[2])};
      kx_ = (I[1] - I[2]) / I[0];
      ky_ = (I[2] - I[0]) / I[1];
      kz_ = (I[0] - I[1]) / I[2];
      mkx_ = (mI[1] - mI[2]) / mI[0];
      mky_ = (mI[2] - mI[0]) / mI[1];
      mkz_ = (mI[0] - mI[1]) / mI[2];
      T unused[18];
      hexarotor_input<T>(I, row(su.truth[3]), row(su.truth[4]), G_, unused);
      hexarotor_input<T>(mI, row(su.model[3]), row(su.model[4]), unused, G_pinv_);
    }

    FTC_HOT_INLINE void drift(const std::array<T, 6>& x, std::array<T, 3>& f,
                              std::array<T, 3>* f_model) {
      T out[3];
      hexarotor_f<T>(kx_, ky_, kz_, x[3], x[4], x[5], out);
      f = {out[0], out[1], out[2]};
      if (f_model) {
        hexarotor_f<T>(mkx_, mky_, mkz_, x[3], x[4], x[5], out);
        *f_model = {out[0], out[1], out[2]};
      }
    }

    // G u, summed G(k,0) u0 + G(k,1) u1 + ... (as the loop sums a constant G).
    FTC_HOT_INLINE void input(const std::array<T, 6>& u, std::array<T, 3>& Gu) const {
      for (int k = 0; k < 3; ++k) {
        T v = G_[k * 6] * u[0];
        for (int i = 1; i < 6; ++i) v = v + G_[k * 6 + i] * u[i];
        Gu[k] = v;
      }
    }

    FTC_HOT_INLINE void pinv(const std::array<T, 6>&, T* out) const {
      for (int i = 0; i < 18; ++i) out[i] = G_pinv_[i];
    }

   private:
    static T row(const double* r) { return lane::load_lanes<T>(r); }
    T kx_, ky_, kz_, mkx_, mky_, mkz_;
    T G_[18], G_pinv_[18];
  };
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

FTC_PLANT_KERNEL(ftc::sim::Hexarotor)
