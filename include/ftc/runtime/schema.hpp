#pragma once
// One description of a JSON file format, used four ways: to read a file strictly (every unknown
// key, wrong type and missing field reported with its JSON path, all at once), to validate a
// struct built in code (ranges and cross-field rules, with the same messages), to write the
// resolved form (every default filled in, keys sorted, so dump() is canonical), and to emit a
// JSON Schema (draft 2020-12) that editors can check files against. The job file, the gains
// file, the controllers and the algorithm settings are described with it, so a field's type,
// default and valid range are written in exactly one place.
//
//   static const auto shape = schema::Object<Scenario>("A fault scenario")
//       .string("name", &Scenario::name, "unique name", schema::kRequired)
//       .number("duration", &Scenario::duration, schema::Range::positive(), "T in s", ...)
//       ...;
//   Scenario s;  schema::read(shape, j, "/scenarios/0", s, errors);
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/range.hpp"

namespace ftc::schema {

using json = nlohmann::json;
using Errors = std::vector<FieldError>;

enum class Presence { optional, required, optional_unwritten_at_default };
inline constexpr Presence kOptional = Presence::optional;
inline constexpr Presence kRequired = Presence::required;
// Optional, and left out of the written form while it holds its default: a key added after
// files were written, whose canonical form (and its sha256) must not change (choice() only).
inline constexpr Presence kUnwrittenAtDefault = Presence::optional_unwritten_at_default;

using ftc::Range;
// JSON Schema keywords of a range (minimum, exclusiveMinimum, ...).
void annotate(const Range& r, json& schema);

// The valid values of an integer: "must be an integer in lo..hi (got v)".
struct IntRange {
  long long min = std::numeric_limits<int>::min();
  long long max = std::numeric_limits<int>::max();
  std::string check(long long v) const;
};

// A JSON value mapped to a T.
template <class T>
class Shape {
 public:
  virtual ~Shape() = default;
  // Types, presence and unknown keys; ranges are validate()'s.
  virtual void read(const json& j, const std::string& path, T& out, Errors& errs) const = 0;
  virtual void validate(const T& value, const std::string& path, Errors& errs) const = 0;
  virtual json write(const T& value) const = 0;
  virtual json json_schema() const = 0;
};

// read() then validate(), reporting a range error only where reading found nothing wrong at that
// path (a missing or mistyped field is reported once).
template <class T>
void read(const Shape<T>& shape, const json& j, const std::string& path, T& out, Errors& errs);

// A JSON Schema document: `shape` with $schema, $id and title.
json document(const json& shape_schema, const std::string& id, const std::string& title);

namespace detail {
std::string type_error(const char* expected, const json& v);
std::string choice_error(const std::vector<std::string>& names, const std::string& got);
bool read_number(const json& v, const std::string& path, double& out, Errors& errs);
// A non-negative integer of up to 64 bits; false (and an error) for anything else.
bool read_uint64(const json& v, const std::string& path, std::uint64_t& out, Errors& errs);
json uint64_schema(const std::string& doc);
json number_schema(const std::string& doc, const Range& r);
void dedupe_append(Errors& to, Errors from);
}  // namespace detail

// An object with named fields, each bound to a member of T.
template <class T>
class Object final : public Shape<T> {
 public:
  struct Field {
    std::string key;
    bool required = false;
    std::function<void(const json&, const std::string&, T&, Errors&)> read;
    std::function<void(const T&, const std::string&, Errors&)> validate;
    // Writes the field into an object (or leaves it out when absent).
    std::function<void(const T&, json&)> write;
    std::function<json()> schema;
  };
  using Rule = std::function<void(const T&, const std::string& path, Errors&)>;

  explicit Object(std::string description = "") : description_(std::move(description)) {}

  Object& field(Field f) {
    fields_.push_back(std::move(f));
    return *this;
  }
  // A cross-field rule (validation only; JSON Schema cannot say it).
  Object& rule(Rule r) {
    rules_.push_back(std::move(r));
    return *this;
  }
  // Message for a key this object does not have (default: unknown key, listing the allowed).
  Object& unknown_key_message(std::function<std::string(const std::string& key)> m) {
    unknown_ = std::move(m);
    return *this;
  }

