#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "ftc/sim/metrics.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "io/text.hpp"
#include "lanes/metric_lanes.hpp"
#include "plants/lane_host.hpp"
#include "short_job.hpp"

namespace {

using ftc::sim::ErrorIntegrals;
using ftc::sim::Metrics;
using ftc::sim::Scenario;
using ftc::sim::SimulationOptions;
using ftc::sim::Window;

// A hand-made trajectory of a plant with 2 axes and 2 actuators, Ts = 0.5 s, four samples
// (t = 0, 0.5, 1, 1.5), every value a small dyadic fraction so that each sum below is exact:
//   k  t    e = X1         u_d
//   0  0    ( 1, -2)       ( 3,  4)
//   1  0.5  ( 0.5, 0.5)    ( 0,  0)
//   2  1    (-1, 0)        ( 0, -2)
//   3  1.5  ( 0, 0.25)     (-1, -2)
struct Sample {
  double t;
  double e[2];
  double u[2];
};
const Sample kTrajectory[] = {
    {0.0, {1.0, -2.0}, {3.0, 4.0}},
    {0.5, {0.5, 0.5}, {0.0, 0.0}},
    {1.0, {-1.0, 0.0}, {0.0, -2.0}},
    {1.5, {0.0, 0.25}, {-1.0, -2.0}},
};

// A scenario of `duration` seconds with a fault at each onset (only the onsets matter here).
Scenario with_onsets(std::vector<double> onsets, double duration = 2.0) {
  Scenario s;
  s.duration = duration;
  for (double t : onsets) {
    ftc::sim::Fault f;
    f.onset = t;
    s.faults.push_back(f);
  }
  return s;
}

// The trajectory through the metrics of one simulated lane: set up by the host's MetricRows,
// accumulated by the kernel's MetricLanes (one lane, T = double), read back by MetricRows, as the
// closed loop does (lanes/closed_loop.hpp, plants/lane_host.hpp). `limits`: the command's
// [lo, hi] per actuator (else ± the scenario's saturation); `diverged_at`: the run stopped there.
struct Limits {
  double lo[2], hi[2];
};
Metrics measure(const Scenario& s, const SimulationOptions& o,
                std::span<const Sample> samples = kTrajectory,
                std::optional<Limits> limits = std::nullopt,
                std::optional<double> diverged_at = std::nullopt) {
  namespace detail = ftc::sim::detail;
  detail::LaneTask lane;
  lane.scenario = &s;
  lane.options = &o;
  if (limits)
    for (int j = 0; j < 2; ++j) {
      lane.lo[j] = limits->lo[j];
      lane.hi[j] = limits->hi[j];
    }
  detail::LaneTask* lanes[1] = {&lane};
  detail::MetricSetup<2> setup;
  detail::MetricRows<2> rows;
  rows.set(lanes, 1, setup);
  detail::MetricLanes<double, 2, 2> acc(setup);
  std::array<double, 2> u_prev{};
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Sample& p = samples[k];
    const std::array<double, 4> x = {p.e[0], p.e[1], 7.0, -7.0};  // X2 takes no part
    const std::array<double, 2> u = {p.u[0], p.u[1]};
    acc.sample(true, static_cast<std::int64_t>(k), 0.5, x, u, u_prev);
    u_prev = u;
  }
  detail::MetricsOut out;
  rows.outputs(out);
  acc.write(0, setup.first_onset[0], out);
  return rows.read(0, out, o, s, diverged_at);
}

Metrics accumulate(Window window, std::vector<Window> extra, std::vector<double> onsets) {
  SimulationOptions o;
  o.window = window;
  o.extra_windows = std::move(extra);
  return measure(with_onsets(std::move(onsets)), o);
}

}  // namespace

