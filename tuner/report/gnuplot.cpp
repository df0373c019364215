#include "report/gnuplot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "ftc/tune/io/files.hpp"
#include "io/text.hpp"

namespace ftc::tune {
namespace plot {

// A string literal for gnuplot (single quotes; a quote inside is doubled).
std::string gp(const std::string& s) {
  std::string o = "'";
  for (char c : s) o += c == '\'' ? std::string("''") : std::string(1, c);
  return o + "'";
}

std::string terminal(FigureFormat f, int width, int height) {
  char buf[160];
  if (f == FigureFormat::png)
    std::snprintf(
        buf, sizeof buf,
        "set terminal pngcairo size %d,%d enhanced font 'DejaVu Sans,11' background rgb 'white'\n",
        width, height);
  else
    std::snprintf(
        buf, sizeof buf,
        "set terminal svg size %d,%d enhanced font 'DejaVu Sans,11' background rgb 'white'\n",
        width, height);
  return buf;
}

const char* extension(FigureFormat f) { return f == FigureFormat::png ? ".png" : ".svg"; }

// Colour-bar tics for a log scale: gnuplot draws none when the range is under a decade, which
// is common for objectives that barely change, so place six at even log spacing.
std::string colour_tics(double lo, double hi, const std::string& lo_label) {
  if (!(lo > 0) || !(hi > lo) || !std::isfinite(hi)) return "";
  std::string s = "set cbrange [" + detail::format_number(lo, "%.9g") + ":" +
                  detail::format_number(hi, "%.9g") + "]\nset cbtics (";
  // Round values inside the range: 1, 2 and 5 per decade, fewer when they would crowd.
  const int k0 = static_cast<int>(std::floor(std::log10(lo))),
            k1 = static_cast<int>(std::ceil(std::log10(hi)));
  const int decades = k1 - k0;
  std::vector<double> mantissas = decades <= 2   ? std::vector<double>{1, 2, 5}
                                  : decades <= 4 ? std::vector<double>{1, 3}
                                                 : std::vector<double>{1};
  const int every = decades > 8 ? (decades + 7) / 8 : 1;  // at most about 8 decades labelled
  std::vector<double> tics;
  for (int k = k0; k <= k1; ++k)
    if ((k - k0) % every == 0)
      for (double m : mantissas) {
        const double v = m * std::pow(10.0, k);
        // Rounded to its own digit, so that the label is exactly the round value.
        const double r = std::stod(detail::format_number(v, "%.1g"));
        // Not crowding the label of lo.
        const double from = lo_label.empty() ? lo * (1 - 1e-9) : lo * 1.8;
        if (r >= from && r <= hi * (1 + 1e-9)) tics.push_back(r);
      }
  bool first = true;
  if (!lo_label.empty()) {
    s += "'" + lo_label + "' " + detail::format_number(lo, "%.9g");
    first = false;
  }
  for (double v : tics) {
    s += (first ? "" : ", ") + std::string("'") + detail::format_number(v, "%g") + "' " +
         detail::format_number(v, "%.9g");
    first = false;
  }
  return s + ")\n";
}

// Vertical dashed lines at the fault onsets, optionally labelled.
std::string onset_marks(const std::vector<double>& onsets, bool labels) {
  std::string s = "unset arrow; unset label\n";
  for (std::size_t i = 0; i < onsets.size(); ++i) {
    char buf[256];
    std::snprintf(
        buf, sizeof buf,
        "set arrow from %.9g, graph 0 to %.9g, graph 1 nohead dt 2 lw 1.2 lc rgb 'gray40' front\n",
        onsets[i], onsets[i]);
    s += buf;
    if (labels) {
      std::snprintf(
          buf, sizeof buf,
          "set label 'fault %zu' at %.9g, graph 0.93 offset 0.5,0 textcolor rgb 'gray30' front\n",
          i + 1, onsets[i]);
      s += buf;
    }
  }
  return s;
}

namespace {
// viridis (matplotlib's default map) at five stops; between them, linear in sRGB.
constexpr unsigned char kViridis[5][3] = {{0x44, 0x01, 0x54},
                                          {0x3b, 0x52, 0x8b},
                                          {0x21, 0x91, 0x8c},
                                          {0x5e, 0xc9, 0x62},
                                          {0xfd, 0xe7, 0x25}};
// Dash types and filled markers, in the order series take them.
constexpr int kDashes[] = {1, 2, 4, 5, 3};
constexpr int kMarkers[] = {7, 5, 9, 13, 11, 3};
}  // namespace

std::string viridis(double t) {
  t = std::clamp(t, 0.0, 1.0) * 4;
  const int i = std::min(3, static_cast<int>(t));
  const double f = t - i;
  char buf[8];
  int rgb[3];
  for (int c = 0; c < 3; ++c)
    rgb[c] =
        static_cast<int>(std::lround(kViridis[i][c] + f * (kViridis[i + 1][c] - kViridis[i][c])));
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", rgb[0], rgb[1], rgb[2]);
  return buf;
}

std::string palette() {
  std::string s = "set palette defined (";
  for (int i = 0; i < 5; ++i)
    s += (i ? ", " : "") + detail::format_number(i / 4.0, "%g") + " '" + viridis(i / 4.0) + "'";
  return s + ")\n";
}

std::string line_styles(int count) {
  std::string s;
  for (int i = 0; i < count; ++i) {
    // From the dark end to 0.85: the yellow end vanishes on white paper.
    const double t = count > 1 ? 0.85 * i / (count - 1) : 0.0;
    char buf[160];
    std::snprintf(buf, sizeof buf, "set style line %d lc rgb '%s' dt %d pt %d lw 1.6 ps 0.9\n",
                  i + 1, viridis(t).c_str(), kDashes[i % 5], kMarkers[i % 6]);
    s += buf;
  }
  return s;
}

int controller_style(const std::string& type, bool tuned, int repeat) {
  if (tuned) return 1;
  int base = 2;  // pi_fosmc and anything unknown
  if (type == "fosmc")
    base = 3;
  else if (type == "nftsmc")
    base = 4;
  else if (type == "adaptive_neural_pi_fosmc")
    base = 5;
  return repeat == 0 ? base : std::min(kControllerStyles, base + 5);
}

std::string controller_styles() {
  // Colour (viridis, darkest for the tuned), dash and marker per type; 6..10 repeat 1..5's colour
  // with another dash and an open marker.
  static const double kShade[5] = {0.0, 0.25, 0.47, 0.68, 0.85};
  static const int kDash[5] = {1, 2, 4, 5, 3};
  static const int kMark[5] = {7, 5, 9, 13, 11};
  std::string s;
  for (int i = 0; i < kControllerStyles; ++i) {
    const int k = i % 5;
    char buf[160];
    std::snprintf(buf, sizeof buf, "set style line %d lc rgb '%s' dt %d pt %d lw %s ps 0.9\n",
                  i + 1, viridis(kShade[k]).c_str(), i < 5 ? kDash[k] : kDash[(k + 2) % 5],
                  i < 5 ? kMark[k] : kMark[k] - 1, i == 0 ? "1.3" : "1.6");
    s += buf;
  }
  return s;
}

std::vector<int> controller_style_list(const std::vector<Series>& series) {
  std::vector<int> out;
  for (std::size_t i = 0; i < series.size(); ++i) {
    int repeat = 0;
    for (std::size_t j = 0; j < i; ++j)
      repeat += !series[j].tuned && !series[i].tuned && series[j].type == series[i].type;
    out.push_back(controller_style(series[i].type, series[i].tuned, repeat));
  }
  return out;
}

std::string styles(int count) {
  return "set datafile separator ','\n" + line_styles(count) +
         "set grid lc rgb '#dddddd'\nset key outside right top vertical box opaque\n";
}

}  // namespace plot

namespace fs = std::filesystem;

void run_gnuplot(const fs::path& dir_in, const std::string& script_name) {
  // Absolute: the file actions below run after the chdir.
  const fs::path dir = fs::absolute(dir_in);
  const std::string log = (dir / (script_name + ".log")).string();
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  std::string prog = "gnuplot", script = script_name;
  char* argv[] = {prog.data(), script.data(), nullptr};
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, "gnuplot", &fa, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0)
    throw std::runtime_error(
        std::string("cannot run gnuplot: ") + std::strerror(rc) +
        " (it comes with the Debian package gnuplot-nox, which tools/bootstrap installs)");
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error("gnuplot failed on " + (dir / script_name).string() + ": " +
                             read_file(log).value_or(""));
  fs::remove(log);
}

}  // namespace ftc::tune
