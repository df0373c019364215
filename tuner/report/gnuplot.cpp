#include "report/gnuplot.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include <string>
#include <vector>

#include "ftc/sim/controllers.hpp"
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
  const sim::ControllerInfo* c = sim::find_controller(type);
  const int base = c ? c->plot_style : 2;  // anything unknown as PI-FOSMC
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

namespace {

// The file a line `set output '...'` names (gp()'s quoting undone), or "" for any other line.
std::string output_of(const std::string& line) {
  static const std::string head = "set output '";
  if (line.rfind(head, 0) != 0 || line.size() < head.size() + 1 || line.back() != '\'') return "";
  std::string name;
  for (std::size_t i = head.size(); i + 1 < line.size(); ++i) {
    if (line[i] == '\'') {
      if (line[i + 1] != '\'') return "";
      ++i;
    }
    name += line[i];
  }
  return name;
}

}  // namespace

bool figure_is_whole(const fs::path& file) {
  const std::optional<std::string> text = read_file(file);
  if (!text || text->empty()) return false;
  const std::string& t = *text;
  const std::string ext = file.extension().string();
  if (ext == ".png") {
    // The last chunk: length 0, "IEND" and its CRC.
    static const std::string iend("\0\0\0\0IEND\xae\x42\x60\x82", 12);
    return t.size() >= 8 + iend.size() && t.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0 &&
           t.compare(t.size() - iend.size(), iend.size(), iend) == 0;
  }
  if (ext == ".svg") {
    const std::size_t last = t.find_last_not_of(" \t\r\n");
    return last != std::string::npos && last + 1 >= 6 && t.compare(last + 1 - 6, 6, "</svg>") == 0;
  }
  if (ext == ".pdf") return t.rfind("%%EOF") != std::string::npos && t.size() - t.rfind("%%EOF") < 64;
  return true;
}

void run_gnuplot(const fs::path& dir_in, const std::string& script_name) {
  // Absolute: the file actions below run after the chdir.
  const fs::path dir = fs::absolute(dir_in);
  const std::string pid = std::to_string(::getpid());
  // gnuplot writes each figure under a temporary name beside it, and each takes its place only
  // once gnuplot has succeeded and the figure is whole (gnuplot exits 0 on a full disk): a figure
  // is the old one or the whole new one, never a truncated one. The script as written stays the
  // one a user re-runs; gnuplot runs a copy with the temporary names.
  const std::optional<std::string> script = read_file(dir / script_name);
  if (!script) throw OutputError("cannot read the gnuplot script " + (dir / script_name).string());
  std::vector<std::pair<fs::path, fs::path>> outputs;  // temporary, final
  std::string rewritten;
  std::size_t from = 0;
  while (from < script->size()) {
    std::size_t nl = script->find('\n', from);
    if (nl == std::string::npos) nl = script->size();
    const std::string line = script->substr(from, nl - from);
    const std::string file = output_of(line);
    if (file.empty()) {
      rewritten += line;
    } else {
      const fs::path target = dir / file;
      refuse_non_regular_target(target);  // before gnuplot's work
      // Beside it, with its extension (which tells figure_is_whole the format).
      const fs::path f(file);
      const std::string temp =
          (f.parent_path() / (f.stem().string() + ".partial-" + pid + f.extension().string()))
              .string();
      outputs.emplace_back(dir / temp, target);
      rewritten += "set output " + plot::gp(temp);
    }
    rewritten += '\n';
    from = nl + 1;
  }
  const std::string run_script = script_name + ".run-" + pid;
  const auto discard = [&] {
    std::error_code ec;
    for (const auto& [temp, target] : outputs) fs::remove(temp, ec);
    fs::remove(dir / run_script, ec);
  };
  write_file_atomic(dir / run_script, rewritten);

  const std::string log = (dir / (script_name + ".log")).string();
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addchdir_np(&fa, dir.c_str());
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  std::string prog = "gnuplot", script_arg = run_script;
  char* argv[] = {prog.data(), script_arg.data(), nullptr};
  pid_t child = 0;
  const int rc = posix_spawnp(&child, "gnuplot", &fa, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    discard();
    throw OutputError(std::string("cannot run gnuplot: ") + std::strerror(rc) +
                      " (it comes with the Debian package gnuplot-nox, which tools/bootstrap "
                      "installs)");
  }
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    discard();
    std::string why = read_file(log).value_or("");
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    throw OutputError("gnuplot failed on " + (dir / script_name).string() + " (" +
                      (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                         : std::string("killed by a signal")) +
                      "), no figure written" + (why.empty() ? "" : ": " + why));
  }
  for (const auto& [temp, target] : outputs)
    if (!figure_is_whole(temp)) {
      discard();
      throw OutputError("gnuplot left " + target.string() +
                        " incomplete (a full disk?); no figure written");
    }
  try {
    for (std::size_t i = 0; i < outputs.size(); ++i) {
      commit_file(outputs[i].first, outputs[i].second);
      outputs[i].first.clear();
    }
  } catch (...) {
    discard();
    throw;
  }
  std::error_code ec;
  fs::remove(dir / run_script, ec);
  fs::remove(log, ec);
}

}  // namespace ftc::tune
