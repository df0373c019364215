#include "ftc/runtime/json_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <istream>
#include <streambuf>
#include <sstream>

#include "ftc/sim/input_error.hpp"

namespace ftc::json_io {

namespace {

// A file descriptor closed when it goes.
struct Fd {
  int fd = -1;
  Fd() = default;
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

InputError too_big(const std::filesystem::path& path, std::uint64_t max_bytes) {
  return InputError(path.string(), "",
                    "is larger than " + std::to_string(max_bytes >> 20) +
                        " MiB, the most a file of its kind may hold");
}

// Opens `path` for reading: false when it cannot be opened. O_NONBLOCK: opening a FIFO does not
// wait for a writer. What is not a regular file (a directory, a FIFO, /dev/zero behind a link)
// is refused before a byte is read, and so is a file larger than max_bytes.
bool open_regular(const std::filesystem::path& path, std::uint64_t max_bytes, Fd& f) {
  f.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (f.fd < 0) return false;
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) return false;
  if (!S_ISREG(st.st_mode)) {
    const char* kind = S_ISDIR(st.st_mode)    ? "a directory"
                       : S_ISFIFO(st.st_mode) ? "a FIFO"
                       : S_ISCHR(st.st_mode)  ? "a character device"
                       : S_ISBLK(st.st_mode)  ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket"
                                              : "not a regular file";
    throw InputError(path.string(), "", std::string("is ") + kind + ", not a file to read");
  }
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes) throw too_big(path, max_bytes);
  return true;
}

// read(2) that retries on EINTR: the bytes read, 0 at the end, -1 on an error.
ssize_t read_some(int fd, char* buf, std::size_t n) {
  for (;;) {
    const ssize_t got = ::read(fd, buf, n);
    if (got >= 0 || errno != EINTR) return got;
  }
}

}  // namespace