TEST(Metrics, OneLaneAccumulatorMatchesHandComputedTrajectory) {
  // ‖e‖² per sample: 5, 0.5, 1, 0.0625; Σ|e_i|: 3, 1, 1, 0.25.
  // Whole run: ise = 0.5 (5 + 0.5 + 1 + 0.0625) = 3.28125, iae = 0.5 (3 + 1 + 1 + 0.25) = 2.625,
  //            itae = 0.5 (0·3 + 0.5·1 + 1·1 + 1.5·0.25) = 0.9375.
  // Window [0.5, 1.5): samples 1, 2: ise = 0.5 (0.5 + 1) = 0.75, iae = 0.5 (1 + 1) = 1,
  //            itae = 0.5 (0.5 + 1) = 0.75.
  // max |u_d| = 4; total variation ‖(−3,−4)‖ + ‖(0,−2)‖ + ‖(−1,0)‖ = 5 + 2 + 1 = 8.
  // Peak ‖e‖ from t = 0.75 on: samples 2, 3: max(1, 0.25) = 1; from t = 2: never (NaN);
  // from t = 0: sqrt(5).
  const Metrics m = accumulate(Window{}, {Window{0.5, 1.5}}, {0.75, 2.0, 0.0});
  EXPECT_EQ(m.errors.ise, 3.28125);
  EXPECT_EQ(m.errors.iae, 2.625);
  EXPECT_EQ(m.errors.itae, 0.9375);
  ASSERT_EQ(m.extra.size(), 1u);
  EXPECT_EQ(m.extra[0].ise, 0.75);
  EXPECT_EQ(m.extra[0].iae, 1.0);
  EXPECT_EQ(m.extra[0].itae, 0.75);
  EXPECT_EQ(m.max_abs_u, 4.0);
  EXPECT_EQ(m.control_tv, 8.0);
  ASSERT_EQ(m.peak_error_after_fault.size(), 3u);
  EXPECT_EQ(m.peak_error_after_fault[0], 1.0);
  EXPECT_TRUE(std::isnan(m.peak_error_after_fault[1]));
  EXPECT_EQ(m.peak_error_after_fault[2], std::sqrt(5.0));
  EXPECT_FALSE(m.diverged);
}

TEST(Metrics, WindowIsHalfOpen) {
  // [1, 1.5) holds sample 2 only (t = 1), not sample 3 (t = 1.5): ise = 0.5 · 1, itae = 0.5 · 1.
  const Metrics m = accumulate(Window{1.0, 1.5}, {}, {});
  EXPECT_EQ(m.errors.ise, 0.5);
  EXPECT_EQ(m.errors.iae, 0.5);
  EXPECT_EQ(m.errors.itae, 0.5);
  EXPECT_TRUE(m.extra.empty());
}

TEST(Metrics, DivergedRunHasInfiniteErrorIntegralsInEveryWindow) {
  SimulationOptions o;
  o.extra_windows = {Window{0.0, 1.0}};
  const Sample first[] = {{0.0, {1.0, 0.0}, {1.0, 1.0}}};
  const Metrics m = measure(with_onsets({}), o, first, std::nullopt, 0.5);
  constexpr double inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(m.diverged);
  EXPECT_EQ(m.diverged_at, 0.5);
  EXPECT_EQ(m.errors.ise, inf);
  EXPECT_EQ(m.errors.itae, inf);
  EXPECT_EQ(m.extra[0].iae, inf);
  EXPECT_EQ(m.max_abs_u, 1.0);  // what was reached before
}

TEST(Metrics, LaneThatStoppedCountingKeepsItsSums) {
  // The kernel's accumulators with a false mask (a lane that has diverged) change nothing;
  // with a true one they add as the one-lane run does.
  namespace lane = ftc::sim::lane;
  const double x[2] = {3.0, -4.0}, u[2] = {-6.0, 8.0}, u_prev[2] = {0.0, 0.0};
  const lane::ErrorNorms<double> e = lane::error_norms<2, double>(x);
  EXPECT_EQ(e.sq, 25.0);
  EXPECT_EQ(e.abs, 7.0);
  const lane::ErrorTerms<double> d = lane::error_terms(0.5, 0.5 * 2.0, e);
  for (const bool counting : {false, true}) {
    double max_abs_u = 0.5, tv = 0.25, peak = 1.0;
    lane::WindowSums<double> w;
    w.ise = 1.0;
    w.iae = 2.0;
    w.itae = 3.0;
    lane::add_error_terms<double>(counting, d, w);
    const double ise = w.ise, iae = w.iae, itae = w.itae;
    lane::add_max_abs_u<2, double>(counting, u, max_abs_u);
    lane::add_control_tv<2, double>(counting, u, u_prev, tv);
    lane::add_peak<double>(counting, std::sqrt(e.sq), peak);
    EXPECT_EQ(ise, counting ? 13.5 : 1.0);
    EXPECT_EQ(iae, counting ? 5.5 : 2.0);
    EXPECT_EQ(itae, counting ? 10.0 : 3.0);
    EXPECT_EQ(max_abs_u, counting ? 8.0 : 0.5);
    EXPECT_EQ(tv, counting ? 10.25 : 0.25);
    EXPECT_EQ(peak, counting ? 5.0 : 1.0);
  }
}

