#pragma once
// A scenario's faults as structured fields, for programs rather than people: evaluation.json
// and evaluation.csv carry them per member (and the Python module's ensemble()). Each fault has
// its actuator (1-based), kind (bias, loss_of_effectiveness, stuck), profile (abrupt,
// incipient), time (the onset, s) and its kind's parameters: rate (1/s, incipient only);
// offset, amplitude, frequency (rad/s), phase (rad) for a bias; fraction for a loss of
// effectiveness; value for a stuck actuator.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ftc/sim/faults.hpp"
#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

// {"actuator", "kind", "profile", "time", then the kind's parameters} (rate only when incipient).
nlohmann::json fault_fields(const sim::Fault& fault);
nlohmann::json fault_fields(const std::vector<sim::Fault>& faults);  // an array of the above

// The most faults any scenario of the job has: its listed ones' and its ensemble members'.
std::size_t max_faults(const Job& job);

// The CSV columns of `n` faults: fault<k>_<field> for k = 1..n and the fields in the order above
// (every field of every kind: a cell that does not apply to the fault, or a fault the scenario
// does not have, is empty). `header` is the names, the other the values of `faults`; both
// start with a comma (or are empty for n = 0).
std::string fault_columns_header(std::size_t n);
std::string fault_columns(const std::vector<sim::Fault>& faults, std::size_t n);

}  // namespace ftc::tune
