#include "ftc/runtime/schema.hpp"

#include <cmath>
#include <limits>
#include <string_view>
#include <unordered_set>
#include <vector>

namespace ftc::schema {

void annotate(const Range& r, json& s) {
  if (std::isfinite(r.min)) s[r.min_open ? "exclusiveMinimum" : "minimum"] = r.min;
  if (std::isfinite(r.max)) s[r.max_open ? "exclusiveMaximum" : "maximum"] = r.max;
}

std::string IntRange::check(long long v) const {
  if (v >= min && v <= max) return "";
  return "must be an integer in " + std::to_string(min) + ".." + std::to_string(max) + " (got " +
         std::to_string(v) + ")";
}

json document(const json& shape_schema, const std::string& id, const std::string& title) {
  json d = shape_schema;
  d["$schema"] = "https://json-schema.org/draft/2020-12/schema";
  d["$id"] = id;
  d["title"] = title;
  return d;
}

namespace detail {

std::string type_error(const char* expected, const json& v) {
  return std::string("expected ") + expected + ", got " + json_io::json_type_name(v);
}

std::string choice_error(const std::vector<std::string>& names, const std::string& got) {
  std::string s;
  if (names.size() == 2) {
    s = "must be \"" + names[0] + "\" or \"" + names[1] + "\"";
  } else {
    s = "must be one of ";
    for (std::size_t i = 0; i < names.size(); ++i) s += (i ? ", " : "") + names[i];
  }
  return s + " (got \"" + got + "\")" + json_io::did_you_mean(got, names);
}

bool read_number(const json& v, const std::string& path, double& out, Errors& errs) {
  if (!v.is_number()) {
    errs.push_back({path, type_error("a number", v)});
    return false;
  }
  out = v.get<double>();
  return true;
}

bool read_uint64(const json& v, const std::string& path, std::uint64_t& out, Errors& errs) {
  long long i = 0;
  if (v.is_number_unsigned())
    out = v.get<std::uint64_t>();
  else if (json_io::json_to_int(v, i) && i >= 0)
    out = static_cast<std::uint64_t>(i);
  else {
    errs.push_back({path, type_error("a non-negative integer", v)});
    return false;
  }
  return true;
}

json uint64_schema(const std::string& doc) {
  return {{"type", "integer"},
          {"minimum", 0},
          {"maximum", std::numeric_limits<std::uint64_t>::max()},
          {"description", doc}};
}

json number_schema(const std::string& doc, const Range& r) {
  json s = {{"type", "number"}};
  if (!doc.empty()) s["description"] = doc;
  annotate(r, s);
  return s;
}

// Linear in the errors. With each path compared against every earlier one it was quadratic:
// `validate` of a job of 30 000 empty scenarios took 4.1 s (0.37 s now; 100 000 take 1.1 s).
void dedupe_append(Errors& to, Errors from) {
  if (from.empty()) return;
  // The views are taken after the reserve and dropped before anything moves.
  to.reserve(to.size() + from.size());
  std::unordered_set<std::string_view> known;
  known.reserve(to.size() + from.size());
  for (const FieldError& p : to) known.insert(p.path);
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < from.size(); ++i)
    if (known.insert(from[i].path).second) keep.push_back(i);
  for (std::size_t i : keep) to.push_back(std::move(from[i]));
}

}  // namespace detail
}  // namespace ftc::schema