  // With `check` false the range is only stated (in the JSON Schema): a rule of the object
  // checks it, e.g. the simulation core's own validate().
  Object& number(std::string key, double T::*m, Range r, std::string doc, Presence p = kOptional,
                 bool check = true) {
    const double dflt = T{}.*m;
    return field({key, p == kRequired,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    detail::read_number(v, path, out.*m, e);
                  },
                  [m, r, check](const T& t, const std::string& path, Errors& e) {
                    if (!check) return;
                    if (std::string msg = r.check(t.*m); !msg.empty()) e.push_back({path, msg});
                  },
                  [m, key](const T& t, json& o) { o[key] = t.*m; },
                  [doc, r, dflt, p] {
                    json s = detail::number_schema(doc, r);
                    if (p == kOptional && std::isfinite(dflt)) s["default"] = dflt;
                    return s;
                  }});
  }
  Object& optional_number(std::string key, std::optional<double> T::*m, Range r, std::string doc,
                          bool check = true) {
    return field({key, false,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    double d = 0;
                    if (detail::read_number(v, path, d, e)) out.*m = d;
                  },
                  [m, r, check](const T& t, const std::string& path, Errors& e) {
                    if (!check || !(t.*m)) return;
                    if (std::string msg = r.check(*(t.*m)); !msg.empty()) e.push_back({path, msg});
                  },
                  [m, key](const T& t, json& o) {
                    if (t.*m) o[key] = *(t.*m);
                  },
                  [doc, r] { return detail::number_schema(doc, r); }});
  }
  Object& integer(std::string key, int T::*m, IntRange r, std::string doc, Presence p = kOptional,
                  bool check = true) {
    const int dflt = T{}.*m;
    return field({key, p == kRequired,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    long long i = 0;
                    if (!json_io::json_to_int(v, i) || i < std::numeric_limits<int>::min() ||
                        i > std::numeric_limits<int>::max())
                      e.push_back({path, detail::type_error("an integer", v)});
                    else
                      out.*m = static_cast<int>(i);
                  },
                  [m, r, check](const T& t, const std::string& path, Errors& e) {
                    if (!check) return;
                    if (std::string msg = r.check(t.*m); !msg.empty()) e.push_back({path, msg});
                  },
                  [m, key](const T& t, json& o) { o[key] = t.*m; },
                  [doc, r, dflt, p] {
                    json s = {{"type", "integer"}, {"description", doc}};
                    s["minimum"] = r.min;
                    s["maximum"] = r.max;
                    if (p == kOptional) s["default"] = dflt;
                    return s;
                  }});
  }
  Object& boolean(std::string key, bool T::*m, std::string doc, Presence p = kOptional) {
    const bool dflt = T{}.*m;
    return field({key, p == kRequired,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    if (!v.is_boolean())
                      e.push_back({path, detail::type_error("true or false", v)});
                    else
                      out.*m = v.get<bool>();
                  },
                  [](const T&, const std::string&, Errors&) {},
                  [m, key](const T& t, json& o) { o[key] = t.*m; },
                  [doc, dflt, p] {
                    json s = {{"type", "boolean"}, {"description", doc}};
                    if (p == kOptional) s["default"] = dflt;
                    return s;
                  }});
  }
  Object& uint64(std::string key, std::uint64_t T::*m, std::string doc, Presence p = kOptional) {
    const std::uint64_t dflt = T{}.*m;
    return field({key, p == kRequired,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    detail::read_uint64(v, path, out.*m, e);
                  },
                  [](const T&, const std::string&, Errors&) {},
                  [m, key](const T& t, json& o) { o[key] = t.*m; },
                  [doc, dflt, p] {
                    json s = detail::uint64_schema(doc);
                    if (p == kOptional) s["default"] = dflt;
                    return s;
                  }});
  }
  // A non-negative integer of up to 64 bits that may be absent (and is then not written).
  Object& optional_uint64(std::string key, std::optional<std::uint64_t> T::*m, std::string doc) {
    return field({key, false,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    std::uint64_t u = 0;
                    if (detail::read_uint64(v, path, u, e)) out.*m = u;
                  },
                  [](const T&, const std::string&, Errors&) {},
                  [m, key](const T& t, json& o) {
                    if (t.*m) o[key] = *(t.*m);
                  },
                  [doc] { return detail::uint64_schema(doc); }});
  }
  // A string; `check` (optional) returns a message for an invalid value.
  Object& string(std::string key, std::string T::*m, std::string doc, Presence p = kOptional,
                 std::function<std::string(const std::string&)> check = {},
                 std::string pattern = "") {
    return field({key, p == kRequired,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    if (!v.is_string())
                      e.push_back({path, detail::type_error("a string", v)});
                    else
                      out.*m = v.get<std::string>();
                  },
                  [m, check](const T& t, const std::string& path, Errors& e) {
                    if (!check) return;
                    if (std::string msg = check(t.*m); !msg.empty()) e.push_back({path, msg});
                  },
                  [m, key](const T& t, json& o) { o[key] = t.*m; },
                  [doc, pattern] {
                    json s = {{"type", "string"}, {"description", doc}};
                    if (!pattern.empty()) s["pattern"] = pattern;
                    return s;
                  }});
  }
  // A string naming one of an enumeration's values.
  template <class E>
  Object& choice(std::string key, E T::*m, std::vector<std::pair<std::string, E>> values,
                 std::string doc, Presence p = kOptional) {
    const E dflt = T{}.*m;
    std::vector<std::string> names;
    for (const auto& [n, e] : values) names.push_back(n);
    return field({key, p == kRequired,
                  [m, values, names](const json& v, const std::string& path, T& out, Errors& e) {
                    if (!v.is_string()) {
                      e.push_back({path, detail::type_error("a string", v)});
                      return;
                    }
                    const std::string s = v.get<std::string>();
                    for (const auto& [n, val] : values)
                      if (n == s) {
                        out.*m = val;
                        return;
                      }
                    e.push_back({path, detail::choice_error(names, s)});
                  },
                  [](const T&, const std::string&, Errors&) {},
                  [m, key, values, dflt, p](const T& t, json& o) {
                    if (p == kUnwrittenAtDefault && t.*m == dflt) return;
                    for (const auto& [n, val] : values)
                      if (val == t.*m) o[key] = n;
                  },
                  [doc, names, values, dflt, p] {
                    json s = {{"type", "string"}, {"enum", names}, {"description", doc}};
                    if (p != kRequired)
                      for (const auto& [n, val] : values)
                        if (val == dflt) s["default"] = n;
                    return s;
                  }});
  }
  // A fixed number of numbers (a std::array, or a std::vector whose size is `count`).
  template <class Seq>
  Object& numbers(std::string key, Seq T::*m, std::size_t count, Range r, std::string doc,
                  Presence p = kOptional, bool check = true) {
    return field(
        {key, p == kRequired,
         [m, count](const json& v, const std::string& path, T& out, Errors& e) {
           if (!v.is_array() || v.size() != count) {
             e.push_back({path, "expected an array of " + std::to_string(count) + " numbers, got " +
                                    (v.is_array() ? "an array of " + std::to_string(v.size())
                                                  : json_io::json_type_name(v))});
             return;
           }
           Seq s = out.*m;
           if constexpr (requires { s.resize(count); }) s.resize(count);
           bool ok = true;
           for (std::size_t i = 0; i < count; ++i)
             ok = detail::read_number(v[i], path + "/" + std::to_string(i), s[i], e) && ok;
           if (ok) out.*m = s;
         },
         [m, r, check](const T& t, const std::string& path, Errors& e) {
           if (!check) return;
           const Seq& s = t.*m;
           for (std::size_t i = 0; i < s.size(); ++i)
             if (std::string msg = r.check(s[i]); !msg.empty())
               e.push_back({path + "/" + std::to_string(i), msg});
         },
         [m, key](const T& t, json& o) {
           const Seq& s = t.*m;
           o[key] = std::vector<double>(s.begin(), s.end());
         },
         [doc, r, count] {
           return json{{"type", "array"},
                       {"items", detail::number_schema("", r)},
                       {"minItems", count},
                       {"maxItems", count},
                       {"description", doc}};
         }});
  }
  // Numbers of any count (checked by a rule where it matters).
  Object& number_list(std::string key, std::vector<double> T::*m, Range r, std::string doc,
                      Presence p = kOptional, bool check = true) {
    return field({key, p == kRequired,
                  [m](const json& v, const std::string& path, T& out, Errors& e) {
                    if (!v.is_array()) {
                      e.push_back({path, detail::type_error("an array of numbers", v)});
                      return;
                    }
                    std::vector<double> s(v.size());
                    bool ok = true;
                    for (std::size_t i = 0; i < v.size(); ++i)
                      ok = detail::read_number(v[i], path + "/" + std::to_string(i), s[i], e) && ok;
                    if (ok) out.*m = std::move(s);
                  },
                  [m, r, check](const T& t, const std::string& path, Errors& e) {
                    if (!check) return;
                    const std::vector<double>& s = t.*m;
                    for (std::size_t i = 0; i < s.size(); ++i)
                      if (std::string msg = r.check(s[i]); !msg.empty())
                        e.push_back({path + "/" + std::to_string(i), msg});
                  },
                  [m, key](const T& t, json& o) { o[key] = t.*m; },
                  [doc, r] {
                    return json{{"type", "array"},
                                {"items", detail::number_schema("", r)},
                                {"description", doc}};
                  }});
  }
  template <class U>
  Object& object(std::string key, U T::*m, std::shared_ptr<const Shape<U>> shape, std::string doc,
                 Presence p = kOptional) {
    return field({key, p == kRequired,
                  [m, shape](const json& v, const std::string& path, T& out, Errors& e) {
                    shape->read(v, path, out.*m, e);
                  },
                  [m, shape](const T& t, const std::string& path, Errors& e) {
                    shape->validate(t.*m, path, e);
                  },
                  [m, key, shape](const T& t, json& o) { o[key] = shape->write(t.*m); },
                  [shape, doc] {
                    json s = shape->json_schema();
                    if (!doc.empty()) s["description"] = doc;
                    return s;
                  }});
  }
  template <class U>
  Object& optional_object(std::string key, std::optional<U> T::*m,
                          std::shared_ptr<const Shape<U>> shape, std::string doc) {
    return field({key, false,
                  [m, shape](const json& v, const std::string& path, T& out, Errors& e) {
                    U u{};
                    shape->read(v, path, u, e);
                    out.*m = std::move(u);
                  },
                  [m, shape](const T& t, const std::string& path, Errors& e) {
                    if (t.*m) shape->validate(*(t.*m), path, e);
                  },
                  [m, key, shape](const T& t, json& o) {
                    if (t.*m) o[key] = shape->write(*(t.*m));
                  },
                  [shape, doc] {
                    json s = shape->json_schema();
                    if (!doc.empty()) s["description"] = doc;
                    return s;
                  }});
  }
  // An array of items; with `keep_empty` false an empty array is left out when writing.
  template <class U>
  Object& array(std::string key, std::vector<U> T::*m, std::shared_ptr<const Shape<U>> item,
                std::string doc, Presence p = kOptional, bool keep_empty = true) {
    return field(
        {key, p == kRequired,
         [m, item](const json& v, const std::string& path, T& out, Errors& e) {
           if (!v.is_array()) {
             e.push_back({path, detail::type_error("an array", v)});
             return;
           }
           std::vector<U> items(v.size());
           for (std::size_t i = 0; i < v.size(); ++i)
             item->read(v[i], path + "/" + std::to_string(i), items[i], e);
           out.*m = std::move(items);
         },
         [m, item](const T& t, const std::string& path, Errors& e) {
           const std::vector<U>& items = t.*m;
           for (std::size_t i = 0; i < items.size(); ++i)
             item->validate(items[i], path + "/" + std::to_string(i), e);
         },
         [m, key, item, keep_empty](const T& t, json& o) {
           const std::vector<U>& items = t.*m;
           if (items.empty() && !keep_empty) return;
           json a = json::array();
           for (const U& u : items) a.push_back(item->write(u));
           o[key] = std::move(a);
         },
         [item, doc] {
           return json{{"type", "array"}, {"items", item->json_schema()}, {"description", doc}};
         }});
  }

  // Reads an object; `also_allowed` are keys handled by an enclosing Variant.
  void read_object(const json& j, const std::string& path, T& out, Errors& errs,
                   const std::set<std::string>& also_allowed) const {
    if (!j.is_object()) {
      errs.push_back({path, "expected an object, got " + json_io::json_type_name(j)});
      return;
    }
    for (const Field& f : fields_) {
      const auto it = j.find(f.key);
      const std::string p = path + "/" + json_io::pointer_escape(f.key);
      if (it == j.end()) {
        if (f.required) errs.push_back({p, "is required"});
        continue;
      }
      f.read(*it, p, out, errs);
    }
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (also_allowed.count(it.key()) || has(it.key())) continue;
      errs.push_back({path + "/" + json_io::pointer_escape(it.key()),
                      unknown_ ? unknown_(it.key()) : unknown_key_text(it.key(), also_allowed)});
    }
  }
  void read(const json& j, const std::string& path, T& out, Errors& errs) const override {
    read_object(j, path, out, errs, {});
  }
  void validate(const T& value, const std::string& path, Errors& errs) const override {
    for (const Field& f : fields_)
      f.validate(value, path + "/" + json_io::pointer_escape(f.key), errs);
    for (const Rule& r : rules_) r(value, path, errs);
  }
  json write(const T& value) const override {
    json o = json::object();
    for (const Field& f : fields_) f.write(value, o);
    return o;
  }
  json json_schema() const override { return object_schema({}); }
  // With extra properties (a Variant's discriminator).
  json object_schema(const json& extra_properties,
                     const std::vector<std::string>& extra_required = {}) const {
    json s = {{"type", "object"}, {"additionalProperties", false}};
    if (!description_.empty()) s["description"] = description_;
    json props = json::object();
    json required = json::array();
    for (const auto& [k, v] : extra_properties.items()) props[k] = v;
    for (const std::string& k : extra_required) required.push_back(k);
    for (const Field& f : fields_) {
      props[f.key] = f.schema();
      if (f.required) required.push_back(f.key);
    }
    s["properties"] = props;
    if (!required.empty()) s["required"] = required;
    return s;
  }
  bool has(const std::string& key) const { return field_index(key) < fields_.size(); }
  // The field's place in the order read() reports errors in (its fields', then unknown keys'):
  // the number of fields for a key that is not one.
  std::size_t field_index(const std::string& key) const {
    std::size_t i = 0;
    while (i < fields_.size() && fields_[i].key != key) ++i;
    return i;
  }

 private:
  std::string unknown_key_text(const std::string& key,
                               const std::set<std::string>& also_allowed) const {
    std::set<std::string> keys(also_allowed);
    for (const Field& f : fields_) keys.insert(f.key);
    std::string allowed;
    for (const std::string& k : keys) allowed += (allowed.empty() ? "" : ", ") + k;
    return "unknown key (allowed here: " + allowed + ")" +
           json_io::did_you_mean(key, {keys.begin(), keys.end()});
  }

  std::string description_;
  std::vector<Field> fields_;
  std::vector<Rule> rules_;
  std::function<std::string(const std::string&)> unknown_;
};

