#pragma once
// Fast decimal output for trajectory CSVs: exactly what printf's "%.9g" and "%.6f" print, at a
// fraction of the cost of printf or of std::to_chars with a precision. Private to tuner/.
#include <cstddef>
#include <string>

namespace ftc::tune::detail {

// Each writes at `out` and returns one past the last character printed. Both may store
// scratch bytes past that point: give them 24 bytes of room (330 for write_f6 from 1e15 up).
char* write_g9(char* out, double v);
// v[0..count) as write_g9 prints them, each after `separator`: faster than one by one. Needs
// 24 bytes of room per number.
char* write_g9_list(char* out, const double* v, std::size_t count, char separator);
char* write_f6(char* out, double v);
// write_g9's text as a string (the numbers of gnuplot scripts and their data blocks).
std::string g9_string(double v);

}  // namespace ftc::tune::detail
