#pragma once
// A structure-aware mutator for the targets whose input is (or carries) a JSON document. Byte
// mutations almost never keep a job file both parseable and valid (in a first trial 15 of ~1800
// inputs the job target kept were valid jobs), so the checks that run on accepted input saw
// little beyond the seeds. This mutator edits the document instead: it swaps a value for an edge
// case, nudges a number, deletes a member, or copies a subtree from elsewhere in the document,
// then writes it out again. One mutation in four is still libFuzzer's own byte mutation, so the
// JSON reader itself is fuzzed too.
//
// That alone was not enough: the corpus fills with invalid inputs (each error message is new
// coverage) and edits of them stay invalid. So the targets remember the inputs they accepted,
// and half the mutations start from one of those instead of from the input libFuzzer picked.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <string_view>
#include <vector>

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace ftc::fuzz {

namespace json_mutation {

using nlohmann::json;

struct Node {
  json* value;
  json* parent;  // nullptr for the root
  std::string key;
  std::size_t index = 0;
};

inline void collect(json& j, json* parent, const std::string& key, std::size_t index,
                    std::vector<Node>& nodes, std::vector<std::string>& strings) {
  nodes.push_back({&j, parent, key, index});
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      strings.push_back(it.key());
      collect(it.value(), &j, it.key(), 0, nodes, strings);
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) collect(j[i], &j, "", i, nodes, strings);
  } else if (j.is_string()) {
    strings.push_back(j.get<std::string>());
  }
}

inline json edge_number(std::minstd_rand& rng) {
  static const double doubles[] = {0.0,
                                   -0.0,
                                   0.5,
                                   -1.0,
                                   1e-300,
                                   5e-324,
                                   1e-12,
                                   1e12,
                                   1e300,
                                   -1e300,
                                   1.7976931348623157e308,
                                   0.1,
                                   3.0,
                                   1e6,
                                   1e9,
                                   2147483648.0,
                                   1e-9,
                                   2.5e-4,
                                   100.0,
                                   -0.001};
  static const std::int64_t ints[] = {0,
                                      1,
                                      -1,
                                      2,
                                      3,
                                      4,
                                      7,
                                      8,
                                      100,
                                      1000000,
                                      1000001,
                                      std::numeric_limits<std::int32_t>::max(),
                                      std::numeric_limits<std::int64_t>::max(),
                                      std::numeric_limits<std::int64_t>::min()};
  switch (rng() % 3) {
    case 0:
      return doubles[rng() % std::size(doubles)];
    case 1:
      return ints[rng() % std::size(ints)];
    default:
      return std::numeric_limits<std::uint64_t>::max() - rng() % 2;
  }
}

inline json nudged(const json& v, std::minstd_rand& rng) {
  const double x = v.get<double>();
  switch (rng() % 6) {
    case 0:
      return x * 10;
    case 1:
      return x / 10;
    case 2:
      return -x;
    case 3:
      return x + 1;
    case 4:  // one below, exactly for integers (no wrap-around of its own)
      if (v.is_number_unsigned() && v.get<std::uint64_t>() > 0) return v.get<std::uint64_t>() - 1;
      if (v.is_number_integer() && v.get<std::int64_t>() > std::numeric_limits<std::int64_t>::min())
        return v.get<std::int64_t>() - 1;
      return x - 1;
    default:
      return x * (1 + 1e-15);
  }
}

inline json edge_string(const std::vector<std::string>& pool, std::minstd_rand& rng) {
  switch (rng() % 5) {
    case 0:
      return "";
    case 1:
      return std::string(1 + rng() % 120, 'a');
    case 2:
      return pool.empty() ? std::string("x") : pool[rng() % pool.size()] + "-" + pool[0];
    default:
      return pool.empty() ? std::string("x") : pool[rng() % pool.size()];
  }
}

