#pragma once
// Reading an optimiser's saved state (a checkpoint) field by field: every size, range and type is
// checked, and a bad field is an InputError with source "checkpoint" and the field's JSON path
// inside the state. A checkpoint is input like any other: its digest proves it is intact, not
// that whoever wrote it wrote a sound state.
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "ftc/tune/optimizers/search_space.hpp"

namespace ftc::tune::state_check {

// Throws InputError("checkpoint", path, message).
[[noreturn]] void fail(const std::string& path, const std::string& message);

// The member `key` of the object `j` at `path` (which must be an object holding it).
const nlohmann::json& member(const nlohmann::json& j, const std::string& path, const char* key);
// An integer in [lo, hi].
std::int64_t integer(const nlohmann::json& j, const std::string& path, std::int64_t lo,
                     std::int64_t hi);
// A number in [lo, hi] (a finite one unless the bounds are infinite).
double number(const nlohmann::json& j, const std::string& path, double lo, double hi);
// A fitness: a number from -1 on (an infeasible candidate's -V/(1+V) is above -1), or null for a
// diverged one (read as +inf, as state() writes it).
double fitness(const nlohmann::json& j, const std::string& path);
bool boolean(const nlohmann::json& j, const std::string& path);
// A vector of the space's dimension of finite numbers, inside its bounds when `bounded`.
Decision decision(const nlohmann::json& j, const std::string& path, const SearchSpace& space,
                  bool bounded);
// The array at `path`, of exactly `size` elements.
const nlohmann::json& array(const nlohmann::json& j, const std::string& path, std::size_t size);

}  // namespace ftc::tune::state_check
