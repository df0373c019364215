#pragma once
// The four control laws, written once over the lane type T (lanes/lane.hpp): T = double is one
// controller (the Controller classes of the runtime wrap it), T = a SIMD batch is W controllers
// in lockstep, one per lane, each with its own gains (the batch simulator). Both run the same
// operations in the same order, so a lane gives the bits the scalar controller gives.
//
// Notation (SPEC §5): X1 positions, X2 rates, a the measured accelerations, f = f(X) from the
// controller's plant model, G⁺ the right inverse of the input matrix (m×n: the same for all
// lanes when G is constant, each lane's own at its state otherwise), u_d the command.
//
//   sig^a(x) = |x|^a sign(x),  sigm(s) = tanh(θ s / 2),  C(X) = c2 sig^α2(X2) + c1 sig^α1(X1)
//
// FOSMC (Appendix D, the sign of D.4 corrected)
//   sF = a + C(X);  u_d = -G⁺ (f + C + ur);  ur += Ts K sigm(sF)
// PI-FOSMC (eqs. 7, 11–13; eq. 12 divided through by Kp)
//   sF = a + C(X);  sPI = Kp sF + Ki I;  u_d = -G⁺ (f + C + (Ki/Kp) I + ur)
//   I += Ts sF;  ur += Ts K sigm(sPI)
// NFTSMC (Appendix C)
//   s = X1 + σ1 sig^α(X1) + σ2 sig^{p/q}(X2)
//   ueq = f + (q/p) σ2⁻¹ (1 + α σ1 |X1|^{α-1}) ⊙ sig^{2-p/q}(X2);  u_d = -G⁺ (ueq + K sigm(s))
// Adaptive neural PI-FOSMC (eqs. 20, 22, 26–30): model-free, Ω and K̂a replace f and the bound
//   ψ_j = exp(-‖X - c_j 1‖² / σ²),  j = 1..l,  c_j evenly spaced on centre_range
//   u_d = -G⁺ (Ω + C + (Ki/Kp) I + ur)
//   I += Ts sF;  ur += Ts (K̂a + ζ) ⊙ sigm(sPI);  K̂a += (Ts/λ) |sPI|;  Ω += Ts Wᵀψ
//   W += Ts · weight_rate · ψ sPIᵀ
//
// Units (spacecraft): X1 rad, X2 rad/s, a, f, C, sF, ur, Ω in rad/s², I in rad/s, K and K̂a, ζ
// in rad/s³, Ki in 1/s; Kp, c1, c2, σ1, σ2, θ·s as the paper gives them. Internal states are
// updated after the command, by forward Euler from the values of sample k.
#include <array>

#include "controllers/sig_power.hpp"
#include "ftc/sim/controller_config.hpp"
#include "lanes/elementary.hpp"

