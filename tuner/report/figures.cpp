#include "report/figures.hpp"

#include <algorithm>
#include <set>
#include <sstream>

#include "ftc/sim/plants.hpp"
#include "ftc/tune/io/files.hpp"

namespace ftc::tune::report_detail {

namespace fs = std::filesystem;
using nlohmann::json;
using plot::gp;
using plot::Series;

namespace {

std::string capitalised(std::string s) {
  if (!s.empty()) s[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(s[0])));
  return s;
}

}  // namespace

std::vector<Figure> draw_run_figures(const fs::path& run_dir, const Job& job, const json& gains,
                                     const std::vector<Series>& series, FigureFormat fmt) {
  const sim::PlantKind& kind = *sim::find_plant_kind(job.plant.model);
  const int n = kind.axes, m = kind.actuators;
  // Trajectory columns: time, x1..x2n, ud1..udm, u1..um.
  const int first_position = 2, first_rate = 2 + n, first_command = 2 + 2 * n,
            first_applied = 2 + 2 * n + m;
  const std::string ext = plot::extension(fmt);
  const sim::Scenario& sc0 = job.scenarios.front();
  std::vector<double> onsets;
  for (const sim::Fault& f : sc0.faults)
    if (f.onset < sc0.duration) onsets.push_back(f.onset);
  std::sort(onsets.begin(), onsets.end());
  onsets.erase(std::unique(onsets.begin(), onsets.end()), onsets.end());
  const std::string scen = job.scenarios.size() > 1 ? " (scenario " + sc0.name + ")" : "";
  const bool paper = job.plant.model == "spacecraft";

  std::ostringstream g;
  g << plot::kStyles;
  std::vector<Figure> figures;

  // Figures 3 and 4: the states in n stacked panels.
  const auto states = [&](const std::string& name, int first_col, const std::string& what,
                          const std::string& unit, int symbol_offset, const std::string& title,
                          const std::string& caption) {
    const std::string file = "figures/" + name + ext;
    // Fixed margins keep the panels aligned although only the first carries the key.
    g << plot::terminal(fmt, 1100, 150 + 270 * n) << "set output " << gp(file) << "\n"
      << "set multiplot layout " << n << ",1 title " << gp(title + scen) << " font ',13'\n"
      << "set lmargin at screen 0.09\nset rmargin at screen 0.78\n"
      << plot::onset_marks(onsets) << "set xrange [0:" << sc0.duration << "]\n";
    for (int i = 0; i < n; ++i) {
      const std::string axis = i < static_cast<int>(kind.axis_names.size())
                                   ? kind.axis_names[static_cast<std::size_t>(i)] + " "
                                   : "";
      g << "set ylabel "
        << gp(axis + (what.empty() ? "" : what + " ") + "x_" +
              std::to_string(symbol_offset + i + 1) + " [" + unit + "]")
        << "\n"
        << (i == n - 1 ? "set xlabel 'time [s]'\n" : "unset xlabel\n")
        << (i == 0 ? "set key outside right top vertical box opaque\n" : "unset key\n")
        << plot::series_plot(series, "1:" + std::to_string(first_col + i), i == 0);
    }
    g << "unset multiplot\nunset xrange\nunset xlabel\nunset lmargin\nunset rmargin\n"
      << "set key outside right top vertical box opaque\n";
    figures.push_back({file, title, caption});
  };
  states("fig3-attitude", first_position, "", kind.position_unit, 0,
         capitalised(kind.positions) + " under actuator faults" + (paper ? " (paper Fig. 3)" : ""),
         capitalised(kind.positions) +
             " X1 of every compared controller; dashed lines mark the fault onsets.");
  states("fig4-rates", first_rate, "rate", kind.rate_unit, n,
         capitalised(kind.rates) + " under actuator faults" + (paper ? " (paper Fig. 4)" : ""),
         capitalised(kind.rates) + " X2 of every compared controller.");

  // Figure 5: convergence.
  {
    const std::string file = "figures/fig5-fitness" + ext;
    const std::string type = gains["optimizer"].value("type", "bat");
    const std::string algorithm =
        type == "bat"      ? "Bat algorithm"
        : type == "random" ? "random search"
        : type == "pagmo"  ? "pagmo " + gains["optimizer"].value("name", std::string("?"))
                           : type;
    g << plot::terminal(fmt, 1000, 600) << "set output " << gp(file) << "\n"
      << "unset arrow; unset label\nset title "
      << gp(std::string("Best fitness per iteration") + (paper ? " (paper Fig. 5)" : ""))
      << " font ',13'\n"
      << "set xlabel 'iteration'\nset ylabel 'best fitness J = 1/objective'\nset format y "
         "'%.6g'\n"
      << "set key inside right bottom\n"
      << "plot 'history.csv' skip 1 using 1:2 with linespoints ls 2 lw 2 pt 7 title "
      << gp(algorithm);
    if (fs::is_regular_file(run_dir / "history-random.csv"))
      g << ", \\\n     'history-random.csv' skip 1 using 1:2 with linespoints ls 5 lw 2 pt 5 "
           "title 'random search, same budget'";
    g << "\nset format y\nunset title\nset key outside right top vertical box opaque\n";
    figures.push_back({file, "Convergence",
                       "Best fitness found after each iteration (iteration 0 "
                       "is the initial population)."});
  }

  // Figure 6: commanded (and, on faulted actuators, applied) outputs per controller.
  {
    const std::string file = "figures/fig6-inputs" + ext;
    const std::size_t c_count = series.size();
    const std::size_t rows = (c_count + 1) / 2;
    std::set<int> faulted;
    for (const sim::Fault& f : sc0.faults) faulted.insert(f.actuator);
    g << plot::terminal(fmt, 1200, static_cast<int>(430 * rows + 60)) << "set output " << gp(file)
      << "\nset multiplot layout " << rows << ",2 title "
      << gp(std::string("Actuator outputs") + (paper ? " (paper Fig. 6)" : "") + scen)
      << " font ',13'\n"
      << plot::onset_marks(onsets, false) << "set xrange [0:" << sc0.duration
      << "]\nset xlabel 'time [s]'\n"
      << "set ylabel 'actuator output u'\nset key below horizontal font ',9' maxrows 2\nset "
         "bmargin 7\n";
    for (std::size_t c = 0; c < c_count; ++c) {
      g << "set title " << gp(series[c].label) << "\nplot ";
      for (int j = 1; j <= m; ++j)
        g << (j > 1 ? ", " : "") << gp(series[c].file)
          << " skip 1 using 1:" << first_command + j - 1 << " with lines ls " << j
          << " lw 1.1 title 'u_{d" << j << "}'";
      for (int j : faulted)
        g << ", " << gp(series[c].file) << " skip 1 using 1:" << first_applied + j - 1
          << " with lines ls " << j << " lw 2 dt 2 title 'applied u_" << j << "'";
      g << "\n";
    }
    g << "unset multiplot\nunset title\nunset xrange\nunset bmargin\nset key outside right "
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
    std::string norm = "sqrt(";
    for (int i = 0; i < n; ++i)
      norm += (i ? " + $" : "$") + std::to_string(first_position + i) + "**2";
    norm += ")";
    g << plot::terminal(fmt, 1100, 600) << "set output " << gp(file) << "\n"
      << plot::onset_marks(onsets) << "set title " << gp("Error ‖X_1‖ after the faults" + scen)
      << " font ',13'\nset logscale y\nset format y '10^{%L}'\nset xrange [" << t0 << ":"
      << sc0.duration << "]\nset xlabel 'time [s]'\nset ylabel "
      << gp("‖X_1‖ [" + kind.position_unit + "]") << "\n"
      << plot::series_plot(series, "1:(" + norm + ")", true)
      << "unset logscale y\nset format y\nunset xrange\nunset title\n";
    figures.push_back({file, "Zoom on the faulted part",
                       "Norm of the error X1 from one second before the first fault on, log "
                       "scale: the part of the run the paper's fault-tolerance claims are about."});
  }

  write_file_atomic(run_dir / "figures" / "report.gp", g.str());
  run_gnuplot(run_dir, "figures/report.gp");
  return figures;
}

}  // namespace ftc::tune::report_detail