// An object whose fields depend on a discriminating string key ("type", "model"): each value
// selects an Object<T> with the fields of that case.
template <class T>
class Variant final : public Shape<T> {
 public:
  struct Case {
    std::string name;
    std::shared_ptr<const Object<T>> shape;
  };
  // get/set translate between T and the case name; `fallback` is the case when the key is
  // absent ("" = the key is required); `unknown` words the error for a name no case has.
  Variant(std::string key, std::function<std::string(const T&)> get,
          std::function<void(T&, const std::string&)> set, std::string description,
          std::string fallback = "", std::function<std::string(const std::string&)> unknown = {})
      : key_(std::move(key)),
        get_(std::move(get)),
        set_(std::move(set)),
        description_(std::move(description)),
        fallback_(std::move(fallback)),
        unknown_(std::move(unknown)) {}

  Variant& add(std::string name, std::shared_ptr<const Object<T>> shape) {
    cases_.push_back({std::move(name), std::move(shape)});
    return *this;
  }

  void read(const json& j, const std::string& path, T& out, Errors& errs) const override {
    if (!j.is_object()) {
      errs.push_back({path, "expected an object, got " + json_io::json_type_name(j)});
      return;
    }
    const std::string kp = path + "/" + json_io::pointer_escape(key_);
    std::string name = fallback_;
    if (const auto it = j.find(key_); it != j.end()) {
      if (!it->is_string()) {
        errs.push_back({kp, detail::type_error("a string", *it)});
        return;
      }
      name = it->get<std::string>();
    } else if (name.empty()) {
      errs.push_back({kp, "is required"});
      return;
    }
    const Case* c = find(name);
    if (!c) {
      std::vector<std::string> names;
      for (const Case& k : cases_) names.push_back(k.name);
      errs.push_back({kp, unknown_ ? unknown_(name) : detail::choice_error(names, name)});
      return;
    }
    set_(out, name);
    c->shape->read_object(j, path, out, errs, {key_});
  }
  void validate(const T& value, const std::string& path, Errors& errs) const override {
    if (const Case* c = find(get_(value))) c->shape->validate(value, path, errs);
  }
  json write(const T& value) const override {
    const Case* c = find(get_(value));
    json o = c ? c->shape->write(value) : json::object();
    o[key_] = get_(value);
    return o;
  }
  json json_schema() const override {
    json cases = json::array();
    for (const Case& c : cases_)
      cases.push_back(c.shape->object_schema({{key_, {{"const", c.name}}}},
                                             fallback_.empty() || c.name != fallback_
                                                 ? std::vector<std::string>{key_}
                                                 : std::vector<std::string>{}));
    json s = {{"type", "object"}, {"oneOf", cases}};
    if (!description_.empty()) s["description"] = description_;
    return s;
  }
  const std::vector<Case>& cases() const { return cases_; }

