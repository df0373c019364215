// Strict JSON reading (sim_core/runtime/json_reader.cpp): a file read as a stream, with the
// elements of one array handed over one by one, is read exactly as its whole text is.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/input_error.hpp"
#include "peak_memory.hpp"

namespace {

using ftc::FieldError;
using ftc::InputError;
using nlohmann::json;
namespace json_io = ftc::json_io;

void write(const std::filesystem::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

// What reading fails with: the source and its first error, or nullopt when it is accepted.
struct Failure {
  std::string source, path, message;
};
std::optional<Failure> failure_of(const std::function<void()>& read) {
  try {
    read();
  } catch (const InputError& e) {
    EXPECT_EQ(e.errors().size(), 1u) << e.what();
    return Failure{e.source(), e.errors().front().path, e.errors().front().message};
  }
  return std::nullopt;
}

// The file read with its "scenarios" array streamed: the document with the elements put back.
json streamed(const std::filesystem::path& p, std::vector<std::size_t>* order = nullptr) {
  std::vector<json> items;
  std::optional<json> doc = json_io::parse_json_file(
      p, p.string(), "scenarios", [&](std::size_t i, json&& e) {
        if (order) order->push_back(i);
        items.push_back(std::move(e));
      });
  EXPECT_TRUE(doc.has_value());
  if (!doc) return json();
  if (doc->is_object() && doc->contains("scenarios") && (*doc)["scenarios"].is_array()) {
    EXPECT_TRUE((*doc)["scenarios"].empty());  // nothing of the array is kept
    for (json& e : items) (*doc)["scenarios"].push_back(std::move(e));
  } else {
    EXPECT_TRUE(items.empty());
  }
  return *doc;
}

// Bytes far enough into a file that a reader's 64 KiB buffer has been refilled before them.
std::string padding() {
  json pad = json::array();
  for (int i = 0; i < 5000; ++i) pad.push_back("padding-" + std::to_string(i));
  return pad.dump(1);
}

// A text whose `bytes` start at offset `at` inside a string value, followed by `rest`.
std::string placed(const std::string& bytes, std::size_t at, const std::string& rest) {
  std::string t = "{\"pad\": \"";
  t += std::string(at - t.size(), 'x');
  return t + bytes + rest;
}

}  // namespace

TEST(JsonReader, AFileReadAsAStreamGivesTheDocumentAndErrorsOfItsText) {
  const auto dir = ftc::testing::fresh_dir("json-reader-stream");
  const std::string pad = padding();
  ASSERT_GT(pad.size(), 70000u);
  // A two-byte sequence straddling the first buffer's end, wherever that falls in the padding.
  std::string straddle = "{\"pad\": \"";
  straddle +=
      std::string(65536 - straddle.size() - 1, 'x') + "\xc3\xa9" + "\", \"scenarios\": [1]}";
  const std::vector<std::string> texts = {
      // accepted
      R"({"schema": "s", "scenarios": [{"a": 1}, [2, {"b": []}], 3, "x", null,
          {"scenarios": [4]}]})",
      R"({"scenarios": [], "other": {"scenarios": [5]}})",
      R"([{"scenarios": [6]}])",
      "{\"pad\": " + pad + ", \"scenarios\": [{\"name\": \"\xc3\xa9\xf0\x9f\x9b\xb0\"}]}",
      straddle,
      // refused: the path and the place are those of the whole text's reading
      R"({"scenarios": [{"duration": 1}, {"duration": 1, "duration": 2}]})",
      R"({"scenarios": [{"duration": 1}, {"faults": [{"onset": -1e999}]}]})",
      R"({"scenarios": [1], "scenarios": [2]})",
      "{\"pad\": " + pad + ",\n \"scenarios\": [{\"x\": 1}, {\"y\": 1e400}]}",
      "{\"pad\": " + pad + ",\n \"scenarios\": [{\"x\": \"\xff\"}]}",
      "{\"pad\": " + pad + ",\n \"scenarios\": [{\"x\": \"\xe2\x82\"}]}",
      "{\"pad\": " + pad + ",\n \"scenarios\": [{\"x\": 1},\n  oops]}",
      "{\"scenarios\": [" + std::string(300, '[') + std::string(300, ']') + "]}",
      "{\"scenarios\": [1, 2",
      "",
      // UTF-8 sequences cut by the reader's 64 KiB buffers, and by the end of the file
      placed("\xe2\x82", 65534, "x\", \"scenarios\": [1]}"),
      placed("\xf0", 65535, "\x9f\x9b\xb0\", \"scenarios\": [1]}"),
      placed("\xf0\x9f\x9b", 65533, "\xb0\", \"scenarios\": [1]}"),
      placed("\xf0\x9f\x9b", 65533, "\xb0\xb0\", \"scenarios\": [1]}"),
      placed("\xe2\x82", 65534, ""),
      placed("\xff", 65535, "\", \"scenarios\": [1]}"),
      placed("\xe2", 65535, "x\", \"scenarios\": [1]}"),
      placed("\x80", 65536, "\", \"scenarios\": [1]}"),
      "{\"scenarios\": [\"\xf0\x9f",
  };
  for (std::size_t t = 0; t < texts.size(); ++t) {
    const std::filesystem::path p = dir / ("case-" + std::to_string(t) + ".json");
    write(p, texts[t]);
    json whole, read;
    const auto a = failure_of([&] { whole = json_io::parse_json_text(texts[t], p.string()); });
    const auto b = failure_of([&] { read = streamed(p); });
    ASSERT_EQ(a.has_value(), b.has_value()) << t << ": " << (a ? a->message : b->message);
    if (a) {
      EXPECT_EQ(b->source, a->source) << t;
      EXPECT_EQ(b->path, a->path) << t;
      EXPECT_EQ(b->message, a->message) << t;
    } else {
      EXPECT_EQ(read, whole) << t;
    }
  }
  // The elements come in order, each with its index.
  std::vector<std::size_t> order;
  streamed(dir / "case-0.json", &order);
  EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5}));
  // Where the errors point, checked once by hand: past the first buffer, on the last line.
  const auto e = failure_of([&] { streamed(dir / "case-8.json"); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->path, "/scenarios/1/y");
  EXPECT_NE(e->message.find("out of the range of a double, at line 5003, column 32"),
            std::string::npos)
      << e->message;
}

