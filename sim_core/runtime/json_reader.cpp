#include "ftc/runtime/json_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

namespace ftc::json_io {

std::optional<std::string> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

using nlohmann::json;

std::string json_type_name(const json& j) {
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_null()) return "null";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return j.type_name();
}

std::string number_text(double v, int significant) {
  std::ostringstream o;
  o.precision(significant);
  o << v;
  return o.str();
}

std::string pointer_escape(const std::string& key) {
  std::string s;
  for (char c : key) {
    if (c == '~')
      s += "~0";
    else if (c == '/')
      s += "~1";
    else
      s += c;
  }
  return s;
}

std::string did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  const auto lower = [](std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string a = lower(name);
  std::string best;
  std::size_t best_d = 3;  // more than two edits is not a near miss
  int ties = 0;            // a guess between equally near names would mislead
  for (const std::string& cand : candidates) {
    const std::string b = lower(cand);
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diag = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    // Short names need a closer match: "c1" is one edit from "c2" and means something else.
    const std::size_t d = row[b.size()];
    if (d * 3 > std::max(a.size(), b.size()) || cand == name) continue;
    if (d < best_d) {
      best_d = d;
      best = cand;
      ties = 0;
    } else if (d == best_d) {
      ++ties;
    }
  }
  return best.empty() || ties > 0 ? "" : "; did you mean \"" + best + "\"?";
}

json parse_json_text(const std::string& text, const std::string& source) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    std::string msg = e.what();  // drop the "[json.exception.parse_error.101] " prefix
    if (auto pos = msg.find("] "); msg.rfind("[json.exception", 0) == 0 && pos != std::string::npos)
      msg = msg.substr(pos + 2);
    throw InputError(source, "", "invalid JSON: " + msg);
  }
}

json json_number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

double json_number_or(const json& j, double if_null) {
  return j.is_number() ? j.get<double>() : if_null;
}

bool json_to_int(const json& v, long long& out) {
  if (v.is_number_integer()) {
    out = v.is_number_unsigned() ? static_cast<long long>(v.get<std::uint64_t>())
                                 : v.get<long long>();
    return true;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (std::isfinite(d) && d == std::floor(d) && std::abs(d) < 9e15) {
      out = static_cast<long long>(d);
      return true;
    }
  }
  return false;
}

ObjectReader::ObjectReader(const json& j, std::string path, std::vector<FieldError>& errors)
    : obj_(j.is_object() ? &j : nullptr), path_(std::move(path)), errors_(errors) {
  if (!obj_) errors_.push_back({path_, "expected an object, got " + json_type_name(j)});
}

const json* ObjectReader::get(const char* key, bool required) {
  if (!obj_) return nullptr;
  seen_.insert(key);
  auto it = obj_->find(key);
  if (it == obj_->end()) {
    if (required) errors_.push_back({path(key), "is required"});
    return nullptr;
  }
  return &*it;
}

void ObjectReader::type_error(const char* key, const char* expected, const json& v) {
  errors_.push_back(
      {path(key), std::string("expected ") + expected + ", got " + json_type_name(v)});
}

bool ObjectReader::number(const char* key, double& out, bool required) {
  const json* v = get(key, required);
  if (!v) return false;
  if (!v->is_number()) {
    type_error(key, "a number", *v);
    return false;
  }
  out = v->get<double>();
  return true;
}

bool ObjectReader::integer(const char* key, int& out, bool required) {
  const json* v = get(key, required);
  if (!v) return false;
  long long i = 0;
  if (!json_to_int(*v, i) || i < -2147483647LL || i > 2147483647LL) {
    type_error(key, "an integer", *v);
    return false;
  }
  out = static_cast<int>(i);
  return true;
}

bool ObjectReader::uint64(const char* key, std::uint64_t& out, bool required) {
  const json* v = get(key, required);
  if (!v) return false;
  if (v->is_number_unsigned()) {
    out = v->get<std::uint64_t>();
    return true;
  }
  long long i = 0;
  if (!json_to_int(*v, i) || i < 0) {
    type_error(key, "a non-negative integer", *v);
    return false;
  }
  out = static_cast<std::uint64_t>(i);
  return true;
}

bool ObjectReader::string(const char* key, std::string& out, bool required) {
  const json* v = get(key, required);
  if (!v) return false;
  if (!v->is_string()) {
    type_error(key, "a string", *v);
    return false;
  }
  out = v->get<std::string>();
  return true;
}

bool ObjectReader::numbers(const char* key, double* out, std::size_t n, bool required) {
  const json* v = get(key, required);
  if (!v) return false;
  if (!v->is_array() || v->size() != n) {
    errors_.push_back({path(key), "expected an array of " + std::to_string(n) + " numbers, got " +
                                      (v->is_array() ? "an array of " + std::to_string(v->size())
                                                     : json_type_name(*v))});
    return false;
  }
  bool ok = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(*v)[i].is_number()) {
      errors_.push_back({path(key) + "/" + std::to_string(i),
                         "expected a number, got " + json_type_name((*v)[i])});
      ok = false;
    } else {
      out[i] = (*v)[i].get<double>();
    }
  }
  return ok;
}

bool ObjectReader::number_list(const char* key, std::vector<double>& out, bool required) {
  const json* v = get(key, required);
  if (!v) return false;
  if (!v->is_array()) {
    errors_.push_back({path(key), "expected an array of numbers, got " + json_type_name(*v)});
    return false;
  }
  out.assign(v->size(), 0.0);
  return numbers(key, out.data(), out.size(), required);
}

std::vector<std::string> ObjectReader::keys() const {
  std::vector<std::string> k;
  if (obj_)
    for (auto it = obj_->begin(); it != obj_->end(); ++it) k.push_back(it.key());
  return k;
}

const json* ObjectReader::child(const char* key, bool required) { return get(key, required); }

void ObjectReader::finish() {
  if (!obj_) return;
  for (auto it = obj_->begin(); it != obj_->end(); ++it) {
    if (seen_.count(it.key())) continue;
    std::string allowed;
    for (const std::string& k : seen_) allowed += (allowed.empty() ? "" : ", ") + k;
    errors_.push_back({path_ + "/" + pointer_escape(it.key()),
                       "unknown key (allowed here: " + allowed + ")" +
                           did_you_mean(it.key(), {seen_.begin(), seen_.end()})});
  }
}

}  // namespace ftc::json_io