 private:
  const Case* find(const std::string& name) const {
    for (const Case& c : cases_)
      if (c.name == name) return &c;
    return nullptr;
  }

  std::string key_;
  std::function<std::string(const T&)> get_;
  std::function<void(T&, const std::string&)> set_;
  std::string description_;
  std::string fallback_;
  std::function<std::string(const std::string&)> unknown_;
  std::vector<Case> cases_;
};

// A shape built by `make` again whenever `generation()` changes: what depends on the plant kinds
// a job can name (the plant, a scenario's true values, an ensemble's scales), which grow when a
// plant plugin is loaded. It is the one object its holders keep; each call reads the current
// build. Thread-safe.
template <class T>
class Regenerated final : public Shape<T> {
 public:
  Regenerated(std::function<std::shared_ptr<const Shape<T>>()> make,
              std::function<std::uint64_t()> generation)
      : make_(std::move(make)), generation_(std::move(generation)) {}

  void read(const json& j, const std::string& path, T& out, Errors& errs) const override {
    current()->read(j, path, out, errs);
  }
  void validate(const T& value, const std::string& path, Errors& errs) const override {
    current()->validate(value, path, errs);
  }
  json write(const T& value) const override { return current()->write(value); }
  json json_schema() const override { return current()->json_schema(); }

  std::shared_ptr<const Shape<T>> current() const {
    std::lock_guard lock(mutex_);
    const std::uint64_t g = generation_();
    if (!shape_ || g != built_) {
      shape_ = make_();
      built_ = g;
    }
    return shape_;
  }

 private:
  std::function<std::shared_ptr<const Shape<T>>()> make_;
  std::function<std::uint64_t()> generation_;
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const Shape<T>> shape_;
  mutable std::uint64_t built_ = 0;
};

template <class T>
void read(const Shape<T>& shape, const json& j, const std::string& path, T& out, Errors& errs) {
  shape.read(j, path, out, errs);
  Errors range;
  shape.validate(out, path, range);
  detail::dedupe_append(errs, std::move(range));
}

}  // namespace ftc::schema