// One edit of `doc` in place.
inline void mutate_once(json& doc, std::minstd_rand& rng) {
  std::vector<Node> nodes;
  std::vector<std::string> strings;
  collect(doc, nullptr, "", 0, nodes, strings);
  const Node& n = nodes[rng() % nodes.size()];
  const json source = *nodes[rng() % nodes.size()].value;  // a copy: it may be n's subtree
  switch (rng() % 8) {
    case 0:  // a scalar of another kind
      switch (rng() % 4) {
        case 0:
          *n.value = nullptr;
          break;
        case 1:
          *n.value = static_cast<bool>(rng() % 2);
          break;
        case 2:
          *n.value = json::array();
          break;
        default:
          *n.value = json::object();
      }
      break;
    case 1:
    case 2:  // numbers are most of what the loaders check
      *n.value = n.value->is_number() && rng() % 2 ? nudged(*n.value, rng) : edge_number(rng);
      break;
    case 3:
      *n.value = edge_string(strings, rng);
      break;
    case 4:  // delete it
      if (n.parent && n.parent->is_object())
        n.parent->erase(n.key);
      else if (n.parent)
        n.parent->erase(n.index);
      break;
    case 5:  // a copy of another part of the document in its place
      *n.value = source;
      break;
    default:  // grow an array or an object with a copy of another part
      if (n.value->is_array())
        n.value->push_back(source);
      else if (n.value->is_object() && !strings.empty())
        (*n.value)[strings[rng() % strings.size()]] = source;
      else
        *n.value = source;
  }
}

}  // namespace json_mutation

// Inputs the target accepted, the newest in place of the oldest. Slots allocated up front: an
// input that allocates what it does not free looks like a leak to libFuzzer, whose leak check
// (10 ms) then runs after it.
struct AcceptedPool {
  static constexpr std::size_t kSize = 512;
  std::array<std::string, kSize> inputs;
  std::size_t count = 0;
  AcceptedPool() {
    for (std::string& s : inputs) s.reserve(8192);
  }
  std::size_t size() const { return count < kSize ? count : kSize; }
};
inline AcceptedPool& accepted_pool() {
  static AcceptedPool pool;
  return pool;
}
inline void remember_accepted(std::string_view input) {
  AcceptedPool& pool = accepted_pool();
  pool.inputs[pool.count++ % AcceptedPool::kSize] = input;
}

// Half the time, replaces `data` with an accepted input (when one fits). Returns the size.
inline std::size_t from_accepted(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                 std::minstd_rand& rng) {
  const AcceptedPool& pool = accepted_pool();
  if (pool.size() == 0 || rng() % 2 == 0) return size;
  const std::string& pick = pool.inputs[rng() % pool.size()];
  if (pick.size() > max_size) return size;
  std::memcpy(data, pick.data(), pick.size());
  return pick.size();
}

// A mutation of `data`, a JSON text at [offset, size), for LLVMFuzzerCustomMutator. The
// prefix before `offset` is kept as it is; without one, `data` may first be swapped for an
// accepted input. Returns the new size.
inline std::size_t mutate_json(std::uint8_t* data, std::size_t size, std::size_t max_size,
                               unsigned int seed, std::size_t offset = 0) {
  std::minstd_rand rng(seed);
  if (offset == 0) size = from_accepted(data, size, max_size, rng);
  if (offset > size || rng() % 4 == 0) return LLVMFuzzerMutate(data, size, max_size);
  nlohmann::json doc = nlohmann::json::parse(data + offset, data + size, nullptr, false);
  if (doc.is_discarded()) return LLVMFuzzerMutate(data, size, max_size);
  for (unsigned int k = 1 + rng() % 3; k > 0; --k) json_mutation::mutate_once(doc, rng);
  const std::string text =
      doc.dump(rng() % 2 ? -1 : 1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (offset + text.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
  std::memcpy(data + offset, text.data(), text.size());
  return offset + text.size();
}

}  // namespace ftc::fuzz

// Defines the target's LLVMFuzzerCustomMutator as mutate_json: for a target whose whole input is
// a JSON document.
#define FTC_FUZZ_JSON_INPUT()                                                               \
  extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,      \
                                                 std::size_t max_size, unsigned int seed) { \
    return ftc::fuzz::mutate_json(data, size, max_size, seed);                              \
  }
