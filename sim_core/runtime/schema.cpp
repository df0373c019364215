#include "ftc/runtime/schema.hpp"

#include <cmath>

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

json number_schema(const std::string& doc, const Range& r) {
  json s = {{"type", "number"}};
  if (!doc.empty()) s["description"] = doc;
  annotate(r, s);
  return s;
}

void dedupe_append(Errors& to, Errors from) {
  for (FieldError& e : from) {
    bool known = false;
    for (const FieldError& p : to) known = known || p.path == e.path;
    if (!known) to.push_back(std::move(e));
  }
}

}  // namespace detail
}  // namespace ftc::schema