namespace {

// A record with every kind of value: extra windows, faults, an unreached peak (NaN), a window
// that never ends (+inf).
Metrics sample_record() {
  Metrics m = accumulate(Window{0.5}, {Window{0.0, 1.0}, Window{1.0, 2.0}}, {0.75, 2.0});
  m.diverged = true;
  m.diverged_at = 1.25;
  return m;
}

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

void expect_same_record(const Metrics& a, const Metrics& b) {
  using ftc::sim::MetricScope;
  EXPECT_EQ(bits(a.window.t0), bits(b.window.t0));
  EXPECT_EQ(bits(a.window.t1), bits(b.window.t1));
  ASSERT_EQ(a.extra.size(), b.extra.size());
  ASSERT_EQ(a.extra_windows.size(), b.extra_windows.size());
  for (std::size_t i = 0; i < a.extra_windows.size(); ++i) {
    EXPECT_EQ(bits(a.extra_windows[i].t0), bits(b.extra_windows[i].t0));
    EXPECT_EQ(bits(a.extra_windows[i].t1), bits(b.extra_windows[i].t1));
  }
  for (const ftc::sim::MetricField& f : ftc::sim::kMetricFields) {
    SCOPED_TRACE(std::string(f.name));
    switch (f.scope) {
      case MetricScope::window:
        EXPECT_EQ(bits(a.errors.*f.in_window), bits(b.errors.*f.in_window));
        for (std::size_t i = 0; i < a.extra.size(); ++i)
          EXPECT_EQ(bits(a.extra[i].*f.in_window), bits(b.extra[i].*f.in_window));
        break;
      case MetricScope::run:
        EXPECT_EQ(bits(a.*f.per_run), bits(b.*f.per_run));
        break;
      case MetricScope::fault:
        ASSERT_EQ((a.*f.per_fault).size(), (b.*f.per_fault).size());
        for (std::size_t i = 0; i < (a.*f.per_fault).size(); ++i)
          EXPECT_EQ(bits((a.*f.per_fault)[i]), bits((b.*f.per_fault)[i]));
        break;
    }
  }
  EXPECT_EQ(a.diverged, b.diverged);
  EXPECT_EQ(bits(a.diverged_at), bits(b.diverged_at));
}

}  // namespace

TEST(Metrics, RecordRoundTripsThroughTheWireFormat) {
  const Metrics m = sample_record();
  std::vector<char> bytes = {'x'};  // a record inside a message
  ftc::sim::append_metrics_wire(bytes, m);
  const std::size_t end = bytes.size();
  bytes.push_back('y');
  std::size_t pos = 1;
  const Metrics back = ftc::sim::read_metrics_wire(bytes, pos);
  EXPECT_EQ(pos, end);
  expect_same_record(m, back);
  // Every prefix of the record is a malformed message, not a read past its end.
  for (std::size_t n = 1; n < end; ++n) {
    const std::vector<char> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    std::size_t p = 1;
    EXPECT_THROW(ftc::sim::read_metrics_wire(cut, p), std::runtime_error) << n;
  }
}

