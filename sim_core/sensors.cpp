#include "ftc/sim/sensors.hpp"

#include <cmath>

#include "checks.hpp"
#include "ftc/sim/elementary.hpp"

namespace ftc::sim {

namespace {

void check(std::vector<FieldError>& errs, const std::string& path, double v) {
  detail::check_range(errs, path, SensorModel::kNoiseRange, v);
}

}  // namespace

bool SensorModel::exact() const {
  bool unbiased = true;
  for (double b : rate.bias) unbiased = unbiased && b == 0.0;
  return angle.noise == 0.0 && angle.quantization == 0.0 && rate.noise == 0.0 && unbiased &&
         rate.bias_walk == 0.0 && rate.quantization == 0.0 && delay == 0 &&
         acceleration.source == AccelerationSource::ideal;
}

std::string SensorModel::summary() const {
  std::string out;
  const auto add = [&](const std::string& part) { out += (out.empty() ? "" : ", ") + part; };
  const auto num = [](double v) { return detail::fmt_num(v); };
  if (angle.noise > 0) add("angle noise " + num(angle.noise) + " rad");
  if (angle.quantization > 0) add("angle step " + num(angle.quantization) + " rad");
  if (rate.noise > 0) add("rate noise " + num(rate.noise) + " rad/s");
  bool biased = false;
  for (double b : rate.bias) biased = biased || b != 0.0;
  if (biased) {
    std::string b = "rate bias";
    for (double v : rate.bias) b.append(" ").append(num(v));
    add(b + " rad/s");
  }
  if (rate.bias_walk > 0) add("bias walk " + num(rate.bias_walk) + " rad/s/√s");
  if (rate.quantization > 0) add("rate step " + num(rate.quantization) + " rad/s");
  if (delay > 0) add("delay " + std::to_string(delay) + (delay == 1 ? " sample" : " samples"));
  if (acceleration.source == AccelerationSource::differentiated)
    add("acceleration differentiated" +
        (acceleration.time_constant > 0 ? " (τ = " + num(acceleration.time_constant) + " s)"
                                        : std::string()));
  else
    add("acceleration ideal");
  if (exact()) return "exact";
  add("noise seed " + std::to_string(stream_seed) + ", stream " + std::to_string(stream_index));
  return out;
}

std::vector<FieldError> SensorModel::validate(const std::string& path, int axes) const {
  std::vector<FieldError> errs;
  check(errs, path + "/angle/noise", angle.noise);
  check(errs, path + "/angle/quantization", angle.quantization);
  check(errs, path + "/rate/noise", rate.noise);
  check(errs, path + "/rate/bias_walk", rate.bias_walk);
  check(errs, path + "/rate/quantization", rate.quantization);
  if (rate.bias.size() > 1 && rate.bias.size() != static_cast<std::size_t>(axes))
    errs.push_back({path + "/rate/bias", "expected one number for every axis or " +
                                             std::to_string(axes) + " (one per axis), got " +
                                             std::to_string(rate.bias.size())});
  for (std::size_t i = 0; i < rate.bias.size(); ++i) {
    std::string at = path + "/rate/bias";
    if (rate.bias.size() > 1) at.append("/").append(std::to_string(i));
    detail::check_range(errs, at, Range::any(), rate.bias[i]);
  }
  detail::check_int_range(errs, path + "/delay", delay, 0, kMaxDelay);
  if (acceleration.source == AccelerationSource::differentiated)
    check(errs, path + "/acceleration/time_constant", acceleration.time_constant);
  return errs;
}

SensorNoise::SensorNoise(const SensorModel& model, int axes, double sample_time)
    : rng_(SplitMix64::member(model.stream_seed, SensorModel::kStreamSalt + model.stream_index)),
      sa_(model.angle.noise),
      sr_(model.rate.noise),
      sw_(model.rate.bias_walk * std::sqrt(sample_time)),
      bias_(static_cast<std::size_t>(axes)),
      z_(3 * static_cast<std::size_t>(axes)) {
  for (int i = 0; i < axes; ++i) bias_[static_cast<std::size_t>(i)] = model.rate.bias_of(i);
}

double SensorNoise::normal() {
  if (have_spare_) {
    have_spare_ = false;
    return spare_;
  }
  const double u1 = rng_.uniform();
  const double u2 = rng_.uniform();
  // ftctune's own log and sincos, not libm's: the same normals on every CPU.
  const double r = std::sqrt(-2.0 * math::log(1.0 - u1));
  double s = 0.0, c = 0.0;
  math::sincos(6.283185307179586 * u2, s, c);  // 2π u2
  spare_ = r * s;
  have_spare_ = true;
  return r * c;
}

void SensorNoise::next(double* angle, double* bias, double* rate) {
  const std::size_t n = bias_.size();
  for (double& z : z_) z = normal();  // angle noise, rate noise, bias walk: each n axes
  for (std::size_t i = 0; i < n; ++i) {
    angle[i] = sa_ * z_[i];
    bias[i] = bias_[i];
    rate[i] = sr_ * z_[n + i];
    bias_[i] = bias_[i] + sw_ * z_[2 * n + i];
  }
}

double quantize(double x, double step) {
  // The lanes' quantiser's steps (lanes/closed_loop.hpp): |x / Q| rounded half away from zero
  // (std::round is exact), its sign put back only where x / Q < 0, so that −0 gives +0 there too.
  if (!(step > 0)) return x;
  const double t = x / step;
  const double r = std::round(std::abs(t));
  return step * (t < 0 ? -r : r);
}

SensorReadout::SensorReadout(const SensorModel& model, int axes, double sample_time)
    : noise_(model, axes, sample_time),
      axes_(axes),
      delay_(model.delay),
      angle_step_(model.angle.quantization),
      rate_step_(model.rate.quantization),
      angle_(static_cast<std::size_t>(axes)),
      bias_(static_cast<std::size_t>(axes)),
      rate_(static_cast<std::size_t>(axes)),
      ring_(static_cast<std::size_t>(model.delay + 1) * 2 * static_cast<std::size_t>(axes)) {}

void SensorReadout::measure(const double* X1, const double* X2, double* X1m, double* X2m) {
  noise_.next(angle_.data(), bias_.data(), rate_.data());
  const auto n = static_cast<std::size_t>(axes_);
  const auto slots = static_cast<long long>(delay_) + 1;
  double* now = ring_.data() + static_cast<std::size_t>(k_ % slots) * 2 * n;
  for (std::size_t i = 0; i < n; ++i) {
    now[i] = quantize(X1[i] + angle_[i], angle_step_);
    now[n + i] = quantize((X2[i] + bias_[i]) + rate_[i], rate_step_);  // (X2 + b_k) + σ_r z
  }
  const long long from = k_ < delay_ ? 0 : (k_ - delay_) % slots;
  const double* read = ring_.data() + static_cast<std::size_t>(from) * 2 * n;
  for (std::size_t i = 0; i < n; ++i) {
    X1m[i] = read[i];
    X2m[i] = read[n + i];
  }
  ++k_;
}

}  // namespace ftc::sim
