#include "ftc/tune/report/report.hpp"

#include <fcntl.h>
#include <openssl/evp.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "ftc/tune/io/files.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "io/text.hpp"

extern char** environ;

namespace ftc::tune {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string read_required(const fs::path& dir, const std::string& name) {
  const fs::path p = dir / name;
  std::optional<std::string> text;
  if (fs::is_regular_file(p)) text = read_file(p);
  if (!text)
    throw InputError(dir.string(), "",
                     "missing " + name + ": not the output directory of `ftctune run`");
  return *text;
}

// A figure gnuplot has just drawn.
std::string figure_bytes(const fs::path& file) {
  std::optional<std::string> bytes = read_file(file);
  if (!bytes) throw std::runtime_error("gnuplot did not write " + file.string());
  return *bytes;
}

json read_json(const fs::path& dir, const std::string& name) {
  json j = json::parse(read_required(dir, name), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw InputError((dir / name).string(), "", "is not a JSON object (damaged output?)");
  return j;
}

std::string base64(const std::string& data) {
  std::string out(4 * ((data.size() + 2) / 3) + 1, '\0');
  const int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                reinterpret_cast<const unsigned char*>(data.data()),
                                static_cast<int>(data.size()));
  out.resize(static_cast<std::size_t>(n));
  return out;
}

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

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
std::string colour_tics(double lo, double hi) {
  if (!(lo > 0) || !(hi > lo) || !std::isfinite(hi)) return "";
  std::string s = "set cbrange [" + detail::format_number(lo, "%.9g") + ":" +
                  detail::format_number(hi, "%.9g") + "]\nset cbtics (";
  for (int i = 0; i <= 5; ++i) {
    const double v = lo * std::pow(hi / lo, i / 5.0);
    s += (i ? ", " : "") + std::string("'") + detail::format_number(v, "%.5g") + "' " +
         detail::format_number(v, "%.9g");
  }
  return s + ")\n";
}

// How the convergence figure names the run's optimiser.
std::string optimizer_label(const json& optimizer) {
  const std::string type = optimizer.value("type", "bat");
  if (type == "random") return "random search";
  if (type == "pagmo") return "pagmo " + optimizer.value("name", std::string("?"));
  return "Bat algorithm";
}

struct Series {
  std::string label;
  std::string file;  // relative to the run directory
};

// Vertical dashed lines at the fault onsets, optionally labelled.
std::string onset_marks(const std::vector<double>& onsets, bool labels = true) {
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

std::string series_plot(const std::vector<Series>& series, const std::string& using_expr,
                        bool titles) {
  std::string s = "plot ";
  for (std::size_t i = 0; i < series.size(); ++i) {
    if (i) s += ", \\\n     ";
    s += gp(series[i].file) + " skip 1 using " + using_expr + " with lines ls " +
         std::to_string(i + 1) + " lw 1.4" +
         (titles ? " title " + gp(series[i].label) : " notitle");
  }
  return s + "\n";
}

const char* kStyles =
    "set datafile separator ','\n"
    "set style line 1 lc rgb '#d62728'\n"
    "set style line 2 lc rgb '#1f77b4'\n"
    "set style line 3 lc rgb '#2ca02c'\n"
    "set style line 4 lc rgb '#9467bd'\n"
    "set style line 5 lc rgb '#ff7f0e'\n"
    "set style line 6 lc rgb '#8c564b'\n"
    "set grid lc rgb '#dddddd'\n"
    "set key outside right top vertical box opaque\n";

}  // namespace

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

ReportResult render_report(const fs::path& run_dir, const ReportOptions& options) {
  if (!fs::is_directory(run_dir)) throw InputError(run_dir.string(), "", "is not a directory");
  const json gains = read_json(run_dir, "gains.json");
  const json comparison = read_json(run_dir, "comparison.json");
  const std::string job_text = read_required(run_dir, "job.json");
  const Job job = parse_job_text(job_text, (run_dir / "job.json").string());
  read_required(run_dir, "history.csv");
  const json run =
      fs::is_regular_file(run_dir / "run.json") ? read_json(run_dir, "run.json") : json::object();

  // Per scenario, the compared controllers' trajectory files.
  if (!comparison.contains("controllers") || !comparison["controllers"].is_array() ||
      comparison["controllers"].empty())
    throw InputError((run_dir / "comparison.json").string(), "/controllers",
                     "lists no controllers");
  const std::size_t S = job.scenarios.size();
  std::vector<std::vector<Series>> series(S);
  for (const json& c : comparison["controllers"]) {
    const json& sc = c.value("scenarios", json::array());
    for (std::size_t s = 0; s < S && s < sc.size(); ++s) {
      if (!sc[s].contains("trajectory"))
        throw InputError((run_dir / "comparison.json").string(), "",
                         "has no trajectories: re-run `ftctune run`");
      const std::string file = sc[s]["trajectory"];
      if (!fs::is_regular_file(run_dir / file))
        throw InputError(run_dir.string(), "", "missing " + file);
      series[s].push_back({c.value("label", "?"), file});
    }
  }

  // The page embeds PNGs: a fifth of the size of SVGs that carry every sample.
  const FigureFormat fmt_fig = options.html ? FigureFormat::png : options.format;
  const std::string ext = extension(fmt_fig);
  fs::create_directories(run_dir / "figures");
  std::ostringstream gpfile;
  gpfile << kStyles;
  ReportResult result;
  struct Figure {
    std::string file, title, caption;
  };
  std::vector<Figure> figures;

  const sim::Scenario& sc0 = job.scenarios.front();
  std::vector<double> onsets;
  for (const sim::Fault& f : sc0.faults)
    if (f.onset < sc0.duration) onsets.push_back(f.onset);
  std::sort(onsets.begin(), onsets.end());
  onsets.erase(std::unique(onsets.begin(), onsets.end()), onsets.end());
  const std::string scen = S > 1 ? " (scenario " + sc0.name + ")" : "";

  // Figures 3 and 4: states in three stacked panels.
  const auto states = [&](const std::string& name, int first_col, const char* const* ylabels,
                          const std::string& title, const std::string& caption) {
    const std::string file = "figures/" + name + ext;
    // Fixed margins keep the three panels aligned although only the first carries the key.
    gpfile << terminal(fmt_fig, 1100, 950) << "set output " << gp(file) << "\n"
           << "set multiplot layout 3,1 title " << gp(title + scen) << " font ',13'\n"
           << "set lmargin at screen 0.09\nset rmargin at screen 0.78\n"
           << onset_marks(onsets) << "set xrange [0:" << sc0.duration << "]\n";
    for (int i = 0; i < 3; ++i) {
      gpfile << "set ylabel " << gp(ylabels[i]) << "\n";
      gpfile << (i == 2 ? "set xlabel 'time [s]'\n" : "unset xlabel\n");
      gpfile << (i == 0 ? "set key outside right top vertical box opaque\n" : "unset key\n");
      gpfile << series_plot(series[0], "1:" + std::to_string(first_col + i), i == 0);
    }
    gpfile << "unset multiplot\nunset xrange\nunset xlabel\nunset lmargin\nunset rmargin\n"
           << "set key outside right top vertical box opaque\n";
    figures.push_back({file, title, caption});
  };
  const char* attitude[] = {"roll x_1 [rad]", "pitch x_2 [rad]", "yaw x_3 [rad]"};
  const char* rates[] = {"x_4 [rad/s]", "x_5 [rad/s]", "x_6 [rad/s]"};
  states("fig3-attitude", 2, attitude, "Attitude angles under actuator faults (paper Fig. 3)",
         "Euler angles of every compared controller; dashed lines mark the fault onsets.");
  states("fig4-rates", 5, rates, "Angular rates under actuator faults (paper Fig. 4)",
         "Rates of the Euler angles of every compared controller.");

  // Figure 5: convergence.
  {
    const std::string file = "figures/fig5-fitness" + ext;
    gpfile << terminal(fmt_fig, 1000, 600) << "set output " << gp(file) << "\n"
           << "unset arrow; unset label\nset title 'Best fitness per iteration (paper Fig. 5)' "
              "font ',13'\n"
           << "set xlabel 'iteration'\nset ylabel 'best fitness J = 1/objective'\nset format y "
              "'%.6g'\n"
           << "set key inside right bottom\n"
           << "plot 'history.csv' skip 1 using 1:2 with linespoints ls 2 lw 2 pt 7 title "
           << gp(optimizer_label(gains["optimizer"]));
    if (fs::is_regular_file(run_dir / "history-random.csv"))
      gpfile << ", \\\n     'history-random.csv' skip 1 using 1:2 with linespoints ls 5 lw 2 pt 5 "
                "title 'random search, same budget'";
    gpfile << "\nset format y\nunset title\nset key outside right top vertical box opaque\n";
    figures.push_back({file, "Convergence",
                       "Best fitness found after each iteration (iteration 0 "
                       "is the initial population)."});
  }

  // Figure 6: commanded (and, on faulted actuators, applied) outputs per controller.
  {
    const std::string file = "figures/fig6-inputs" + ext;
    const std::size_t n = series[0].size();
    const std::size_t rows = (n + 1) / 2;
    std::set<int> faulted;
    for (const sim::Fault& f : sc0.faults) faulted.insert(f.actuator);
    gpfile << terminal(fmt_fig, 1200, static_cast<int>(430 * rows + 60)) << "set output "
           << gp(file) << "\nset multiplot layout " << rows << ",2 title "
           << gp("Actuator outputs (paper Fig. 6)" + scen) << " font ',13'\n"
           << onset_marks(onsets, false) << "set xrange [0:" << sc0.duration
           << "]\nset xlabel 'time [s]'\n"
           << "set ylabel 'actuator output u'\nset key below horizontal font ',9' maxrows 2\nset "
              "bmargin 7\n";
    for (std::size_t c = 0; c < n; ++c) {
      gpfile << "set title " << gp(series[0][c].label) << "\nplot ";
      for (int j = 1; j <= 4; ++j)
        gpfile << (j > 1 ? ", " : "") << gp(series[0][c].file) << " skip 1 using 1:" << 7 + j
               << " with lines ls " << j << " lw 1.1 title 'u_{d" << j << "}'";
      for (int j : faulted)
        gpfile << ", " << gp(series[0][c].file) << " skip 1 using 1:" << 11 + j << " with lines ls "
               << j << " lw 2 dt 2 title 'applied u_" << j << "'";
      gpfile << "\n";
    }
    gpfile << "unset multiplot\nunset title\nunset xrange\nunset bmargin\nset key outside right "
              "top vertical box opaque\n";
    figures.push_back(
        {file, "Actuator outputs",
         "Commanded outputs u_d of each controller (solid) and, dashed in the same colour, "
         "the applied output of each faulted actuator (bias added, effectiveness lost). "
         "Fault onsets are the grey dashed lines."});
  }

  // Figure 7: the faulted part, where the controllers differ, on a log scale.
  if (!onsets.empty()) {
    const std::string file = "figures/fig7-fault-zoom" + ext;
    const double t0 = std::max(0.0, onsets.front() - 1.0);
    gpfile << terminal(fmt_fig, 1100, 600) << "set output " << gp(file) << "\n"
           << onset_marks(onsets) << "set title " << gp("Attitude error after the faults" + scen)
           << " font ',13'\nset logscale y\nset format y '10^{%L}'\nset xrange [" << t0 << ":"
           << sc0.duration << "]\nset xlabel 'time [s]'\nset ylabel '‖X_1‖ [rad]'\n"
           << series_plot(series[0], "1:(sqrt($2**2 + $3**2 + $4**2))", true)
           << "unset logscale y\nset format y\nunset xrange\nunset title\n";
    figures.push_back({file, "Zoom on the faulted part",
                       "Norm of the attitude error from one second before the first fault on, log "
                       "scale: the part of the run the paper's fault-tolerance claims are about."});
  }

  write_file_atomic(run_dir / "figures" / "report.gp", gpfile.str());
  run_gnuplot(run_dir, "figures/report.gp");
  for (const Figure& f : figures) result.figures.push_back(run_dir / f.file);

  if (!options.html) return result;

  // report.html: figures inline, so the one file can be attached to a design review.
  std::ostringstream h;
  const std::string title = "ftctune report: " + job.name;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>"
    << html_escape(title)
    << "</title>\n<style>body{font-family:'DejaVu "
       "Sans',Arial,sans-serif;max-width:1200px;margin:2em auto;"
       "color:#222}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid "
       "#ccc;padding:4px 8px;"
       "text-align:right}th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}"
       "img{max-width:100%;border:1px solid #eee}pre{background:#f7f7f7;padding:1em;overflow:auto}"
       "figcaption{color:#555;margin-bottom:2em}</style></head><body>\n";
  h << "<h1>" << html_escape(title) << "</h1>\n";
  h << "<h2>Tuned gains</h2>\n<table><tr><th>parameter</th><th>tuned</th><th>job's "
       "value</th></tr>\n";
  for (auto it = gains["tuned"].begin(); it != gains["tuned"].end(); ++it)
    h << "<tr><td>" << html_escape(it.key()) << "</td><td>"
      << detail::format_number(it.value().get<double>(), "%.6g") << "</td><td>"
      << detail::format_number(gains["baseline"]["controller"].value(it.key(), NAN), "%.6g")
      << "</td></tr>\n";
  // In the metrics JSON, null error integrals mean a diverged run (+inf); other nulls, a value
  // that does not exist (a fault whose onset was never reached).
  const auto num_or = [](const json& j) { return json_number_or(j, NAN); };
  const auto integral = [](const json& j) { return json_number_or(j, INFINITY); };
  h << "</table>\n<p>Fitness J = " << detail::format_number(num_or(gains["fitness"]), "%.6g")
    << " (job's controller: " << detail::format_number(num_or(gains["baseline"]["fitness"]), "%.6g")
    << "); objective " << html_escape(gains["objective"].value("metric", "")) << " = "
    << detail::format_number(num_or(gains["objective"]["value"]), "%.6g") << "; "
    << gains["optimizer"].value("evaluations", 0) << " evaluations, seed "
    << gains["optimizer"].value("seed", 0) << ".</p>\n";

  for (std::size_t s = 0; s < S; ++s) {
    h << "<h2>Controllers compared"
      << (S > 1 ? ", scenario " + html_escape(job.scenarios[s].name) : "")
      << "</h2>\n<table><tr><th>controller</th><th>ISE</th><th>IAE</th><th>ITAE</th><th>max "
         "|u_d|</th>"
         "<th>control TV</th>";
    const json& first = comparison["controllers"][0]["scenarios"][s];
    for (const json& seg : first.value("segments", json::array()))
      h << "<th>ISE [" << detail::format_number(num_or(seg["window"][0])) << ", "
        << detail::format_number(num_or(seg["window"][1])) << ")</th>";
    for (std::size_t f = 0; f < first.value("peak_error_after_fault", json::array()).size(); ++f)
      h << "<th>peak ‖e‖ after fault " << f + 1 << "</th>";
    h << "</tr>\n";
    for (const json& c : comparison["controllers"]) {
      const json& m = c["scenarios"][s];
      h << "<tr><td>" << html_escape(c.value("label", "?"))
        << (m.value("diverged", false) ? " (diverged)" : "") << "</td><td>"
        << detail::format_number(integral(m["ise"])) << "</td><td>"
        << detail::format_number(integral(m["iae"])) << "</td><td>"
        << detail::format_number(integral(m["itae"])) << "</td><td>"
        << detail::format_number(num_or(m["max_abs_u"])) << "</td><td>"
        << detail::format_number(num_or(m["control_tv"])) << "</td>";
      for (const json& seg : m.value("segments", json::array()))
        h << "<td>" << detail::format_number(integral(seg["ise"])) << "</td>";
      for (const json& p : m.value("peak_error_after_fault", json::array()))
        h << "<td>" << detail::format_number(num_or(p)) << "</td>";
      h << "</tr>\n";
    }
    h << "</table>\n<p>ISE, IAE, ITAE over the objective window; ISE in rad²·s, peak errors in "
         "rad; control "
         "TV = Σ‖u_k − u_{k−1}‖ measures chattering.</p>\n";
  }

  h << "<h2>Figures</h2>\n";
  for (const Figure& f : figures)
    h << "<figure><img alt=\"" << html_escape(f.title) << "\" src=\"data:image/png;base64,"
      << base64(figure_bytes(run_dir / f.file)) << "\"><figcaption>" << html_escape(f.caption)
      << "</figcaption></figure>\n";

  h << "<h2>Run</h2>\n<table>\n";
  for (auto it = run.begin(); it != run.end(); ++it)
    h << "<tr><td>" << html_escape(it.key()) << "</td><td>"
      << html_escape(it.value().is_string() ? it.value().get<std::string>() : it.value().dump())
      << "</td></tr>\n";
  h << "<tr><td>job SHA-256</td><td>" << html_escape(gains["job"].value("sha256", ""))
    << "</td></tr>\n"
    << "<tr><td>generator</td><td>" << html_escape(gains["generator"].dump())
    << "</td></tr>\n</table>\n";
  h << "<h2>Job</h2>\n<pre>" << html_escape(job_text) << "</pre>\n</body></html>\n";
  result.html = run_dir / "report.html";
  write_file_atomic(result.html, h.str());
  return result;
}

LandscapeResult compute_landscape(const Job& job_in, const fs::path& out_dir,
                                  const LandscapeOptions& options, BatchEvaluator& evaluator) {
  if (!job_in.tuning)
    throw InputError(job_in.name, "/tuning", "is required: it gives the parameters' bounds");
  std::vector<std::string> params = options.params;
  if (params.empty())
    for (const ParameterBounds& b : job_in.tuning->parameters)
      if (params.size() < 2) params.push_back(b.name);
  if (params.size() != 2 || params[0] == params[1])
    throw InputError("--params", "",
                     "needs two different tuned parameters (the job tunes " +
                         std::to_string(job_in.tuning->parameters.size()) + ")");
  if (options.n1 < 2 || options.n2 < 2 || options.n1 > 1000 || options.n2 > 1000)
    throw InputError("--grid", "", "needs 2..1000 points per parameter");

  // A job tuning exactly the two parameters, everything else at the job's values.
  Job job = job_in;
  std::vector<ParameterBounds> bounds;
  for (const std::string& p : params) {
    auto it = std::find_if(job_in.tuning->parameters.begin(), job_in.tuning->parameters.end(),
                           [&](const ParameterBounds& b) { return b.name == p; });
    if (it == job_in.tuning->parameters.end())
      throw InputError("--params", "", p + " is not under tuning.parameters of the job");
    bounds.push_back(*it);
  }
  job.tuning->parameters = bounds;
  const TuningProblem problem(job);
  const std::size_t i0 = problem.space().names[0] == params[0] ? 0 : 1;  // problem orders by field

  std::vector<Decision> grid;
  for (int a = 0; a < options.n1; ++a)
    for (int b = 0; b < options.n2; ++b) {
      const double v0 =
          bounds[0].lower + (bounds[0].upper - bounds[0].lower) * a / (options.n1 - 1);
      const double v1 =
          bounds[1].lower + (bounds[1].upper - bounds[1].lower) * b / (options.n2 - 1);
      grid.push_back(i0 == 0 ? Decision{v0, v1} : Decision{v1, v0});
    }
  std::vector<sim::ControllerConfig> controllers;
  controllers.reserve(grid.size());
  for (const Decision& x : grid) controllers.push_back(problem.controller_for(x));
  const std::vector<CandidateOutcome> outcomes = problem.evaluate(controllers, evaluator);

  LandscapeResult r;
  r.params = params;
  r.simulations = static_cast<std::int64_t>(controllers.size() * problem.scenarios());
  r.best_objective = std::numeric_limits<double>::infinity();
  double worst_objective = 0.0;
  std::string csv = params[0] + "," + params[1] + ",objective,fitness,diverged\n";
  char buf[160];
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const Evaluation& e = outcomes[k].evaluation;
    const double p0 = grid[k][i0], p1 = grid[k][1 - i0];
    std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g,%.9g,%d\n", p0, p1,
                  std::isfinite(e.objective) ? e.objective : NAN, e.fitness, e.diverged ? 1 : 0);
    csv += buf;
    if ((k + 1) % static_cast<std::size_t>(options.n2) == 0) csv += "\n";  // gnuplot grid rows
    if (e.objective < r.best_objective) {
      r.best_objective = e.objective;
      r.best = {p0, p1};
    }
    if (std::isfinite(e.objective)) worst_objective = std::max(worst_objective, e.objective);
  }
  fs::create_directories(out_dir);
  r.csv = out_dir / "landscape.csv";
  write_file_atomic(r.csv, csv);

  r.figure = out_dir / (std::string("landscape") + extension(options.format));
  std::ostringstream g;
  g << kStyles << terminal(options.format, 1000, 800) << "set output "
    << gp(r.figure.filename().string()) << "\nset title "
    << gp("Objective (" + std::string(sim::to_string(job.objective.metric)) + ") of " + job.name +
          " over " + params[0] + " and " + params[1])
    << " font ',13'\nset logscale cb\n"
    << colour_tics(r.best_objective, worst_objective) << "set cblabel "
    << gp(std::string(sim::to_string(job.objective.metric)) + " (log scale; lower is better)")
    << "\nset palette rgb 33,13,10\nset xlabel " << gp(params[0]) << "\nset ylabel "
    << gp(params[1]) << "\nset xrange [" << bounds[0].lower << ":" << bounds[0].upper
    << "]\nset yrange [" << bounds[1].lower << ":" << bounds[1].upper
    << "]\nset key outside top center horizontal\n"
    << "plot 'landscape.csv' skip 1 using 1:2:3 with image notitle";
  if (!options.history.empty()) {
    if (!fs::is_regular_file(options.history))
      throw InputError(options.history.string(), "", "cannot read the history file");
    std::istringstream hist(read_file(options.history).value_or(""));
    std::string header;
    std::getline(hist, header);
    std::vector<std::string> cols;
    std::stringstream hs(header);
    for (std::string c; std::getline(hs, c, ',');) cols.push_back(c);
    const auto col = [&](const std::string& n) {
      return static_cast<int>(std::find(cols.begin(), cols.end(), n) - cols.begin()) + 1;
    };
    const int c0 = col(params[0]), c1 = col(params[1]);
    if (c0 > static_cast<int>(cols.size()) || c1 > static_cast<int>(cols.size()))
      throw InputError(options.history.string(), "",
                       "has no columns " + params[0] + " and " + params[1]);
    const fs::path copy = out_dir / "history.csv";
    if (fs::absolute(options.history) != fs::absolute(copy))
      fs::copy_file(options.history, copy, fs::copy_options::overwrite_existing);
    g << ", \\\n     'history.csv' skip 1 using " << c0 << ":" << c1
      << " with linespoints lw 2.5 pt 7 ps 1.3 lc rgb 'black' title 'optimiser: best so far, by "
         "iteration'";
  }
  g << ", \\\n     '-' using 1:2 with points pt 6 ps 3 lw 3 lc rgb 'black' title 'best grid "
       "point'\n"
    << r.best[0] << "," << r.best[1] << "\ne\n";
  write_file_atomic(out_dir / "landscape.gp", g.str());
  run_gnuplot(out_dir, "landscape.gp");
  return r;
}