std::optional<std::string> read_file(const std::filesystem::path& path, std::uint64_t max_bytes) {
  Fd f;
  if (!open_regular(path, max_bytes, f)) return std::nullopt;
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) return std::nullopt;
  std::string text;
  text.reserve(static_cast<std::size_t>(st.st_size));
  char buf[65536];
  for (;;) {
    const ssize_t n = read_some(f.fd, buf, sizeof buf);
    if (n < 0) return std::nullopt;
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) throw too_big(path, max_bytes);  // it grew while read
  }
  return text;
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
    // Edits of one character (insert, delete, replace) or a swap of two neighbours ("onest" is
    // one slip from "onset"): the optimal string alignment distance, three rows kept.
    std::vector<std::size_t> before(b.size() + 1), prev(b.size() + 1), row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        row[j] =
            std::min({prev[j] + 1, row[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
        if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
          row[j] = std::min(row[j], before[j - 2] + 1);
      }
      before.swap(prev);  // before = the row of i - 1
      prev.swap(row);     // prev = the row of i
    }
    // Short names need a closer match: "c1" is one edit from "c2" and means something else.
    const std::size_t d = prev[b.size()];
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

namespace {

// Length of the UTF-8 sequence starting at text[i], or 0 when it is not well formed (overlong
// forms, surrogates and code points above U+10FFFF included).
std::size_t utf8_sequence(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b = byte(i);
  if (b < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the valid range of the second byte
  if (b >= 0xC2 && b <= 0xDF) {
    n = 2;
  } else if (b >= 0xE0 && b <= 0xEF) {
    n = 3;
    if (b == 0xE0) lo = 0xA0;
    if (b == 0xED) hi = 0x9F;
  } else if (b >= 0xF0 && b <= 0xF4) {
    n = 4;
    if (b == 0xF0) lo = 0x90;
    if (b == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + n > text.size() || byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}

// "line L, column C" of a byte offset (both from 1; the column counts bytes).
std::string line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  const std::size_t line =
      1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + offset, '\n'));
  const std::size_t nl = text.rfind('\n', offset == 0 ? 0 : offset - 1);
  const std::size_t column =
      nl == std::string_view::npos || nl >= offset ? offset + 1 : offset - nl;
  return std::string("line ")
      .append(std::to_string(line))
      .append(", column ")
      .append(std::to_string(column));
}

// Deeper nesting than any ftctune file has; the limit keeps recursive code that later walks the
// document (copies, dumps) off the end of the stack.
constexpr std::size_t kMaxDepth = 256;

// Builds the document like json::parse, but tracks the JSON path of the value being read, so an
// error (a number out of range, a duplicate key) names it, and stops at the first problem
// instead of throwing library exceptions. When given a key and a receiver, the elements of the
// root object's array under that key are handed over one by one as each is complete, and not
// kept: the document then holds that array empty.
class StrictReader : public json::json_sax_t {
 public:
  using Locate = std::function<std::string(std::size_t)>;  // "line L, column C" of an offset
  using Element = std::function<void(std::size_t, json&&)>;

  StrictReader(json& root, Locate locate, std::string streamed_key = {}, Element element = {})
      : root_(root),
        locate_(std::move(locate)),
        streamed_key_(std::move(streamed_key)),
        element_(std::move(element)) {}

  const std::optional<FieldError>& error() const { return error_; }

  bool null() override { return scalar(nullptr); }
  bool boolean(bool v) override { return scalar(v); }
  bool number_integer(number_integer_t v) override { return scalar(v); }
  bool number_unsigned(number_unsigned_t v) override { return scalar(v); }
  bool number_float(number_float_t v, const string_t&) override { return scalar(v); }
  bool string(string_t& v) override { return scalar(std::move(v)); }
  bool binary(binary_t& v) override { return scalar(std::move(v)); }
  bool start_object(std::size_t) override { return open(json::object()); }
  bool start_array(std::size_t) override { return open(json::array()); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }

  bool key(string_t& k) override {
    Frame& f = frames_.back();
    f.key = std::move(k);
    if (f.value->contains(f.key)) {
      // Which of two values a reader takes differs between JSON libraries (RFC 8259, 4).
      error_ = FieldError{path(), "duplicate key (a key may appear only once in an object)"};
      return false;
    }
    return true;
  }

  bool parse_error(std::size_t position, const std::string& token,
                   const json::exception& e) override {
    if (e.id == 406) {  // a number beyond the range of a double
      const std::size_t start = position >= token.size() ? position - token.size() : position;
      error_ = FieldError{path(), std::string("invalid JSON: number ")
                                      .append(token)
                                      .append(" is out of the range of a double, at ")
                                      .append(locate_(start))};
      return false;
    }
    std::string msg = e.what();  // drop the "[json.exception.parse_error.101] " prefix
    if (auto p = msg.find("] "); msg.rfind("[json.exception", 0) == 0 && p != std::string::npos)
      msg = msg.substr(p + 2);
    error_ = FieldError{"", "invalid JSON: " + msg};
    return false;
  }

 private:
  struct Frame {
    json* value;
    std::string key;        // objects: the key being read
    std::size_t count = 0;  // arrays: the elements begun so far (handed-over ones included)
    bool streamed = false;  // the array whose elements are handed over
  };

  // The JSON pointer of the value being read: an array's last element while it is open, the
  // next one otherwise.
  std::string path() const {
    std::string p;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      if (f.value->is_object()) {
        p.append("/").append(pointer_escape(f.key));
      } else {
        const std::size_t n = f.count;
        p.append("/").append(std::to_string(i + 1 < frames_.size() && n > 0 ? n - 1 : n));
      }
    }
    return p;
  }

  template <class V>
  json* put(V&& v) {
    if (frames_.empty()) {
      root_ = json(std::forward<V>(v));
      return &root_;
    }
    Frame& f = frames_.back();
    json& parent = *f.value;
    if (parent.is_array()) {
      ++f.count;
      parent.push_back(json(std::forward<V>(v)));
      return &parent.back();
    }
    json& slot = parent[f.key];
    slot = json(std::forward<V>(v));
    return &slot;
  }

  template <class V>
  bool scalar(V&& v) {
    put(std::forward<V>(v));
    hand_over();
    return true;
  }

  // Hands over a complete element of the streamed array, if the value just completed is one.
  void hand_over() {
    if (frames_.empty() || !frames_.back().streamed) return;
    Frame& f = frames_.back();
    json item = std::move(f.value->back());
    f.value->erase(f.value->size() - 1);
    element_(f.count - 1, std::move(item));
  }

  bool open(json&& empty) {
    if (frames_.size() >= kMaxDepth) {
      error_ = FieldError{
          path(),
          std::string("nested deeper than ").append(std::to_string(kMaxDepth)).append(" levels")};
      return false;
    }
    const bool streamed = element_ && empty.is_array() && frames_.size() == 1 &&
                          frames_[0].value->is_object() && frames_[0].key == streamed_key_;
    json* v = put(std::move(empty));
    frames_.push_back({v, {}, 0, streamed});
    return true;
  }

  bool close() {
    frames_.pop_back();
    hand_over();
    return true;
  }

  json& root_;
  Locate locate_;
  std::string streamed_key_;
  Element element_;
  std::vector<Frame> frames_;
  std::optional<FieldError> error_;
};

// Checks bytes for UTF-8 as they come, buffer by buffer: a sequence cut by a buffer's end is
// judged with the next buffer's bytes.
class Utf8Check {
 public:
  // The offset (from the first byte fed) of the first byte that is not well-formed UTF-8 among
  // `n` more bytes, nullopt while all are; `end` says no byte follows them.
  std::optional<std::uint64_t> feed(const char* p, std::size_t n, bool end) {
    std::size_t i = 0;
    if (carried_ > 0) {  // complete the cut sequence with the first new bytes
      const std::size_t take = std::min(n, sizeof head_ - carried_);
      std::memcpy(head_ + carried_, p, take);
      const std::size_t have = carried_ + take;
      const std::size_t len = utf8_sequence(std::string_view(head_, have), 0);
      if (len == 0) {
        if (!end && have < 4 && take == n) {  // still cut short: wait for more
          carried_ = have;
          return std::nullopt;
        }
        return at_;
      }
      i = len - carried_;  // the new bytes it used
      at_ += carried_;
      carried_ = 0;
    }
    const std::string_view chunk(p, n);
    while (i < n) {
      const std::size_t len = utf8_sequence(chunk, i);
      if (len == 0) {
        if (!end && n - i < 4) {  // perhaps cut short: judged with the next bytes
          carried_ = n - i;
          std::memcpy(head_, p + i, carried_);
          at_ += i;
          return std::nullopt;
        }
        return at_ + i;
      }
      i += len;
    }
    at_ += n;
    return std::nullopt;
  }

 private:
  char head_[8] = {};
  std::size_t carried_ = 0;  // the first bytes of a cut sequence, in head_
  std::uint64_t at_ = 0;     // the offset of head_[0] while carrying, else of the next buffer
};

// Reads a file through a buffer of its own, stopping after `limit` bytes (what a first pass
// counted), so the parser sees no more bytes than that pass checked. The bytes are checked for
// UTF-8 again as they are read: a file that got shorter, or whose bytes are no longer UTF-8, is
// noticed, not parsed (one rewritten into other valid text is read as it then is).
class FdBuf : public std::streambuf {
 public:
  FdBuf(int fd, std::uint64_t limit) : fd_(fd), left_(limit) {}
  bool failed() const { return failed_; }    // a read failed
  bool changed() const { return changed_; }  // bytes the first pass did not see

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    if (left_ == 0 || failed_ || changed_) return traits_type::eof();
    const std::size_t want =
        static_cast<std::size_t>(std::min<std::uint64_t>(sizeof buf_, left_));
    const ssize_t n = read_some(fd_, buf_, want);
    if (n <= 0) {  // an error, or the file got shorter
      (n < 0 ? failed_ : changed_) = true;
      return traits_type::eof();
    }
    left_ -= static_cast<std::uint64_t>(n);
    if (utf8_.feed(buf_, static_cast<std::size_t>(n), left_ == 0)) {
      changed_ = true;
      return traits_type::eof();
    }
    setg(buf_, buf_, buf_ + n);
    return traits_type::to_int_type(*gptr());
  }

 private:
  int fd_;
  std::uint64_t left_;
  bool failed_ = false, changed_ = false;
  Utf8Check utf8_;
  char buf_[65536];
};

