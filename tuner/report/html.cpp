#include "report/html.hpp"

#include <openssl/evp.h>

#include <cmath>
#include <sstream>

#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/run/documents.hpp"
#include "io/text.hpp"

namespace ftc::tune::report_detail {

using json_io::json_number_or;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

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

// A figure gnuplot has just drawn.
std::string figure_bytes(const fs::path& file) {
  std::optional<std::string> bytes = read_file(file);
  if (!bytes) throw std::runtime_error("gnuplot did not write " + file.string());
  return *bytes;
}

// The settings of a job as rows of (path, value): objects open into dotted paths, lists of
// objects into indexed ones, and a list of plain values stays on one row.
void settings_rows(const nlohmann::ordered_json& j, const std::string& path,
                   std::ostringstream& h) {
  const auto scalar_list = [](const nlohmann::ordered_json& a) {
    for (const auto& e : a)
      if (e.is_structured()) return false;
    return true;
  };
  if (j.is_object() && !j.empty()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      settings_rows(it.value(), path.empty() ? it.key() : path + "." + it.key(), h);
  } else if (j.is_array() && !j.empty() && !scalar_list(j)) {
    for (std::size_t i = 0; i < j.size(); ++i)
      settings_rows(j[i], path + "[" + std::to_string(i) + "]", h);
  } else {
    std::string value;
    if (j.is_array()) {
      for (const auto& e : j) value += (value.empty() ? "" : ", ") + e.dump();
      value = "[" + value + "]";
    } else {
      value = j.is_string() ? j.get<std::string>() : j.dump();
    }
    h << "<tr><td>" << html_escape(path) << "</td><td>" << html_escape(value) << "</td></tr>\n";
  }
}

// The robust table of comparison.md: each controller's aggregates over every scenario.
void summary_table(const json& comparison, const Job& job, std::ostringstream& h) {
  const auto num = [](const json& j) { return detail::format_number(json_number_or(j, NAN)); };
  const json& first = comparison["controllers"][0].value("ensemble", json::object());
  h << "<h2>All " << first.value("scenarios", 0) << " scenarios</h2>\n<p>"
    << first.value("unrecoverable", 0)
    << " cannot be controlled by any gains once their faults have started"
    << (first.value("counted", 0) < first.value("scenarios", 0)
            ? ", and the objective leaves them out"
            : "")
    << ". Values are " << html_escape(std::string(job.objective.metric->name))
    << " per scenario; quantiles by nearest rank.</p>\n<table><tr><th>controller</th><th>"
    << html_escape(objective_label(job))
    << "</th><th>mean</th><th>median</th><th>p90</th><th>max</th><th>CVaR"
    << detail::format_number(job.objective.alpha, "%.3g") << "</th><th>diverged</th></tr>\n";
  for (const json& c : comparison["controllers"]) {
    const json& m = c.value("ensemble", json::object());
    h << "<tr><td>" << html_escape(c.value("label", "?")) << "</td><td>"
      << num(m.value("objective", json())) << "</td><td>" << num(m.value("mean", json()))
      << "</td><td>" << num(m.value("median", json())) << "</td><td>" << num(m.value("p90", json()))
      << "</td><td>" << num(m.value("max", json())) << "</td><td>" << num(m.value("cvar", json()))
      << "</td><td>" << m.value("diverged", 0) << "</td></tr>\n";
  }
  h << "</table>\n";
}

// comparison.md's goals table: each goal's value per controller, its limit and whether the
// controller meets every limit, read back out of the controllers of comparison.json (or of
// evaluation.json, aggregated over `scenarios`; 0: the job's).
void goals_table(const json& controllers, const Job& job, std::size_t scenarios,
                 std::ostringstream& h) {
  const auto num = [](const json& j) { return detail::format_number(json_number_or(j, NAN)); };
  h << "<table><tr><th>controller</th>";
  for (std::size_t k = 0; k < job.goals.size(); ++k)
    h << "<th>" << html_escape(goal_label(job, k, scenarios)) << "</th>";
  h << "<th>total violation</th><th>feasible</th></tr>\n";
  for (const json& c : controllers) {
    const json g = c.value("goals", json::object());
    const json list = g.value("goals", json::array());
    h << "<tr><td>" << html_escape(c.value("label", "?")) << "</td>";
    for (std::size_t k = 0; k < job.goals.size(); ++k)
      h << "<td>"
        << num(k < list.size() && list[k].is_object() ? list[k].value("value", json()) : json())
        << "</td>";
    h << "<td>" << num(g.value("total_violation", json())) << "</td><td>"
      << (g.value("feasible", false) ? "yes" : "no") << "</td></tr>\n";
  }
  h << "</table>\n";
}

// The held-out front in `dir` (`ftctune evaluate --front RUN`, evaluation/front.json) when it is
// one of this job: every point's soft goals in sample and held out, side by side, whether it
// stays on the held-out front, and the figure that joins the two (front-held-out.png). An
// in-sample front is not called robust until this says which points hold.
void held_out_front_section(const fs::path& dir, const Job& job, const std::string& job_sha256,
                            bool heading, std::ostringstream& h) {
  std::optional<Front> front;
  try {
    front = read_front(dir, job, job_sha256);
  } catch (const InputError& e) {
    h << "<p>evaluation/front.json cannot be read: " << html_escape(e.what()) << "</p>\n";
    return;
  }
  if (!front || !front->held_out || front->points.empty()) return;
  const FrontHeldOut& where = *front->held_out;
  const auto value = [](double v) { return detail::format_number(v, "%.4g"); };
  std::size_t on = 0;
  for (const FrontPoint& p : front->points) on += p.dominated ? 0 : 1;
  if (heading) h << "<h2>Out-of-sample evaluation</h2>\n";
  h << "<h3>The front held out</h3>\n<p>From <code>ftctune evaluate --front</code> "
       "(evaluation/front.json): the run's "
    << front->points.size() << " front points on " << where.count << " held-out members (seed "
    << where.seed << "); " << on
    << " stay on the front there (not dominated by another point's held-out values, feasible)."
    << " Hypervolume held out " << value(front->hypervolume) << ", in sample "
    << value(where.in_sample_hypervolume) << ", against the run's reference point.";
  if (on > 0) h << " The held-out knee is point " << front->picked << ".";
  h << "</p>\n<div class=\"wide\"><table class=\"front\"><tr><th>#</th><th>held out</th>";
  for (std::size_t s : front->soft)
    h << "<th title=\"" << html_escape(front->goals[s].label) << "\">goal " << s + 1
      << " in sample</th><th>goal " << s + 1
      << " held out</th><th>held out / in sample (the point's noise floor)</th>";
  h << "</tr>\n";
  for (std::size_t i = 0; i < front->points.size(); ++i) {
    const FrontPoint& p = front->points[i];
    const bool knee = on > 0 && front->picked == i;
    h << "<tr" << (knee ? " class=\"picked\"" : "") << "><td>" << i << (knee ? " ★" : "")
      << "</td><td class=\"note\">"
      << (p.dominated ? "off the front"
          : knee      ? "on the front (knee)"
                      : "on the front")
      << "</td>";
    for (std::size_t s : front->soft) {
      const double in = s < p.in_sample.size() ? p.in_sample[s] : NAN, out = p.goals[s];
      const double floor = s < p.noise_floor.size() ? p.noise_floor[s].value_or(NAN) : NAN;
      h << "<td>" << value(in) << "</td><td>" << value(out) << "</td><td>"
        << (std::isfinite(in) && std::isfinite(out) && in != 0 ? value(out / in) + "×"
                                                               : std::string("–"))
        << (std::isfinite(floor) ? " (" + detail::format_number(100 * floor, "%.2g") + " %)"
                                 : std::string())
        << "</td>";
    }
    h << "</tr>\n";
  }
  h << "</table></div>\n";
  std::error_code ec;
  if (const std::optional<std::string> png = fs::is_regular_file(dir / "front-held-out.png", ec)
                                                 ? read_file(dir / "front-held-out.png")
                                                 : std::nullopt)
    h << "<figure><img alt=\"held-out front\" src=\"data:image/png;base64," << base64(*png)
      << "\"><figcaption>evaluation/front-held-out.png: each point in sample (open) and held "
         "out (filled; a cross when it drops off the held-out front), joined.</figcaption>"
         "</figure>\n";
}

// The run's evaluation/ (`ftctune evaluate`'s default place), when there is one: its table of
// aggregates over the held-out members, and its figure.
void evaluation_section(const fs::path& run_dir, const Job& job, const std::string& job_sha256,
                        std::ostringstream& h) {
  const fs::path dir = run_dir / "evaluation";
  std::error_code ec;
  const std::optional<std::string> text = fs::is_regular_file(dir / "evaluation.json", ec)
                                              ? read_file(dir / "evaluation.json")
                                              : std::nullopt;
  const json e = text ? json::parse(*text, nullptr, false) : json();
  if (e.is_discarded() || !e.is_object() || !e.contains("controllers") ||
      !e["controllers"].is_array())
    return held_out_front_section(dir, job, job_sha256, true, h);  // a front alone, if any
  const auto num = [](const json& j) { return detail::format_number(json_number_or(j, NAN)); };
  h << "<h2>Out-of-sample evaluation</h2>\n<p>From <code>ftctune evaluate</code> "
       "(evaluation/evaluation.json): "
    << e.value("listed", 0) << " listed scenario(s) and " << e.value("count", 0)
    << " held-out ensemble members (seed " << e.value("seed", 0) << "); "
    << html_escape(e.value("metric", "")) << " of each scenario over the objective window.";
  if (!e["controllers"].empty()) {
    const json& a = e["controllers"][0].value("aggregates", json::object());
    h << " " << a.value("unrecoverable", 0) << " of " << a.value("scenarios", 0)
      << " scenarios are unrecoverable"
      << (a.value("counted", 0) < a.value("scenarios", 0) ? " and left out of the aggregates"
                                                          : " and counted");
  }
  h << ".</p>\n<table><tr><th>controller</th><th>source</th><th>mean</th><th>median</th>"
       "<th>p90</th><th>max</th><th>CVaR</th><th>diverged</th></tr>\n";
  for (const json& c : e["controllers"]) {
    const json& a = c.value("aggregates", json::object());
    h << "<tr><td>" << html_escape(c.value("label", "?")) << "</td><td>"
      << html_escape(c.value("source", "")) << "</td><td>" << num(a.value("mean", json()))
      << "</td><td>" << num(a.value("median", json())) << "</td><td>" << num(a.value("p90", json()))
      << "</td><td>" << num(a.value("max", json())) << "</td><td>" << num(a.value("cvar", json()))
      << "</td><td>" << a.value("diverged", 0) << "</td></tr>\n";
  }
  h << "</table>\n";
  if (!job.goals.empty()) {  // each goal aggregated over the same members
    h << "<p>The job's goals over the same scenarios:</p>\n";
    goals_table(e["controllers"], job,
                static_cast<std::size_t>(e.value("listed", 0) + e.value("count", 0)), h);
  }
  if (const std::optional<std::string> png = fs::is_regular_file(dir / "evaluation.png", ec)
                                                 ? read_file(dir / "evaluation.png")
                                                 : std::nullopt)
    h << "<figure><img alt=\"out-of-sample evaluation\" src=\"data:image/png;base64,"
      << base64(*png) << "\"><figcaption>evaluation/evaluation.png</figcaption></figure>\n";
  held_out_front_section(dir, job, job_sha256, false, h);
}

// The Pareto front (front.json): what it is, a table of its points with the picked one marked
// and the compared controllers under them, and its figures.
void front_section(const fs::path& run_dir, const Job& job, const Front& front,
                   const std::vector<Figure>& figures, std::ostringstream& h) {
  const std::size_t G = front.goals.size();
  const auto value = [](double v) { return detail::format_number(v, "%.6g"); };
  if (front.points.empty()) {
    h << "<h2>Pareto front</h2>\n<p class=\"front\">No trial of the run met the hard goals, so "
         "its Pareto front is empty: there is no trade-off to show and no point was picked. "
         "gains.json holds the trial with the least total violation of the hard goals, which is "
         "not deployable (its fitness is negative).</p>\n";
    return;
  }
  std::vector<std::string> param_names;
  if (job.tuning)
    for (const ParameterBounds& b : job.tuning->parameters) param_names.push_back(b.name);
  // The points that another point cannot be told apart from (front.json's partners).
  std::size_t twinned = 0;
  for (const FrontPoint& p : front.points) twinned += p.within_noise.empty() ? 0 : 1;
  h << "<h2>Pareto front</h2>\n<p class=\"front\">The run kept " << front.points.size()
    << " tuned point(s) that no other candidate it evaluated beats on every soft goal: the "
       "trade-offs this search found, not a proven optimum. Its hypervolume, on log10 of each "
       "soft goal against the reference point (";
  for (std::size_t k = 0; k < front.reference.size(); ++k)
    h << (k ? ", " : "") << value(front.reference[k]);
  h << "), is " << value(front.hypervolume) << ".";
  h << " gains.json holds point #" << front.picked << ", picked by the rule <code>"
    << html_escape(front.rule) << "</code>; <code>ftctune pick</code> writes another.";
  h << " The noise floor is each goal's relative spread over a point's perturbed re-runs, where "
       "the run measured it (\u2013 elsewhere); ";
  if (twinned)
    h << twinned
      << " point(s) differ from another by no more than the noise floor of one of "
         "the two on every soft goal (marked below): their differences are noise, "
         "not a trade-off.";
  else
    h << "no two points differ by less than the noise floor of one of them on every soft goal.";
  // The goals named once, above the table, and its columns by number: with each goal's label
  // in two headers (its value and its floor) the table was 1 485 px wide and its notes ran off
  // the page. The notes come second, where they stay in sight.
  h << "</p>\n<p>The goals (the columns \"goal k\" hold their values, \"floor k\" their noise "
       "floors):</p>\n<ol class=\"goals\">";
  for (const FrontGoal& g : front.goals)
    h << "<li>" << html_escape(g.label) << " [" << html_escape(g.unit) << "]"
      << (g.soft() ? ", minimized" : " ≤ " + value(*g.at_most)) << "</li>";
  h << "</ol>\n<div class=\"wide\"><table class=\"front\"><tr><th>#</th><th>note</th>";
  for (const std::string& n : param_names) {
    // A line may break after an underscore of a long name (switching_gain).
    std::string name = html_escape(n);
    for (std::size_t at = 0; (at = name.find('_', at)) != std::string::npos; at += 6)
      name.insert(at + 1, "<wbr>");
    h << "<th>" << name << "</th>";
  }
  for (std::size_t g = 0; g < G; ++g)
    h << "<th title=\"" << html_escape(front.goals[g].label) << "\">goal " << g + 1
      << (front.goals[g].soft() ? " (min)" : " ≤ " + value(*front.goals[g].at_most)) << "</th>";
  h << "<th title=\"yes, or no with the total violation of the hard goals\">feasible</th>";
  for (std::size_t g = 0; g < G; ++g)
    h << "<th title=\"the noise floor of goal " << g + 1 << "\">floor " << g + 1 << "</th>";
  h << "<th>trial</th></tr>\n";
  for (std::size_t i = 0; i < front.points.size(); ++i) {
    const FrontPoint& p = front.points[i];
    const bool picked = front.picked == i;
    h << "<tr" << (picked ? " class=\"picked\"" : "") << "><td>" << i << (picked ? " ★" : "")
      << "</td>";
    std::string note = picked ? "picked (" + front.rule + ")" : "";
    if (!p.within_noise.empty()) {
      std::string list;
      for (std::size_t t : p.within_noise) list += (list.empty() ? "#" : ", #") + std::to_string(t);
      note += (note.empty() ? "" : "; ") + std::string("within the noise floor of ") + list;
    }
    h << "<td class=\"note\">" << html_escape(note) << "</td>";
    for (std::size_t k = 0; k < param_names.size(); ++k)
      h << "<td>" << value(k < p.parameters.size() ? p.parameters[k] : NAN) << "</td>";
    for (std::size_t g = 0; g < G; ++g) h << "<td>" << value(p.goals[g]) << "</td>";
    h << "<td>" << (p.feasible() ? "yes" : "no (violation " + value(p.violation) + ")") << "</td>";
    for (std::size_t g = 0; g < G; ++g) {
      const double f = p.noise_floor[g].value_or(NAN);
      h << "<td>"
        << (std::isfinite(f) ? detail::format_number(100 * f, "%.2g") + " %" : std::string("–"))
        << "</td>";
    }
    h << "<td>" << p.trial << "</td></tr>\n";
  }
  for (const FrontCompared& c : front.compared) {
    h << "<tr class=\"compared\"><td>" << html_escape(c.label)
      << (c.role == "baseline" ? " (job's gains)" : "") << "</td><td class=\"note\">compared</td>";
    for (std::size_t k = 0; k < param_names.size(); ++k) h << "<td></td>";
    for (std::size_t g = 0; g < G; ++g) h << "<td>" << value(c.goals[g]) << "</td>";
    h << "<td>" << (c.feasible ? "yes" : "no") << "</td>";
    for (std::size_t g = 0; g < G; ++g) h << "<td></td>";
    h << "<td></td></tr>\n";
  }
  h << "</table></div>\n";
  for (const Figure& f : figures)
    h << "<figure><img alt=\"" << html_escape(f.title) << "\" src=\"data:image/png;base64,"
      << base64(figure_bytes(run_dir / f.file)) << "\"><figcaption>" << html_escape(f.caption)
      << "</figcaption></figure>\n";
}

}  // namespace