TEST(Metrics, RecordRoundTripsThroughJson) {
  // metrics_json writes every field of the record under its name (non-finite values as null),
  // the extra windows' fields in "segments"; read back by the same description it gives the
  // record.
  using ftc::sim::MetricScope;
  const Metrics m = sample_record();
  const nlohmann::json j = nlohmann::json::parse(ftc::tune::metrics_json(m).dump());
  const auto number = [](const nlohmann::json& v) {
    return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
  };
  Metrics back;
  back.window = {j.at("window")[0].get<double>(), number(j.at("window")[1])};
  back.extra.resize(j.at("segments").size());
  for (const nlohmann::json& s : j.at("segments"))
    back.extra_windows.push_back({s.at("window")[0].get<double>(), number(s.at("window")[1])});
  for (const ftc::sim::MetricField& f : ftc::sim::kMetricFields) {
    const std::string name(f.name);
    switch (f.scope) {
      case MetricScope::window:
        back.errors.*f.in_window = number(j.at(name));
        for (std::size_t i = 0; i < back.extra.size(); ++i)
          back.extra[i].*f.in_window = number(j.at("segments")[i].at(name));
        break;
      case MetricScope::run:
        back.*f.per_run = number(j.at(name));
        break;
      case MetricScope::fault:
        for (const nlohmann::json& v : j.at(name)) (back.*f.per_fault).push_back(number(v));
        break;
    }
  }
  back.diverged = j.at("diverged").get<bool>();
  back.diverged_at = j.at("diverged_at").get<double>();
  // The window's end +inf is written as null: read back as NaN, compared as +inf.
  EXPECT_EQ(m.window.t1, std::numeric_limits<double>::infinity());
  EXPECT_TRUE(j.at("window")[1].is_null());
  back.window.t1 = m.window.t1;
  expect_same_record(m, back);
  EXPECT_EQ(j.at("segments").size(), 2u);
  EXPECT_EQ(j.at("ise"), m.errors.ise);
}

namespace {

// The cells of a Markdown table row, trimmed.
std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  for (std::size_t i = 1; i < line.size(); ++i) {
    if (line[i] == '|' && line[i - 1] != '\\') {
      const std::size_t a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
      out.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
      cell.clear();
    } else {
      cell += line[i];
    }
  }
  return out;
}

}  // namespace

TEST(Metrics, RecordRoundTripsThroughMarkdown) {
  // comparison.md's table: read back by column name, each cell is the field's value as
  // format_number writes it (4 significant digits), every field of the description has its
  // columns, and a diverged row is marked.
  using ftc::sim::MetricScope;
  const Metrics m = sample_record();
  const std::string table = ftc::tune::metrics_markdown_table({{"tuned", &m}});
  std::vector<std::string> lines;
  for (std::size_t a = 0, b; (b = table.find('\n', a)) != std::string::npos; a = b + 1)
    lines.push_back(table.substr(a, b - a));
  ASSERT_EQ(lines.size(), 3u);
  const std::vector<std::string> head = cells(lines[0]), sep = cells(lines[1]),
                                 row = cells(lines[2]);
  // controller; ise, iae, itae, max|u|, tv; ISE per extra window (2); peak per fault (2): the
  // fields of the tables
  ASSERT_EQ(head.size(), 10u);
  ASSERT_EQ(sep.size(), head.size());
  ASSERT_EQ(row.size(), head.size());
  EXPECT_EQ(row[0], "tuned (diverged)");
  const auto column = [&](const std::string& name) -> std::string {
    for (std::size_t i = 0; i < head.size(); ++i)
      if (head[i] == name) return row[i];
    ADD_FAILURE() << "no column " << name;
    return {};
  };
  const auto text = [](double v) { return ftc::tune::detail::format_number(v); };
  for (const ftc::sim::MetricField& f : ftc::sim::kMetricFields) {
    const std::string label(f.label);
    if (!f.in_tables) {  // in the JSON documents and evaluate's files only
      for (const std::string& h : head) EXPECT_EQ(h.find(label), std::string::npos) << h;
      continue;
    }
    switch (f.scope) {
      case MetricScope::window:
        EXPECT_EQ(column(label), text(m.errors.*f.in_window));
        if (f.column_per_extra_window) {
          EXPECT_EQ(column(label + " [0, 1)"), text(m.extra[0].*f.in_window));
          EXPECT_EQ(column(label + " [1, 2)"), text(m.extra[1].*f.in_window));
        }
        break;
      case MetricScope::run:
        EXPECT_EQ(column(label), text(m.*f.per_run));
        break;
      case MetricScope::fault:
        for (std::size_t k = 0; k < (m.*f.per_fault).size(); ++k)
          EXPECT_EQ(column(label + " " + std::to_string(k + 1)), text((m.*f.per_fault)[k]));
        break;
    }
  }
  // Parsed back: the window [0.5, inf) leaves out sample 0: ISE = 0.5 (0.5 + 1 + 0.0625).
  EXPECT_NEAR(std::stod(column("ISE")), 0.78125, 1e-4);
  EXPECT_EQ(column("peak ‖e‖ after fault 2"), "–");  // never reached
}

