// A scenario's faults as structured fields (run/fault_fields.hpp).
#include "ftc/tune/run/fault_fields.hpp"

#include <algorithm>
#include <array>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "io/text.hpp"

namespace ftc::tune {

using nlohmann::json;

namespace {

// The numeric fields after actuator, kind and profile, in column order.
constexpr std::array<const char*, 8> kNumberFields = {"rate",      "time",  "offset",   "amplitude",
                                                      "frequency", "phase", "fraction", "value"};

// Whether a field applies to the fault, and its value.
bool number_field(const sim::Fault& f, std::size_t i, double& v) {
  switch (i) {
    case 0:
      v = f.profile.rate;
      return f.profile.type == sim::FaultProfileType::incipient;
    case 1:
      v = f.onset;
      return true;
    case 2:
      v = f.offset;
      return f.type == sim::FaultType::bias;
    case 3:
      v = f.amplitude;
      return f.type == sim::FaultType::bias;
    case 4:
      v = f.frequency;
      return f.type == sim::FaultType::bias;
    case 5:
      v = f.phase;
      return f.type == sim::FaultType::bias;
    case 6:
      v = f.fraction;
      return f.type == sim::FaultType::loss_of_effectiveness;
    default:
      v = f.value;
      return f.type == sim::FaultType::stuck;
  }
}

}  // namespace

json fault_fields(const sim::Fault& f) {
  json j;
  j["actuator"] = f.actuator;
  j["kind"] = sim::to_string(f.type);
  j["profile"] = sim::to_string(f.profile.type);
  for (std::size_t i = 0; i < kNumberFields.size(); ++i) {
    double v = 0;
    if (number_field(f, i, v)) j[kNumberFields[i]] = json_io::json_number(v);
  }
  return j;
}

json fault_fields(const std::vector<sim::Fault>& faults) {
  json a = json::array();
  for (const sim::Fault& f : faults) a.push_back(fault_fields(f));
  return a;
}

std::size_t max_faults(const Job& job) {
  std::size_t n = 0;
  for (const sim::Scenario& s : job.scenarios) n = std::max(n, s.faults.size());
  if (job.ensemble && job.ensemble->faults)
    n = std::max(n, static_cast<std::size_t>(std::max(0, job.ensemble->faults->count_hi)));
  return n;
}

std::string fault_columns_header(std::size_t n) {
  std::string h;
  for (std::size_t k = 1; k <= n; ++k) {
    const std::string p = ",fault" + std::to_string(k) + "_";
    h += p + "actuator" + p + "kind" + p + "profile";
    for (const char* f : kNumberFields) h += p + f;
  }
  return h;
}

std::string fault_columns(const std::vector<sim::Fault>& faults, std::size_t n) {
  std::string s;
  for (std::size_t k = 0; k < n; ++k) {
    if (k >= faults.size()) {
      s.append(3 + kNumberFields.size(), ',');
      continue;
    }
    const sim::Fault& f = faults[k];
    s += "," + std::to_string(f.actuator) + "," + sim::to_string(f.type) + "," +
         sim::to_string(f.profile.type);
    for (std::size_t i = 0; i < kNumberFields.size(); ++i) {
      double v = 0;
      s += ",";
      if (number_field(f, i, v)) s += detail::format_number(v, "%.17g");
    }
  }
  return s;
}

}  // namespace ftc::tune