// "line L, column C" of a byte offset in the first `size` bytes of a file, as line_column gives
// it for text.
std::string file_line_column(int fd, std::uint64_t offset, std::uint64_t size) {
  offset = std::min(offset, size);
  std::uint64_t line = 1, last_newline_end = 0, at = 0;  // the offset after the last '\n'
  char buf[65536];
  while (at < offset) {
    const std::size_t want =
        static_cast<std::size_t>(std::min<std::uint64_t>(sizeof buf, offset - at));
    const ssize_t n = ::pread(fd, buf, want, static_cast<off_t>(at));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    for (ssize_t i = 0; i < n; ++i)
      if (buf[i] == '\n') {
        ++line;
        last_newline_end = at + static_cast<std::uint64_t>(i) + 1;
      }
    at += static_cast<std::uint64_t>(n);
  }
  offset = std::min(offset, at);
  return std::string("line ")
      .append(std::to_string(line))
      .append(", column ")
      .append(std::to_string(offset - last_newline_end + 1));
}

std::string not_utf8_message(unsigned char b, const std::string& where) {
  char byte[8];
  std::snprintf(byte, sizeof byte, "0x%02X", b);
  return std::string("invalid JSON: not UTF-8 (byte ")
      .append(byte)
      .append(" at ")
      .append(where)
      .append(")");
}

}  // namespace