namespace {

// The lines of a text, each split at `sep` (no quoting: the test's fields have none).
std::vector<std::vector<std::string>> split_rows(const std::string& text, char sep) {
  std::vector<std::vector<std::string>> rows;
  for (std::size_t a = 0, b; (b = text.find('\n', a)) != std::string::npos; a = b + 1) {
    std::vector<std::string> row;
    const std::string line = text.substr(a, b - a);
    for (std::size_t c = 0, d;; c = d + 1) {
      d = line.find(sep, c);
      row.push_back(line.substr(c, d == std::string::npos ? std::string::npos : d - c));
      if (d == std::string::npos) break;
    }
    rows.push_back(row);
  }
  return rows;
}

// An evaluation of table1-short's one scenario by two controllers: a finite record and a
// diverged one (its integrals +inf), each with two fault onsets, the second never reached (NaN).
ftc::tune::EvaluationResult sample_evaluation() {
  ftc::tune::EvaluationResult r;
  r.job = ftc::tune::parse_job(ftc::testing::short_table1_job(), "table1-short");
  int k = 0;
  for (const Metrics& m : {accumulate(Window{0.5}, {}, {0.75, 2.0}), sample_record()}) {
    ftc::tune::EvaluatedController c;
    c.label = "c" + std::to_string(++k);
    c.source = "job";
    c.controller = r.job.controller;
    ftc::tune::MemberResult x;
    x.scenario = r.job.scenarios[0].name;
    x.objective = m.errors.ise;
    x.metrics = ftc::sim::MetricValues::of(m);
    x.diverged = m.diverged;
    c.members.push_back(x);
    r.controllers.push_back(c);
  }
  return r;
}

}  // namespace

