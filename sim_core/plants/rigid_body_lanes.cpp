// The rigid body's dynamics (rigid_body and multirotor) as lane code for the closed loop
// (lanes/closed_loop.hpp). Compiled once per instruction set (ftc_plant_kernels() in
// sim_core/CMakeLists.txt), never on its own.
//
// Per lane: J, D, D⁺ and m of the simulated plant and of the controller's model
// (RigidBody::f_constants()): J may differ lane by lane (model mismatch), so J⁻¹ D is formed once
// per pack per lane, in the diagonal or the full form by that lane's own J (BodyTerms). Every
// lane of a pack is the same plant, so the kinematics and m are the pack's. With Euler
// kinematics the sines of roll and pitch come from angle trackers, set by each drift() and read
// by the input() and pinv() that follow it; with body rates G and G⁺ are constant and nothing
// trigonometric is evaluated.
#include "lanes/angle_tracker.hpp"
#include "lanes/closed_loop.hpp"
#include "plants/rigid_body_dynamics.hpp"

namespace ftc::sim::detail {
inline namespace FTC_ISA_NS {

template <>
struct PlantLanes<RigidBody> {
  static constexpr int N = 3, M = kMaxBodyActuators;

  template <class T>
  class Lanes {
   public:
    static constexpr bool kTrimmed = true;
    static constexpr bool kConstantInput = false;

    explicit Lanes(const PackSetup<N, M>& su) {
      truth_.load([&](int i) { return row(su.truth[i]); });
      model_.load([&](int i) { return row(su.model[i]); });
      euler_ = truth_.euler;
      if (!euler_) body_pinv<T>(model_, trig_, G_pinv_);
    }

    FTC_HOT_INLINE void drift(const std::array<T, 6>& x, std::array<T, 3>& f,
                              std::array<T, 3>* f_model) {
      if (euler_) {
        tracker_[0].eval(x[0], trig_.sf, trig_.cf);
        tracker_[1].eval(x[1], trig_.st, trig_.ct);
        trig_.ict = T(1.0) / trig_.ct;
      }
      T out[3];
      body_f<T>(truth_, trig_, x.data(), out);
      f = {out[0], out[1], out[2]};
      if (f_model) {
        body_f<T>(model_, trig_, x.data(), out);
        *f_model = {out[0], out[1], out[2]};
      }
    }

    FTC_HOT_INLINE void input(const std::array<T, M>& u, std::array<T, 3>& Gu) const {
      T out[3];
      body_input<T>(truth_, trig_, u.data(), out);
      Gu = {out[0], out[1], out[2]};
    }

    FTC_HOT_INLINE void pinv(const std::array<T, 6>&, T* out) const {
      if (euler_) {
        body_pinv<T>(model_, trig_, out);
        return;
      }
      for (int i = 0; i < M * N; ++i) out[i] = G_pinv_[i];
    }

    // At each sample, in the lanes that still count: whether |θ| has passed 85°, where the
    // 3-2-1 Euler angles approach their singularity (model_invalid).
    FTC_HOT_INLINE void observe(const std::array<T, 6>& x, const lane::Mask<T>& counting) {
      if (euler_) invalid_ = invalid_ | (counting & (lane::abs(x[1]) > T(kPitchLimit)));
    }
    bool model_invalid(int l) const {
      bool b[kMaxLanes] = {};
      lane::store_mask(invalid_, b);
      return b[l];
    }

   private:
    static constexpr double kPitchLimit = 85.0 * 3.14159265358979323846 / 180.0;
    static T row(const double* r) { return lane::load_lanes<T>(r); }
    BodyTerms<T> truth_, model_;
    bool euler_ = true;
    BodyTrig<T> trig_{T(0.0), T(1.0), T(0.0), T(1.0), T(1.0)};
    std::array<AngleTracker<T>, 2> tracker_;
    T G_pinv_[M * N];
    lane::Mask<T> invalid_ = lane::abs(T(0.0)) > T(1.0);  // false in every lane
  };
};

}  // namespace FTC_ISA_NS
}  // namespace ftc::sim::detail

FTC_PLANT_KERNEL(ftc::sim::RigidBody)