fs::path draw_study(const fs::path& dir, const std::string& title,
                    const std::string& objective_label, const std::vector<StudySeries>& series,
                    FigureFormat format) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const StudySeries& s : series)
    for (double v : s.objectives)
      if (std::isfinite(v) && v > 0) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
  const bool log_scale = hi >= 10 * lo;
  const fs::path figure = dir / (std::string("study") + extension(format));
  std::ostringstream g;
  g << kStyles << terminal(format, 1000, 600) << "set output " << gp(figure.filename().string())
    << "\nset title " << gp(title) << " font ',13'\nset ylabel " << gp(objective_label) << "\n"
    << (log_scale ? "set logscale y\nset format y '%.3g'\n" : "set format y '%.6g'\n")
    << "set xrange [-0.6:" << series.size() - 0.4 << "]\nset xtics noenhanced rotate by -30 left (";
  for (std::size_t i = 0; i < series.size(); ++i)
    g << (i ? ", " : "") << gp(series[i].label) << " " << i;
  // Algorithm names keep their underscores (no enhanced-text subscripts). The key goes top left:
  // callers order the algorithms best median first, so that corner is the emptiest.
  g << ")\nset grid xtics ytics lc rgb '#dddddd'\nset key inside top left opaque box\n"
    << "$runs << EOD\n";
  // Runs side by side within an algorithm's slot, in seed order, so equal results stay visible.
  for (std::size_t i = 0; i < series.size(); ++i) {
    const std::size_t n = series[i].objectives.size();
    for (std::size_t k = 0; k < n; ++k) {
      const double v = series[i].objectives[k];
      if (!std::isfinite(v) || (log_scale && v <= 0)) continue;
      const double dx =
          n > 1 ? 0.5 * (static_cast<double>(k) / static_cast<double>(n - 1) - 0.5) : 0.0;
      g << detail::format_number(static_cast<double>(i) + dx, "%.6g") << ","
        << detail::format_number(v, "%.17g") << "\n";
    }
  }
  g << "EOD\n$medians << EOD\n";
  for (std::size_t i = 0; i < series.size(); ++i) {
    std::vector<double> v = series[i].objectives;
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    const double m = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    if (!std::isfinite(m)) continue;
    g << static_cast<double>(i) - 0.35 << "," << detail::format_number(m, "%.17g") << ",0.7,0\n";
  }
  g << "EOD\nplot $runs using 1:2 with points pt 7 ps 1.1 lc rgb '#1f77b4' title 'best "
       "objective of one run (one point per seed)', \\\n"
    << "     $medians using 1:2:3:4 with vectors nohead lw 3 lc rgb '#d62728' title 'median'\n";
  write_file_atomic(dir / "study.gp", g.str());
  run_gnuplot(dir, "study.gp");
  return figure;
}

}  // namespace ftc::tune