std::string report_html(const fs::path& run_dir, const Job& job, const std::string& job_text,
                        const json& gains, const json& comparison, const json& run,
                        const std::vector<Figure>& figures, const Front* front,
                        const std::vector<Figure>& front_figures) {
  const std::size_t S = job.scenarios.size();
  std::ostringstream h;
  const std::string title = "ftctune report: " + job.name;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>"
    << html_escape(title)
    << "</title>\n<style>body{font-family:'DejaVu "
       "Sans',Arial,sans-serif;max-width:1200px;margin:2em auto;"
       "color:#222}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid "
       "#ccc;padding:4px 8px;"
       "text-align:right}th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}"
       ".settings td{text-align:left;font-family:monospace}"
       "img{max-width:100%;border:1px solid #eee}pre{background:#f7f7f7;padding:1em;overflow:auto}"
       "figcaption{color:#555;margin-bottom:2em}tr.picked td{background:#fff4c2;font-weight:bold}"
       "tr.compared td{background:#f7f7f7}.wide{overflow-x:auto}"
       "table.front td.note{text-align:left;white-space:normal;min-width:9em}"
       "table.front td,table.front th{padding:3px 5px}table.front td{white-space:nowrap}"
       "table.front td:first-child{white-space:normal;min-width:4em}table.front "
       "th:nth-child(2){text-align:left}"
       "</style></head><body>\n";
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
    << "); " << html_escape(objective_label(job)) << " = "
    << detail::format_number(num_or(gains["objective"]["value"]), "%.6g") << "; "
    << gains["optimizer"].value("evaluations", 0) << " evaluations, seed "
    << gains["optimizer"].value("seed", 0) << ".</p>\n";
  if (gains.contains("warnings") && gains["warnings"].is_array() && !gains["warnings"].empty()) {
    h << "<ul class=\"warnings\">\n";
    for (const auto& w : gains["warnings"])
      if (w.is_string())
        h << "<li><b>Warning:</b> " << html_escape(w.get<std::string>()) << "</li>\n";
    h << "</ul>\n";
  }

  if (front) front_section(run_dir, job, *front, front_figures, h);

  // comparison.md's noise-floor sentence and, for an ensemble job, its robust table.
  if (comparison.contains("noise_floor") && comparison["noise_floor"].is_string())
    h << "<p class=\"noise-floor\">" << html_escape(comparison["noise_floor"].get<std::string>())
      << "</p>\n";
  if (!job.goals.empty()) {
    h << "<h2>Goals</h2>\n";
    goals_table(comparison["controllers"], job, 0, h);
  }
  if (job.ensemble) summary_table(comparison, job, h);

  for (std::size_t s = 0; s < S; ++s) {
    h << "<h2>Controllers compared"
      << (S > 1 ? ", scenario " + html_escape(job.scenarios[s].name) : "") << "</h2>\n";
    if (const auto& sensors = job.scenarios[s].sensors)
      h << "<p class=\"sensors\">The controller read sensors: " << html_escape(sensors->summary())
        << ". The metrics measure the true state.</p>\n";
    h << "<table><tr><th>controller</th>";
    // The columns of comparison.md's table (metrics_markdown_table), from the metrics record's
    // description (ftc/sim/metrics_record.hpp), read back out of comparison.json.
    using sim::MetricScope;
    const auto field = [](const json& o, const sim::MetricField& f) {
      return o.is_object() ? o.value(std::string(f.name), json()) : json();
    };
    // A window field's null is a diverged run (+inf), another's a value never reached.
    const auto cell = [&](const sim::MetricField& f, const json& v) {
      h << "<td>" << detail::format_number(f.scope == MetricScope::window ? integral(v) : num_or(v))
        << "</td>";
    };
    for (const sim::MetricField& f : sim::kMetricFields)
      if (f.in_tables && f.scope != MetricScope::fault)
        h << "<th>" << html_escape(sim::plain_label(f)) << "</th>";
    const json& first = comparison["controllers"][0]["scenarios"][s];
    for (const sim::MetricField& f : sim::kMetricFields)
      if (f.column_per_extra_window)
        for (const json& seg : first.value("segments", json::array()))
          h << "<th>" << html_escape(sim::plain_label(f)) << " ["
            << detail::format_number(num_or(seg["window"][0])) << ", "
            << detail::format_number(num_or(seg["window"][1])) << ")</th>";
    for (const sim::MetricField& f : sim::kMetricFields)
      if (f.in_tables && f.scope == MetricScope::fault)
        for (std::size_t k = 0; k < first.value(std::string(f.name), json::array()).size(); ++k)
          h << "<th>" << html_escape(sim::plain_label(f)) << " " << k + 1 << "</th>";
    h << "</tr>\n";
    for (const json& c : comparison["controllers"]) {
      const json& m = c["scenarios"][s];
      h << "<tr><td>" << html_escape(c.value("label", "?"))
        << (m.value("diverged", false) ? " (diverged)" : "") << "</td>";
      for (const sim::MetricField& f : sim::kMetricFields)
        if (f.in_tables && f.scope != MetricScope::fault) cell(f, field(m, f));
      for (const sim::MetricField& f : sim::kMetricFields)
        if (f.column_per_extra_window)
          for (const json& seg : m.value("segments", json::array())) cell(f, field(seg, f));
      for (const sim::MetricField& f : sim::kMetricFields)
        if (f.in_tables && f.scope == MetricScope::fault)
          for (const json& p : m.value(std::string(f.name), json::array())) cell(f, p);
      h << "</tr>\n";
    }
    h << "</table>\n<p>Over the objective window; " << html_escape(sim::units_note(false))
      << "</p>\n";
  }

  h << "<h2>Figures</h2>\n";
  for (const Figure& f : figures)
    h << "<figure><img alt=\"" << html_escape(f.title) << "\" src=\"data:image/png;base64,"
      << base64(figure_bytes(run_dir / f.file)) << "\"><figcaption>" << html_escape(f.caption)
      << "</figcaption></figure>\n";

  // A landscape drawn into the run directory (`ftctune landscape`'s default place).
  for (const char* ext : {".png", ".svg"}) {
    const fs::path file = run_dir / "landscape" / (std::string("landscape") + ext);
    if (!fs::is_regular_file(file)) continue;
    // `run --force` keeps landscape/: one drawn before this run's gains may be of other gains'
    // job and path, so only a landscape drawn after the run is shown.
    std::error_code ec;
    if (fs::last_write_time(file, ec) < fs::last_write_time(run_dir / "gains.json", ec)) break;
    const std::optional<std::string> bytes = read_file(file);
    if (!bytes) continue;
    h << "<h2>Landscape</h2>\n<figure><img alt=\"objective landscape\" src=\"data:image/"
      << (ext == std::string(".png") ? "png" : "svg+xml") << ";base64," << base64(*bytes)
      << "\"><figcaption>The objective over a grid of two tuned parameters, from "
         "<code>ftctune landscape</code> (landscape/landscape"
      << ext
      << "). It shows whether the optimum is a basin or a ridge and "
         "whether the search bounds cut it off.</figcaption></figure>\n";
    break;
  }

  {
    const json sha = gains.value(json::json_pointer("/job/sha256"), json(""));
    evaluation_section(run_dir, job, sha.is_string() ? sha.get<std::string>() : std::string(), h);
  }

  h << "<h2>Run</h2>\n<table>\n";
  for (auto it = run.begin(); it != run.end(); ++it)
    h << "<tr><td>" << html_escape(it.key()) << "</td><td>"
      << html_escape(it.value().is_string() ? it.value().get<std::string>() : it.value().dump())
      << "</td></tr>\n";
  h << "<tr><td>job SHA-256</td><td>" << html_escape(gains["job"].value("sha256", ""))
    << "</td></tr>\n"
    << "<tr><td>generator</td><td>" << html_escape(gains["generator"].dump())
    << "</td></tr>\n</table>\n";
  h << "<h2>Job</h2>\n<table class=\"settings\"><tr><th>setting</th><th>value</th></tr>\n";
  // In the file's order, which is the order the user wrote (or the loader resolved) them in.
  settings_rows(nlohmann::ordered_json::parse(job_text, nullptr, false), "", h);
  h << "</table>\n<details><summary>job.json as written</summary><pre>" << html_escape(job_text)
    << "</pre></details>\n</body></html>\n";
  return h.str();
}

}  // namespace ftc::tune::report_detail