TEST(Metrics, RecordRoundTripsThroughEvaluationCsvAndJson) {
  // evaluation.csv and evaluation.json write every field of the record in the objective's
  // window by the description: read back by column or key name, each member gives the values it
  // was written from, to the bit (non-finite values: "inf" / "nan" in the CSV, null in JSON).
  using ftc::sim::MetricScope;
  const ftc::tune::EvaluationResult r = sample_evaluation();
  std::string csv, js;
  ftc::tune::write_evaluation_csv(r, [&](std::string_view s) { csv.append(s); });
  ftc::tune::write_evaluation_json(r, [&](std::string_view s) { js.append(s); });
  const auto rows = split_rows(csv, ',');
  ASSERT_EQ(rows.size(), 3u);
  const std::vector<std::string>& head = rows[0];
  const nlohmann::json doc = nlohmann::json::parse(js);
  for (std::size_t k = 0; k < 2; ++k) {
    const ftc::sim::MetricValues& want = r.controllers[k].members[0].metrics;
    ASSERT_EQ(rows[k + 1].size(), head.size());
    const nlohmann::json& member = doc.at("controllers")[k].at("members")[0];
    std::size_t checked = 0;
    for (std::size_t f = 0; f < ftc::sim::kMetricFieldCount; ++f) {
      const ftc::sim::MetricField& field = ftc::sim::kMetricFields[f];
      SCOPED_TRACE(std::string(field.name) + " of member " + std::to_string(k));
      const std::span<const double> v = want.field(f);
      ASSERT_EQ(v.size(), field.scope == MetricScope::fault ? 2u : 1u);
      // CSV: the column under the field's name; a fault field's values split at ';'.
      std::size_t col = 0;
      while (col < head.size() && head[col] != field.name) ++col;
      ASSERT_LT(col, head.size());
      const std::vector<std::string> cell = split_rows(rows[k + 1][col] + "\n", ';')[0];
      ASSERT_EQ(cell.size(), v.size());
      // JSON: the value under the name, an array for a fault field.
      const nlohmann::json j = member.at(std::string(field.name));
      ASSERT_EQ(j.is_array(), field.scope == MetricScope::fault);
      for (std::size_t i = 0; i < v.size(); ++i) {
        EXPECT_EQ(bits(std::stod(cell[i])), bits(v[i])) << cell[i];
        const nlohmann::json& ji = j.is_array() ? j[i] : j;
        if (std::isfinite(v[i]))
          EXPECT_EQ(bits(ji.get<double>()), bits(v[i]));
        else
          EXPECT_TRUE(ji.is_null()) << ji;
        ++checked;
      }
    }
    EXPECT_EQ(checked, want.values.size());
    EXPECT_EQ(member.at("diverged").get<bool>(), k == 1);
  }
  // The values themselves: the finite member's ISE over [0.5, inf) and its first peak (from
  // t = 0.75 on: ‖e‖ = 1 at t = 1, 0.25 at t = 1.5).
  EXPECT_EQ(r.controllers[0].members[0].metrics.get("ise"), 0.78125);
  EXPECT_EQ(r.controllers[0].members[0].metrics.field(5)[0], 1.0);
  EXPECT_TRUE(std::isnan(r.controllers[0].members[0].metrics.field(5)[1]));
  EXPECT_EQ(rows[1].back(), "0");
  EXPECT_EQ(rows[2].back(), "1");
}

TEST(Metrics, RecordSaysHowEachFieldCombinesOverScenarios) {
  using ftc::sim::metric_field;
  using ftc::sim::over_scenarios;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> v = {0.5, nan, 2.0, 0.25};
  // Integrals and the control TV add up; peaks take the largest value reached.
  EXPECT_EQ(over_scenarios(metric_field("ise"), std::vector<double>{0.5, 2.0, 0.25}), 2.75);
  EXPECT_EQ(over_scenarios(metric_field("control_tv"), std::vector<double>{1.0, 2.0}), 3.0);
  EXPECT_EQ(over_scenarios(metric_field("max_abs_u"), v), 2.0);
  EXPECT_EQ(over_scenarios(metric_field("peak_error_after_fault"), v), 2.0);
  EXPECT_TRUE(
      std::isnan(over_scenarios(metric_field("peak_error_after_fault"), std::vector<double>{nan})));
  EXPECT_THROW(metric_field("no_such_metric"), std::logic_error);
  // Every field of the tables is in the note under them with its unit, the control TV with its
  // definition; the others are not.
  const std::string note = ftc::sim::units_note(false);
  for (const ftc::sim::MetricField& f : ftc::sim::kMetricFields)
    EXPECT_EQ(
        note.find(ftc::sim::plain_label(f) + " in " + std::string(f.unit)) != std::string::npos,
        f.in_tables)
        << f.name << ": " << note;
  EXPECT_EQ(over_scenarios(metric_field("saturation_fraction"), v), 2.75 / 3.0);  // the mean
  EXPECT_NE(note.find("control TV = Σ‖u_k − u_{k−1}‖ (chattering)"), std::string::npos) << note;
  EXPECT_NE(ftc::sim::units_note(true).find("max \\|u_d\\| in"), std::string::npos);
}