std::optional<std::size_t> invalid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_sequence(text, i);
    if (n == 0) return i;
    i += n;
  }
  return std::nullopt;
}

std::string printable(std::string_view text) {
  std::string s;
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_sequence(text, i);
    if (n == 0) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", static_cast<unsigned char>(text[i]));
      s += buf;
      ++i;
    } else {
      s.append(text.substr(i, n));
      i += n;
    }
  }
  return s;
}

json parse_json_text(const std::string& text, const std::string& source) {
  // JSON text is UTF-8 (RFC 8259, 8.1). Checked first, so that no message below quotes a broken
  // byte (a service would fail to encode its error response).
  if (const auto bad = invalid_utf8(text))
    throw InputError(source, "",
                     not_utf8_message(static_cast<unsigned char>(text[*bad]),
                                      line_column(text, *bad)));
  json doc;
  StrictReader reader(doc, [&text](std::size_t at) { return line_column(text, at); });
  if (!json::sax_parse(text, &reader)) {
    if (!reader.error()) throw InputError(source, "", "invalid JSON");
    const FieldError& e = *reader.error();
    throw InputError(source, e.path, printable(e.message));
  }
  return doc;
}

std::optional<json> parse_json_file(const std::filesystem::path& path, const std::string& source,
                                    const std::string& streamed_key,
                                    const std::function<void(std::size_t, json&&)>& element,
                                    std::uint64_t max_bytes) {
  Fd f;
  if (!open_regular(path, max_bytes, f)) return std::nullopt;
  // First pass: the bytes are UTF-8 (as parse_json_text checks the text), and how many there
  // are.
  std::uint64_t total = 0;
  {
    char buf[65536];
    Utf8Check utf8;
    for (;;) {
      const ssize_t n = read_some(f.fd, buf, sizeof buf);
      if (n < 0) return std::nullopt;
      if (const auto bad = utf8.feed(buf, static_cast<std::size_t>(n), n == 0)) {
        unsigned char b = 0;
        if (::pread(f.fd, &b, 1, static_cast<off_t>(*bad)) != 1) return std::nullopt;
        throw InputError(source, "",
                         not_utf8_message(b, file_line_column(f.fd, *bad, total + n)));
      }
      if (n == 0) break;
      total += static_cast<std::uint64_t>(n);
      if (total > max_bytes) throw too_big(path, max_bytes);  // it grew while read
    }
  }
  if (::lseek(f.fd, 0, SEEK_SET) != 0) return std::nullopt;
  FdBuf buf(f.fd, total);
  std::istream in(&buf);
  json doc;
  const int fd = f.fd;
  StrictReader reader(
      doc, [fd, total](std::size_t at) { return file_line_column(fd, at, total); }, streamed_key,
      element);
  const bool parsed = json::sax_parse(in, &reader);
  if (buf.failed()) return std::nullopt;
  if (buf.changed()) throw InputError(source, "", "changed while it was read; read it again");
  if (!parsed) {
    if (!reader.error()) throw InputError(source, "", "invalid JSON");
    const FieldError& e = *reader.error();
    throw InputError(source, e.path, printable(e.message));
  }
  return doc;
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