// The file is read twice (UTF-8, then the parse): bytes that change in between are not parsed.
TEST(JsonReader, AFileChangedWhileItIsReadIsRefused) {
  const auto dir = ftc::testing::fresh_dir("json-reader-changed");
  const std::filesystem::path p = dir / "changing.json";
  const std::string text = "{\"scenarios\": [1, \"" + std::string(200000, 'a') + "\"]}";
  for (const bool shorten : {false, true}) {
    write(p, text);
    // Once the first element is in, past the parser's first buffer a byte becomes 0xFF, or the
    // file loses its end.
    const auto change = [&](std::size_t, json&&) {
      if (shorten) {
        std::filesystem::resize_file(p, 100000);
      } else {
        std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(150000);
        f.put('\xff');
      }
    };
    const auto e = failure_of([&] { json_io::parse_json_file(p, "c", "scenarios", change); });
    ASSERT_TRUE(e) << shorten;
    EXPECT_EQ(e->message, "changed while it was read; read it again") << shorten;
  }
}

TEST(JsonReader, AFileThatCannotBeReadIsSaidSo) {
  const auto dir = ftc::testing::fresh_dir("json-reader-refusals");
  const auto ignore = [](std::size_t, json&&) {};
  EXPECT_FALSE(json_io::parse_json_file(dir / "missing.json", "m", "scenarios", ignore));
  const auto e = failure_of([&] { json_io::parse_json_file(dir, "d", "scenarios", ignore); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->message, "is a directory, not a file to read");
  write(dir / "big.json", std::string(2 << 20, ' ') + "{}");
  const auto big = failure_of(
      [&] { json_io::parse_json_file(dir / "big.json", "b", "scenarios", ignore, 1 << 20); });
  ASSERT_TRUE(big);
  EXPECT_NE(big->message.find("is larger than 1 MiB"), std::string::npos) << big->message;
  // What the receiver throws passes through.
  write(dir / "one.json", R"({"scenarios": [{"a": 1}]})");
  EXPECT_THROW(json_io::parse_json_file(dir / "one.json", "o", "scenarios",
                                        [](std::size_t, json&&) { throw std::bad_alloc(); }),
               std::bad_alloc);
}

// Memory by design (issue 29): reading a file of many elements, handed over and dropped, takes
// hardly more memory than a file of few. Reading the text whole took the text and a document
// several times its size. Measured in a child process, by its peak resident set over its size
// when it began.
TEST(JsonReader, ReadingAStreamedArrayTakesMemoryThatDoesNotGrowWithItsLength) {
  if (const char* why = ftc::testing::why_no_peak()) GTEST_SKIP() << why;
  const auto dir = ftc::testing::fresh_dir("json-reader-memory");
  json item = {{"name", "member-0"},
               {"initial_state", {-0.7, -0.07, 1.5, 0.3, 1.3, -0.2}},
               {"faults", {{{"actuator", 1}, {"type", "bias"}, {"onset", 0.005}, {"offset", 5}}}}};
  const auto file_of = [&](int n) {
    const std::filesystem::path p = dir / ("items-" + std::to_string(n) + ".json");
    std::ofstream f(p);
    f << "{\"schema\": \"s\", \"scenarios\": [\n";
    for (int i = 0; i < n; ++i) f << (i ? ",\n" : "") << item.dump(2);
    f << "]}\n";
    return p;
  };
  const auto growth_kb = [](const std::filesystem::path& p, int n) {
    return ftc::testing::peak_growth_kb([&p, n] {
      std::size_t count = 0;
      const std::optional<json> doc = json_io::parse_json_file(
          p, p.string(), "scenarios", [&](std::size_t, json&& e) { count += e.size(); });
      return doc && count == 3u * static_cast<std::size_t>(n);
    });
  };
  const std::filesystem::path small_file = file_of(100), large_file = file_of(60000);
  ASSERT_GT(std::filesystem::file_size(large_file), 12u << 20);
  const long small = growth_kb(small_file, 100), large = growth_kb(large_file, 60000);
  ASSERT_GE(small, 0);
  ASSERT_GE(large, 0);
  // The text alone would add 13 MB; its document several times that.
  EXPECT_LT(large - small, 4 * 1024) << small << " kB against " << large << " kB";
}
