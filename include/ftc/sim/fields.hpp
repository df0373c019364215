#pragma once
// A struct's numeric fields described once: name, member, valid range, unit, meaning. The sim
// core's validate() functions check values against these tables, and the file formats build
// their readers, messages and JSON Schema from the same tables, so a range is written once.
#include <span>

#include "ftc/sim/range.hpp"

namespace ftc::sim {

template <class T>
struct NumberField {
  const char* name;
  double T::*member;
  Range range;
  const char* unit;
  const char* description;
};

template <class T>
struct IntegerField {
  const char* name;
  int T::*member;
  long long min, max;  // the upper bound of an index into the plant is the plant's n or m
  const char* description;
};

}  // namespace ftc::sim