TEST(Metrics, WindowMetricsMatchHandComputedTrajectory) {
  // The trajectory above with command limits [-3, 3] and [-2, 2] (at a limit: samples 0, 2 and
  // 3), a run of 2 s, the faults at 0.75 s and 2 s:
  //   k  t    ‖e‖²     ‖u‖²   max|u_j|
  //   0  0    5        25     4
  //   1  0.5  0.5      0      0
  //   2  1    1        4      2
  //   3  1.5  0.0625   5      2
  const auto run = [](Window w, double threshold, double tail, std::vector<double> onsets) {
    SimulationOptions o;
    o.window = w;
    o.extra_windows = {Window{0.0, 1.0}};
    o.metrics.settling_threshold = threshold;
    o.metrics.steady_state_tail = tail;
    return measure(with_onsets(std::move(onsets)), o, kTrajectory,
                   Limits{{-3.0, -2.0}, {3.0, 2.0}});
  };
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  const Metrics m = run(Window{}, 0.8, 1.0, {2.0, 0.75});
  // Whole run: energy 0.5 (25 + 0 + 4 + 5), peak 4, 3 of 4 samples at a limit.
  EXPECT_EQ(m.errors.control_energy, 17.0);
  EXPECT_EQ(m.errors.peak_command, 4.0);
  EXPECT_EQ(m.errors.saturation_fraction, 0.75);
  // From the first fault (0.75 s, the earliest onset, not the first listed): ‖e‖ = 1 ≥ 0.8 at
  // 1 s, 0.25 < 0.8 from 1.5 s on: settled 0.75 s after the fault.
  EXPECT_EQ(m.errors.settling_time, 0.75);
  // The tail [min(inf, 2) - 1, inf) = [1, inf): samples 2 and 3, mean ‖e‖ = (1 + 0.25) / 2.
  EXPECT_EQ(m.errors.steady_state_error, 0.625);
  // The extra window [0, 1): samples 0 and 1; no sample after the fault (NaN settling time);
  // its tail [0, 1): both samples.
  const ErrorIntegrals& x = m.extra[0];
  EXPECT_EQ(x.control_energy, 12.5);
  EXPECT_EQ(x.peak_command, 4.0);
  EXPECT_EQ(x.saturation_fraction, 0.5);
  EXPECT_TRUE(std::isnan(x.settling_time));
  EXPECT_EQ(x.steady_state_error, (std::sqrt(5.0) + std::sqrt(0.5)) / 2.0);
  // A window from 0.5 s: energy 0.5 · 9, peak 2, 2 of 3 samples at a limit.
  const Metrics late = run(Window{0.5}, 2.0, 0.5, {0.75});
  EXPECT_EQ(late.errors.control_energy, 4.5);
  EXPECT_EQ(late.errors.peak_command, 2.0);
  EXPECT_EQ(late.errors.saturation_fraction, 2.0 / 3.0);
  EXPECT_EQ(late.errors.settling_time, 0.25);       // below 2 from the first sample after the fault
  EXPECT_EQ(late.errors.steady_state_error, 0.25);  // the tail [1.5, inf): sample 3
  // Not below 0.2 by the window's end: +inf; no threshold, tail or fault: NaN.
  EXPECT_EQ(run(Window{}, 0.2, nan, {0.75}).errors.settling_time, inf);
  const Metrics none = run(Window{}, nan, nan, {0.75});
  EXPECT_TRUE(std::isnan(none.errors.settling_time));
  EXPECT_TRUE(std::isnan(none.errors.steady_state_error));
  EXPECT_TRUE(std::isnan(run(Window{}, 0.8, nan, {}).errors.settling_time));
  // Without limits no sample is at one.
  EXPECT_EQ(measure(with_onsets({}), SimulationOptions{}).errors.saturation_fraction, 0.0);
  // A diverged run: every window metric +inf.
  SimulationOptions o;
  o.extra_windows = {Window{0.0, 1.0}};
  const Metrics d = measure(with_onsets({0.75}), o, kTrajectory, std::nullopt, 0.5);
  for (const ftc::sim::MetricField& f : ftc::sim::kMetricFields)
    if (f.scope == ftc::sim::MetricScope::window) {
      EXPECT_EQ(d.errors.*f.in_window, inf) << f.name;
      EXPECT_EQ(d.extra[0].*f.in_window, inf) << f.name;
    }
}
