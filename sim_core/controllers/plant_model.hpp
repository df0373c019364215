#pragma once
// The plant as a model-based controller uses it: f(X) and G⁺(X) at the measured state. G⁺ is
// read once when the plant says G is constant (the spacecraft), which saves a virtual call
// and an m×n copy every sample; f comes from the measurement when the caller already has it.
#include <array>

#include "ftc/sim/controller.hpp"

namespace ftc::sim::detail {

template <int N, int M>
class PlantModel {
 public:
  using P = Plant<N, M>;

  explicit PlantModel(const P& plant)
      : plant_(plant), constant_G_(plant.input_matrix_is_constant()) {
    if (constant_G_) rows(plant.G_pinv(P::State::Zero()), G_pinv_);
  }

  Vec<N> f(const Measurement<N>& m) const {
    return m.f && m.f_of == static_cast<const void*>(&plant_) ? *m.f : plant_.f(state(m));
  }
  // G⁺(X), row-major m×n, as the control laws read it.
  const double* G_pinv(const Measurement<N>& m) {
    if (!constant_G_) rows(plant_.G_pinv(state(m)), G_pinv_);
    return G_pinv_.data();
  }

 private:
  static typename P::State state(const Measurement<N>& m) {
    return (typename P::State() << m.X1, m.X2).finished();
  }
  static void rows(const typename P::InputInverse& g, std::array<double, M * N>& out) {
    for (int i = 0; i < M; ++i)
      for (int k = 0; k < N; ++k) out[i * N + k] = g(i, k);
  }

  const P& plant_;
  bool constant_G_;
  std::array<double, M * N> G_pinv_{};
};

// The controller class of each type (include/ftc/sim/controllers.hpp), specialised in each
// class's header, for visit_controller_type(): ControllerClass<t>::type<N, M>.
template <ControllerType>
struct ControllerClass;

// A control law of controllers/laws.hpp as a Controller: the runtime's scalar controller.
template <int N, int M, template <class, int, int> class Law, bool ModelBased>
class LawController : public Controller<N, M> {
 public:
  static constexpr bool kModelBased = ModelBased;  // controllers.hpp's model_based

  LawController(const ControllerConfig& config, const Plant<N, M>& plant, double sample_time)
      : config_(checked_config(config, sample_time)),
        config_ptr_(&config_),
        plant_(plant),
        law_(&config_ptr_, sample_time),
        Ts_(sample_time) {}

  void reset() override { law_.reset(); }
  using Controller<N, M>::step;
  Vec<M> step(const Measurement<N>& m) override {
    law::Sample<double, N> s;
    for (int i = 0; i < N; ++i) {
      s.X1[i] = m.X1[i];
      s.X2[i] = m.X2[i];
      s.a[i] = m.a[i];
      s.f[i] = 0.0;
    }
    if constexpr (ModelBased) {
      const Vec<N> f = plant_.f(m);
      for (int i = 0; i < N; ++i) s.f[i] = f[i];
    }
    law::V<double, M> u;
    law_.step(s, plant_.G_pinv(m), u);
    return Eigen::Map<const Vec<M>>(u.data());
  }
  const ControllerConfig& config() const override { return config_; }
  double sample_time() const override { return Ts_; }

 protected:
  const Law<double, N, M>& law() const { return law_; }

 private:
  ControllerConfig config_;
  const ControllerConfig* config_ptr_;
  PlantModel<N, M> plant_;
  Law<double, N, M> law_;
  double Ts_;
};

}  // namespace ftc::sim::detail