namespace ftc::sim {
inline namespace FTC_ISA_NS {
namespace law {

template <class T, int N>
using V = std::array<T, N>;

// One sample's measurements as a law reads them, at t = k·Ts.
template <class T, int N>
struct Sample {
  V<T, N> X1, X2, a, f;  // f is read by the model-based laws only
  double t = 0.0;        // read by a runtime Controller only (closed_loop.hpp's ObjectLaw)
};

// W values of one lane-dependent gain, one per lane's configuration.
template <class T, class Get>
T per_lane(const ControllerConfig* const* configs, Get&& get) {
  double v[lane::kWidth<T>];
  for (int l = 0; l < lane::kWidth<T>; ++l) v[l] = get(*configs[l]);
  return lane::load_lanes<T>(v);
}

// sigm(y) for y = θ s / 2; tanh is ±1 in double precision past |y| = 19.5 (lane::tanh gives
// those bits too), which spares a tanh whenever every lane is that far out.
template <class T>
FTC_HOT_INLINE T sigm_of(const T& y) {
  if (lane::all(lane::abs(y) > T(19.5))) return lane::copysign(T(1.0), y);
  return lane::tanh(y);
}

// u = -(G⁺ v), G⁺ row-major m×n: the same for every lane (double) or each lane's own (T, a
// plant whose G depends on X).
template <class T, int N, int M, class GP>
FTC_HOT_INLINE void command(const GP* G_pinv, const V<T, N>& v, V<T, M>& u) {
  for (int i = 0; i < M; ++i) {
    T s = T(G_pinv[i * N]) * v[0];
    for (int k = 1; k < N; ++k) s = s + T(G_pinv[i * N + k]) * v[k];
    u[i] = -s;
  }
}

// C(X) = c2 sig^α2(X2) + c1 sig^α1(X1).
template <class T>
class FosmTerm {
 public:
  static constexpr int W = lane::kWidth<T>;
  explicit FosmTerm(const ControllerConfig* const* c)
      : c1_(per_lane<T>(c, [](const ControllerConfig& k) { return k.c1; })),
        c2_(per_lane<T>(c, [](const ControllerConfig& k) { return k.c2; })),
        pow1_(exponents(c, true).data()),
        pow2_(exponents(c, false).data()) {}

  template <std::size_t N>
  FTC_HOT_INLINE std::array<T, N> operator()(const std::array<T, N>& X1,
                                             const std::array<T, N>& X2) const {
    std::array<T, N> C;
    for (std::size_t i = 0; i < N; ++i) C[i] = c2_ * pow2_(X2[i]) + c1_ * pow1_(X1[i]);
    return C;
  }

 private:
  static std::array<double, W> exponents(const ControllerConfig* const* c, bool first) {
    std::array<double, W> a;
    for (int l = 0; l < W; ++l) a[l] = first ? c[l]->resolved_alpha1() : c[l]->alpha2;
    return a;
  }
  T c1_, c2_;
  SigPowerLanes<T> pow1_, pow2_;
};

template <class T, int N, int M>
class Fosmc {
 public:
  Fosmc(const ControllerConfig* const* c, double Ts)
      : fosm_(c),
        TsK_(per_lane<T>(c, [Ts](const ControllerConfig& k) { return Ts * k.switching_gain; })),
        half_theta_(per_lane<T>(c, [](const ControllerConfig& k) { return 0.5 * k.theta; })) {
    reset();
  }
  void reset() { ur_.fill(T(0.0)); }
  // Lanes outside `keep` back to their initial state (a diverged lane in the batch simulator).
  void reset_lanes(const lane::Mask<T>& keep) {
    for (T& v : ur_) v = lane::select(keep, v, T(0.0));
  }

  template <class GP>
  FTC_HOT_INLINE void step(const Sample<T, N>& m, const GP* G_pinv, V<T, M>& u) {
    const V<T, N> C = fosm_(m.X1, m.X2);
    V<T, N> sF, v;
    for (int i = 0; i < N; ++i) {
      sF[i] = m.a[i] + C[i];
      v[i] = (m.f[i] + C[i]) + ur_[i];
    }
    command<T, N, M>(G_pinv, v, u);
    for (int i = 0; i < N; ++i) ur_[i] = ur_[i] + TsK_ * sigm_of(half_theta_ * sF[i]);
  }

 private:
  FosmTerm<T> fosm_;
  T TsK_, half_theta_;
  V<T, N> ur_;
};

// With Kp = 1 and Ki = 0 it issues FOSMC's commands: x + 0·I = x and 1·sF = sF exactly.
template <class T, int N, int M>
class PiFosmc {
 public:
  PiFosmc(const ControllerConfig* const* c, double Ts)
      : fosm_(c),
        Kp_(per_lane<T>(c, [](const ControllerConfig& k) { return k.Kp; })),
        Ki_(per_lane<T>(c, [](const ControllerConfig& k) { return k.Ki; })),
        Ki_over_Kp_(per_lane<T>(c, [](const ControllerConfig& k) { return k.Ki / k.Kp; })),
        TsK_(per_lane<T>(c, [Ts](const ControllerConfig& k) { return Ts * k.switching_gain; })),
        half_theta_(per_lane<T>(c, [](const ControllerConfig& k) { return 0.5 * k.theta; })),
        Ts_(Ts) {
    reset();
  }
  void reset() {
    I_.fill(T(0.0));
    ur_.fill(T(0.0));
  }
  void reset_lanes(const lane::Mask<T>& keep) {
    for (int i = 0; i < N; ++i) {
      I_[i] = lane::select(keep, I_[i], T(0.0));
      ur_[i] = lane::select(keep, ur_[i], T(0.0));
    }
  }

  template <class GP>
  FTC_HOT_INLINE void step(const Sample<T, N>& m, const GP* G_pinv, V<T, M>& u) {
    const V<T, N> C = fosm_(m.X1, m.X2);
    V<T, N> sF, sPI, v;
    for (int i = 0; i < N; ++i) {
      sF[i] = m.a[i] + C[i];
      sPI[i] = Kp_ * sF[i] + Ki_ * I_[i];
      v[i] = ((m.f[i] + C[i]) + Ki_over_Kp_ * I_[i]) + ur_[i];
    }
    command<T, N, M>(G_pinv, v, u);
    const T Ts(Ts_);
    for (int i = 0; i < N; ++i) {
      I_[i] = I_[i] + Ts * sF[i];
      ur_[i] = ur_[i] + TsK_ * sigm_of(half_theta_ * sPI[i]);
    }
  }

 private:
  FosmTerm<T> fosm_;
  T Kp_, Ki_, Ki_over_Kp_, TsK_, half_theta_;
  double Ts_;
  V<T, N> I_, ur_;
};

template <class T, int N, int M>
class Nftsmc {
 public:
  static constexpr int W = lane::kWidth<T>;
  Nftsmc(const ControllerConfig* const* c, double /*Ts*/)
      : sigma1_(per_lane<T>(c, [](const ControllerConfig& k) { return k.sigma1; })),
        sigma2_(per_lane<T>(c, [](const ControllerConfig& k) { return k.sigma2; })),
        k_(per_lane<T>(c, [](const ControllerConfig& k) { return (k.q / k.p) / k.sigma2; })),
        alpha_sigma1_(per_lane<T>(c, [](const ControllerConfig& k) { return k.alpha * k.sigma1; })),
        K_(per_lane<T>(c, [](const ControllerConfig& k) { return k.switching_gain; })),
        half_theta_(per_lane<T>(c, [](const ControllerConfig& k) { return 0.5 * k.theta; })),
        pow_alpha_(exponents(c, [](const ControllerConfig& k) { return k.alpha; }).data()),
        pow_pq_(exponents(c, [](const ControllerConfig& k) { return k.p / k.q; }).data()),
        pow_rate_(exponents(c, [](const ControllerConfig& k) { return 2.0 - k.p / k.q; }).data()),
        pow_gain_(exponents(c, [](const ControllerConfig& k) { return k.alpha - 1.0; }).data()) {}
  void reset() {}  // memoryless
  void reset_lanes(const lane::Mask<T>&) {}

  template <class GP>
  FTC_HOT_INLINE void step(const Sample<T, N>& m, const GP* G_pinv, V<T, M>& u) {
    V<T, N> v;
    for (int i = 0; i < N; ++i) {
      const T s = (m.X1[i] + sigma1_ * pow_alpha_(m.X1[i])) + sigma2_ * pow_pq_(m.X2[i]);
      // |X1|^(α-1) with α > p/q > 1, so 0^(α-1) = 0: no singularity at X1 = 0.
      const T gain = T(1.0) + alpha_sigma1_ * pow_gain_(lane::abs(m.X1[i]));
      const T ueq = m.f[i] + (k_ * gain) * pow_rate_(m.X2[i]);
      v[i] = ueq + K_ * sigm_of(half_theta_ * s);
    }
    command<T, N, M>(G_pinv, v, u);
  }

 private:
  template <class Get>
  static std::array<double, W> exponents(const ControllerConfig* const* c, Get&& get) {
    std::array<double, W> a;
    for (int l = 0; l < W; ++l) a[l] = get(*c[l]);
    return a;
  }
  T sigma1_, sigma2_, k_, alpha_sigma1_, K_, half_theta_;
  // sig^α, sig^{p/q}, sig^{2-p/q} and |·|^{α-1}
  SigPowerLanes<T> pow_alpha_, pow_pq_, pow_rate_, pow_gain_;
};

template <class T, int N, int M>
class AdaptiveNeuralPiFosmc {
 public:
  static constexpr int W = lane::kWidth<T>;
  static constexpr int kMaxNodes = 64;

  // Every lane must have the same number of nodes (the batch simulator packs them so).
  AdaptiveNeuralPiFosmc(const ControllerConfig* const* c, double Ts)
      : fosm_(c),
        Kp_(per_lane<T>(c, [](const ControllerConfig& k) { return k.Kp; })),
        Ki_(per_lane<T>(c, [](const ControllerConfig& k) { return k.Ki; })),
        Ki_over_Kp_(per_lane<T>(c, [](const ControllerConfig& k) { return k.Ki / k.Kp; })),
        zeta_(per_lane<T>(c, [](const ControllerConfig& k) { return k.zeta; })),
        half_theta_(per_lane<T>(c, [](const ControllerConfig& k) { return 0.5 * k.theta; })),
        Ts_over_lambda_(per_lane<T>(c, [Ts](const ControllerConfig& k) { return Ts / k.lambda; })),
        inv_w2_(
            per_lane<T>(c, [](const ControllerConfig& k) { return 1.0 / (k.width * k.width); })),
        rate_(per_lane<T>(c, [Ts](const ControllerConfig& k) { return Ts * k.weight_rate; })),
        ka0_(per_lane<T>(c, [](const ControllerConfig& k) { return k.ka0; })),
        Ts_(Ts),
        l_(static_cast<int>(c[0]->nodes)) {
    for (int j = 0; j < l_; ++j)
      centres_[j] = per_lane<T>(c, [&](const ControllerConfig& k) {
        const double lo = k.centre_range[0], hi = k.centre_range[1];
        return l_ == 1 ? 0.5 * (lo + hi) : lo + (hi - lo) * j / (l_ - 1);
      });
    reset();
  }

  void reset() {
    I_.fill(T(0.0));
    ur_.fill(T(0.0));
    Ka_.fill(ka0_);
    Omega_.fill(T(0.0));
    for (int j = 0; j < l_; ++j) W_[j].fill(T(0.0));
  }
  void reset_lanes(const lane::Mask<T>& keep) {
    for (int i = 0; i < N; ++i) {
      I_[i] = lane::select(keep, I_[i], T(0.0));
      ur_[i] = lane::select(keep, ur_[i], T(0.0));
      Ka_[i] = lane::select(keep, Ka_[i], ka0_);
      Omega_[i] = lane::select(keep, Omega_[i], T(0.0));
      for (int j = 0; j < l_; ++j) W_[j][i] = lane::select(keep, W_[j][i], T(0.0));
    }
  }

  template <class GP>
  FTC_HOT_INLINE void step(const Sample<T, N>& m, const GP* G_pinv, V<T, M>& u) {
    const V<T, N> C = fosm_(m.X1, m.X2);
    V<T, N> sF, sPI, v;
    for (int i = 0; i < N; ++i) {
      sF[i] = m.a[i] + C[i];
      sPI[i] = Kp_ * sF[i] + Ki_ * I_[i];
      v[i] = ((Omega_[i] + C[i]) + Ki_over_Kp_ * I_[i]) + ur_[i];
    }
    command<T, N, M>(G_pinv, v, u);

    // ψ_j with μ_j = c_j (1,…,1).
    std::array<T, kMaxNodes> psi;
    for (int j = 0; j < l_; ++j) {
      T d2(0.0);  // over X = (X1, X2), in that order
      for (int i = 0; i < N; ++i) {
        const T d = m.X1[i] - centres_[j];
        d2 = d2 + d * d;
      }
      for (int i = 0; i < N; ++i) {
        const T d = m.X2[i] - centres_[j];
        d2 = d2 + d * d;
      }
      psi[j] = lane::exp(-(d2 * inv_w2_));
    }

    const T Ts(Ts_);
    for (int i = 0; i < N; ++i) {
      I_[i] = I_[i] + Ts * sF[i];
      ur_[i] = ur_[i] + Ts * ((Ka_[i] + zeta_) * sigm_of(half_theta_ * sPI[i]));
      Ka_[i] = Ka_[i] + Ts_over_lambda_ * lane::abs(sPI[i]);
      T net(0.0);
      for (int j = 0; j < l_; ++j) net = net + psi[j] * W_[j][i];
      Omega_[i] = Omega_[i] + Ts * net;
    }
    for (int j = 0; j < l_; ++j) {
      const T g = rate_ * psi[j];
      for (int i = 0; i < N; ++i) W_[j][i] = W_[j][i] + g * sPI[i];
    }
  }

  const V<T, N>& adaptive_gain() const { return Ka_; }
  const V<T, N>& network_output() const { return Omega_; }

 private:
  FosmTerm<T> fosm_;
  T Kp_, Ki_, Ki_over_Kp_, zeta_, half_theta_, Ts_over_lambda_, inv_w2_, rate_, ka0_;
  double Ts_;
  int l_;
  std::array<T, kMaxNodes> centres_{};
  V<T, N> I_, ur_, Ka_, Omega_;
  std::array<V<T, N>, kMaxNodes> W_{};  // the weights θ̂, row j for node j
};

// The law of each controller type (include/ftc/sim/controllers.hpp), for
// visit_controller_type(): LawOf<t>::type<T, N, M>.
template <ControllerType>
struct LawOf;
template <>
struct LawOf<ControllerType::nftsmc> {
  template <class T, int N, int M>
  using type = Nftsmc<T, N, M>;
};
template <>
struct LawOf<ControllerType::fosmc> {
  template <class T, int N, int M>
  using type = Fosmc<T, N, M>;
};
template <>
struct LawOf<ControllerType::pi_fosmc> {
  template <class T, int N, int M>
  using type = PiFosmc<T, N, M>;
};
template <>
struct LawOf<ControllerType::adaptive_neural_pi_fosmc> {
  template <class T, int N, int M>
  using type = AdaptiveNeuralPiFosmc<T, N, M>;
};

}  // namespace law
}  // namespace FTC_ISA_NS
}  // namespace ftc::sim
