#pragma once
// A one-line progress bar on stderr, drawn only when stderr is a terminal. Log lines printed
// through spdlog clear it first (clear()), then draw() puts it back.
#include <cstdint>

namespace ftc::cli {

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled);
  ~ProgressBar();
  void draw(std::int64_t done, std::int64_t total, double elapsed_s);
  void clear();

 private:
  bool enabled_;
  bool shown_ = false;
};

}  // namespace ftc::cli
