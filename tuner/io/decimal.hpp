#pragma once
// Fast decimal output for trajectory CSVs: exactly what printf's "%.9g" and "%.6f" print, at a
// fraction of the cost of printf or of std::to_chars with a precision. Private to tuner/.
namespace ftc::tune::detail {

// Each writes at `out` and returns one past the last character printed. Both may store
// scratch bytes past that point: give them 24 bytes of room (330 for write_f6 from 1e15 up).
char* write_g9(char* out, double v);
char* write_f6(char* out, double v);

}  // namespace ftc::tune::detail
