#pragma once
// Reports engineers can look at, drawn with gnuplot (Debian package gnuplot-nox) from the files
// a run writes:
//   fig3-attitude    x1..x3 of every compared controller against time, fault onsets marked
//   fig4-rates       x4..x6 likewise
//   fig5-fitness     the optimiser's best fitness per iteration (and random search, if present)
//   fig6-inputs      commanded outputs u_d1..u_d4 per controller, applied outputs of faulted
//   actuators fig7-fault-zoom  ‖X1‖ on a log scale over the faulted part of the run
// and report.html, one self-contained page with the figures inline, the comparison table, the
// tuned gains, the job and the run metadata.
#include <filesystem>
#include <string>
#include <vector>

#include "ftc/tune/job/job.hpp"

namespace ftc::tune {

enum class FigureFormat { png, svg };

struct ReportOptions {
  bool html = true;                         // write report.html with the figures inline as PNG
  FigureFormat format = FigureFormat::png;  // of the figure files when html is false
};

struct ReportResult {
  std::vector<std::filesystem::path> figures;  // in figures/
  std::filesystem::path html;                  // empty when not asked for
};

// Throws InputError (source: the run directory or the offending file) when the directory is not
// a complete `ftctune run` output; std::runtime_error when gnuplot is missing or fails.
ReportResult render_report(const std::filesystem::path& run_dir, const ReportOptions& options = {});

// Runs `gnuplot script` in `dir`. Every figure the script names (`set output '...'` lines) is
// written under a temporary name and moved into place (commit_file) only when gnuplot succeeded
// and it is whole: a figure is the earlier one or the whole new one. Throws OutputError with
// gnuplot's message when it fails or leaves a figure incomplete.
void run_gnuplot(const std::filesystem::path& dir, const std::string& script_name);
// True when `file` is a whole PNG (ends with its IEND chunk), SVG (ends with </svg>) or PDF.
bool figure_is_whole(const std::filesystem::path& file);

}  // namespace ftc::tune
