#include "ftc/tune/report/report.hpp"

#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "ftc/tune/io/files.hpp"
#include "report/figures.hpp"
#include "report/front_figures.hpp"
#include "report/html.hpp"

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

json read_json(const fs::path& dir, const std::string& name) {
  json j = json::parse(read_required(dir, name), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw InputError((dir / name).string(), "", "is not a JSON object (damaged output?)");
  return j;
}

}  // namespace

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
  std::vector<std::vector<plot::Series>> series(S);
  for (const json& c : comparison["controllers"]) {
    const json& sc = c.value("scenarios", json::array());
    for (std::size_t s = 0; s < S && s < sc.size(); ++s) {
      if (!sc[s].contains("trajectory"))
        throw InputError((run_dir / "comparison.json").string(), "",
                         "has no trajectories: re-run `ftctune run`");
      const std::string file = sc[s]["trajectory"];
      if (!fs::is_regular_file(run_dir / file))
        throw InputError(run_dir.string(), "", "missing " + file);
      series[s].push_back({c.value("label", "?"), file, c.value("role", "") == "tuned",
                           c.value("controller", json::object()).value("type", "")});
    }
  }

  // The page embeds PNGs: a fifth of the size of SVGs that carry every sample.
  const FigureFormat format = options.html ? FigureFormat::png : options.format;
  fs::create_directories(run_dir / "figures");
  const std::vector<report_detail::Figure> figures =
      report_detail::draw_run_figures(run_dir, job, gains, series[0], format);
  // A run with two or more soft goals: its front's scatter and hypervolume.
  // Only this run's: a front.json left by an earlier run of another job is ignored.
  const json sha = gains.value(json::json_pointer("/job/sha256"), json(""));
  const std::optional<Front> front =
      read_front(run_dir, job, sha.is_string() ? sha.get<std::string>() : std::string());
  std::vector<report_detail::Figure> front_figures;
  if (front) front_figures = report_detail::draw_front_figures(run_dir, *front, format);
  if (front_figures.empty()) {  // no front, or an empty one
    std::error_code ec;
    fs::remove(run_dir / "figures" / "front.gp", ec);  // of an earlier run's front
  }
  // Once the new figures are drawn: a figure of an earlier report (another format, another
  // scenario count) must not sit beside them as if it were current.
  std::set<fs::path> current;
  for (const report_detail::Figure& f : figures) current.insert(fs::absolute(run_dir / f.file));
  for (const report_detail::Figure& f : front_figures)
    current.insert(fs::absolute(run_dir / f.file));
  for (const auto& e : fs::directory_iterator(run_dir / "figures"))
    if (e.is_regular_file() && (e.path().extension() == ".png" || e.path().extension() == ".svg") &&
        !current.count(fs::absolute(e.path())))
      fs::remove(e.path());
  ReportResult result;
  for (const report_detail::Figure& f : figures) result.figures.push_back(run_dir / f.file);
  for (const report_detail::Figure& f : front_figures) result.figures.push_back(run_dir / f.file);
  if (!options.html) return result;
  result.html = run_dir / "report.html";
  write_file_atomic(result.html,
                    report_detail::report_html(run_dir, job, job_text, gains, comparison, run,
                                               figures, front ? &*front : nullptr, front_figures));
  return result;
}

}  // namespace ftc::tune
