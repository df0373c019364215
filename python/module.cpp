// The native half of the ftctune Python module (ftctune._core): every call from Python into the
// library is in this file. python/ftctune/__init__.py is the public face: it turns what these
// functions return (numbers, numpy arrays, JSON and CSV text of the CLI's own documents) into
// dicts and pandas DataFrames. docs/python.md describes the API.
//
// Long calls release the GIL and run their simulations through PythonEvaluator, which hands the
// batch to TBB a slice at a time and looks for a pending signal (Ctrl-C) between slices; a
// Python exception (KeyboardInterrupt, or one raised by a callback) stops the call and is
// raised once the GIL is back.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "ftc/runtime/controller_json.hpp"
#include "ftc/runtime/gains.hpp"
#include "ftc/runtime/json_reader.hpp"
#include "ftc/sim/controllers.hpp"
#include "ftc/sim/input_error.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/sim/plants.hpp"
#include "ftc/tune/api/api.hpp"
#include "ftc/tune/api/run_directory.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/job/ensemble.hpp"
#include "ftc/tune/job/job.hpp"
#include "ftc/tune/problem/problem.hpp"
#include "ftc/tune/run/documents.hpp"
#include "ftc/tune/run/evaluate.hpp"
#include "ftc/tune/run/memory_budget.hpp"
#include "ftc/tune/run/tuning_run.hpp"
#include "ftc/version.hpp"

namespace py = pybind11;
using nlohmann::json;

namespace {

namespace fs = std::filesystem;
using ftc::FieldError;
using ftc::InputError;
namespace tune = ftc::tune;
namespace sim = ftc::sim;

// A Python exception is set on this thread: raise it once the GIL is held again. Not a
// std::exception, so that nothing on the way takes it for a library error.
struct PythonErrorPending {};

// Raises the pending Python exception (the GIL is held).
[[noreturn]] void raise_pending() { throw py::error_already_set(); }

// The interpreter exiting while a call still runs in a daemon thread: Python ends such a thread
// when it next takes the GIL by unwinding its stack, which through the library's C++ frames
// aborted the process (SIGABRT, exit 134). An atexit hook (registered at import, run before
// the interpreter starts to finalise) marks the exit; from then on a call in a daemon thread
// that would take the GIL parks its thread instead, and the process's exit ends it without
// unwinding. The hook waits, with the GIL released, until every such call has parked or
// returned: a call looks between slices of about 0.4 s, so this takes under a second. Only
// daemon threads park: when atexit hooks run, every other thread has been joined but the one
// running the hooks, whose calls (an atexit hook may simulate) go on as ever. (An atexit hook
// that waits for a daemon thread still inside a call waits for ever: it is parked.)
std::atomic<bool> g_exiting{false};
std::atomic<int> g_running{0};  // calls inside without_gil in daemon threads
std::atomic<int> g_parked{0};
thread_local bool t_daemon = false;  // this thread's call runs in a daemon thread
constexpr double kExitWaitSeconds = 5.0;

[[noreturn]] void park() {
  ++g_parked;
  for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

// Before a call's thread takes the GIL.
void park_if_exiting() {
  if (t_daemon && g_exiting.load()) park();
}

void on_interpreter_exit() {  // atexit, with the GIL
  g_exiting = true;
  py::gil_scoped_release release;
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::duration<double>(kExitWaitSeconds);
  while (g_running.load() > g_parked.load() && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

// Runs f with the GIL released; a PythonErrorPending thrown inside is raised as its exception.
template <class F>
auto without_gil(F&& f) -> decltype(f()) {
  // With the GIL held: whether this thread is a daemon (one the interpreter may exit under).
  const bool daemon =
      py::module_::import("threading").attr("current_thread")().attr("daemon").cast<bool>();
  struct Running {
    bool daemon, outer;
    explicit Running(bool d) : daemon(d), outer(t_daemon) {
      t_daemon = d;
      if (daemon) ++g_running;
    }
    ~Running() {
      if (daemon) --g_running;
      t_daemon = outer;
    }
  } running(daemon);
  try {
    py::gil_scoped_release release;
    // Destroyed before `release` takes the GIL back, also when f throws.
    struct ParkAtExit {
      ~ParkAtExit() { park_if_exiting(); }
    } park_at_exit;
    return f();
  } catch (const PythonErrorPending&) {
    raise_pending();
  }
}

// From a thread without the GIL: stops the call when a signal handler raised (Ctrl-C).
void check_signals() {
  park_if_exiting();
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) throw PythonErrorPending{};
}

// TBB, a slice of the batch at a time (about 0.4 s each), with a look for
// Ctrl-C between slices. Each task's result does not depend on which slice or pack it ran in
// (batch_evaluator.hpp), so the values are those of `ftctune run`'s evaluator to the bit.
class PythonEvaluator final : public tune::BatchEvaluator {
 public:
  explicit PythonEvaluator(int threads) : inner_(threads) {}
  std::vector<tune::TaskResult> run(const tune::SimulationBatch& batch) override {
    std::vector<tune::TaskResult> out;
    out.reserve(batch.tasks.size());
    const std::size_t min_slice = 64 * static_cast<std::size_t>(std::max(1, concurrency()));
    for (std::size_t k = 0; k < batch.tasks.size();) {
      check_signals();
      const std::size_t n = std::min(std::max(slice_, min_slice), batch.tasks.size() - k);
      const auto t0 = std::chrono::steady_clock::now();
      std::vector<tune::TaskResult> part =
          inner_.run({batch.set, batch.candidates, batch.tasks.subspan(k, n), batch.record_every});
      const double dt =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      for (tune::TaskResult& r : part) out.push_back(std::move(r));
      k += n;
      if (n >= slice_) {
        const double rate = static_cast<double>(n) / std::max(dt, 1e-6);
        slice_ = static_cast<std::size_t>(std::clamp(rate * kSliceSeconds, 1.0, 1e7));
      }
    }
    check_signals();
    return out;
  }
  int concurrency() const override { return inner_.concurrency(); }
  std::string name() const override { return inner_.name(); }

 private:
  static constexpr double kSliceSeconds = 0.4;
  tune::TbbEvaluator inner_;
  std::size_t slice_ = 0;  // grows to the tasks of kSliceSeconds after the first slice
};

int threads_of(const std::optional<int>& threads) {
  if (threads && (*threads < 0 || *threads > 4096))
    throw InputError("threads", "", "must be in [0, 4096] (0: one per core)");
  return threads.value_or(0);
}

py::object json_module() { return py::module_::import("json"); }

// Python values to JSON through the json module's text (numbers round-trip exactly).
json to_json_value(const py::handle& value, const std::string& what) {
  std::string text;
  try {
    text = json_module().attr("dumps")(value, py::arg("allow_nan") = false).cast<std::string>();
  } catch (py::error_already_set& e) {
    throw InputError(what, "", std::string("is not JSON: ") + e.what());
  }
  return json::parse(text);
}

struct Job {
  tune::Job job;
  std::string source;  // the file, or "<dict>"
};

// The module's types are made only by its functions (load_job, problem, tune), whose results
// pybind11 builds without the type's __new__. Their __new__ refuses: an object it made has no C++
// value (no __init__ builds one), and its first method call read raw memory (a crash).
PyObject* refuse_new(PyTypeObject* type, PyObject*, PyObject*) {
  PyErr_Format(PyExc_TypeError,
               "%s objects cannot be made directly: use ftctune.load_job, ftctune.Problem and "
               "ftctune.tune",
               type->tp_name);
  return nullptr;
}
template <class T>
void made_by_functions(py::class_<T>& cls) {
  reinterpret_cast<PyTypeObject*>(cls.ptr())->tp_new = &refuse_new;
}

Job load_job(const py::object& from) {
  if (py::isinstance<py::dict>(from)) {
    // As text, so that the keys keep the dict's order (that of tuning.parameters is the
    // decision vector's); a scenarios file it names is read relative to the working directory.
    std::string text;
    try {
      text = json_module().attr("dumps")(from, py::arg("allow_nan") = false).cast<std::string>();
    } catch (py::error_already_set& e) {
      throw InputError("<dict>", "", std::string("is not JSON: ") + e.what());
    }
    return {tune::parse_job_text(text, "<dict>", fs::current_path()), "<dict>"};
  }
  const std::string path = py::module_::import("os").attr("fspath")(from).cast<std::string>();
  return {tune::load_job(path), path};
}

void require_tuning(const Job& j, const char* what) {
  if (!j.job.tuning)
    throw InputError(j.source, "/tuning",
                     std::string("is required by ") + what + " (what should be tuned?)");
}

// X as rows of the problem's dimension: (n, d), or (d,) as one row.
struct Rows {
  std::vector<std::vector<double>> rows;
  bool single = false;
};

Rows rows_of(const py::array_t<double, py::array::c_style | py::array::forcecast>& x,
             const tune::TuningProblem& p) {
  const std::size_t d = p.space().dimension();
  Rows r;
  if (x.ndim() == 1) {
    r.single = true;
    if (static_cast<std::size_t>(x.shape(0)) != d)
      throw InputError(
          "X", "",
          "has " + std::to_string(x.shape(0)) + " values, the problem " + std::to_string(d));
    r.rows.emplace_back(x.data(), x.data() + d);
  } else if (x.ndim() == 2) {
    if (static_cast<std::size_t>(x.shape(1)) != d)
      throw InputError("X", "",
                       "has " + std::to_string(x.shape(1)) + " columns, the problem " +
                           std::to_string(d) + " parameters");
    for (py::ssize_t i = 0; i < x.shape(0); ++i)
      r.rows.emplace_back(x.data(i, 0), x.data(i, 0) + d);
  } else {
    throw InputError("X", "", "must have shape (n, d) or (d,)");
  }
  // As TuningProblem::objective: inside the tuning bounds, finite.
  std::vector<FieldError> errs;
  const auto& params = p.job().tuning->parameters;
  for (std::size_t i = 0; i < r.rows.size(); ++i)
    for (std::size_t j = 0; j < d; ++j) {
      const double v = r.rows[i][j];
      if (v >= params[j].lower && v <= params[j].upper) continue;
      std::string message = params[j].name;
      message.append(" = ").append(ftc::json_io::number_text(v, 17));
      message.append(" is outside its bounds [").append(ftc::json_io::number_text(params[j].lower));
      message.append(", ").append(ftc::json_io::number_text(params[j].upper)).append("]");
      std::string path = "/";
      path.append(std::to_string(i)).append("/").append(std::to_string(j));
      errs.push_back({std::move(path), std::move(message)});
      if (errs.size() >= 20) break;
    }
  ftc::throw_if_errors("X", std::move(errs));
  return r;
}

// The job's problem with every scenario held, its ensemble's members included (a run's problem
// generates them as they are simulated and keeps only the listed scenarios' metrics), so that
// metrics() has a row for each member.
tune::TuningProblem holding_every_scenario(const tune::Job& job) {
  std::vector<sim::Scenario> all = job.scenarios;
  for (sim::Scenario& m : tune::expand_ensemble(job)) all.push_back(std::move(m));
  return tune::TuningProblem(job, std::move(all), job.scenarios.size());
}

// A job as a tuning problem, with its evaluator (threads as `ftctune run --threads`).
// Memory by design, as `ftctune run` checks it: the members held as listed scenarios, and
// `candidates` scored at once with their metrics.
void check_memory(const tune::Job& job, double candidates, const std::string& what,
                  bool metrics = false) {
  tune::check_memory_need(tune::estimated_scoring_bytes(job, candidates, true, metrics),
                          tune::memory_budget_bytes(), job.name, what);
}

struct Problem {
  Problem(const Job& j, std::optional<int> threads)
      : problem((require_tuning(j, "Problem"), check_memory(j.job, 1, "a Problem of this job"),
                 holding_every_scenario(j.job))),
        evaluator(threads_of(threads)) {}
  tune::TuningProblem problem;
  PythonEvaluator evaluator;
  // One batch at a time through the evaluator: Python threads may share a Problem.
  std::mutex busy;

  std::vector<tune::CandidateOutcome> outcomes(const Rows& r, bool metrics) {
    check_memory(problem.job(), static_cast<double>(r.rows.size()),
                 std::to_string(r.rows.size()) + " rows of X at once", metrics);
    std::vector<sim::ControllerConfig> controllers;
    controllers.reserve(r.rows.size());
    for (const auto& x : r.rows) controllers.push_back(problem.controller_with(x));
    return without_gil([&] {
      const std::lock_guard<std::mutex> lock(busy);
      return problem.evaluate(controllers, evaluator);
    });
  }

  py::object objective(const py::array_t<double, py::array::c_style | py::array::forcecast>& x) {
    const Rows r = rows_of(x, problem);
    const std::vector<tune::CandidateOutcome> out = outcomes(r, false);
    py::array_t<double> values(static_cast<py::ssize_t>(out.size()));
    auto v = values.mutable_unchecked<1>();
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (!out[i].error.empty()) throw InputError("X", "/" + std::to_string(i), out[i].error);
      v(static_cast<py::ssize_t>(i)) = out[i].evaluation.objective;
    }
    if (r.single) return py::float_(v(0));
    return values;
  }

  // Columns of one row per (candidate, scenario): every metric of the metrics record, the
  // objective window's and each fault segment's (<metric>_segment<k>, its window
  // segment<k>_t0 and segment<k>_t1 in s), per fault (<metric>_fault<k>), and the scenario's
  // value of the job's metric. simulate() names its columns alike.
  py::dict metrics(const py::array_t<double, py::array::c_style | py::array::forcecast>& x) {
    const Rows r = rows_of(x, problem);
    const std::vector<tune::CandidateOutcome> out = outcomes(r, true);
    std::size_t segments = 0, faults = 0;
    for (const auto& o : out)
      for (const sim::Metrics& m : o.evaluation.scenarios) {
        segments = std::max(segments, m.extra.size());
        for (const sim::MetricField& f : sim::kMetricFields)
          if (f.scope == sim::MetricScope::fault)
            faults = std::max(faults, (m.*f.per_fault).size());
      }
    std::map<std::string, std::vector<double>> num;
    std::vector<std::string> order;
    const auto column = [&](const std::string& name) -> std::vector<double>& {
      if (!num.count(name)) order.push_back(name);
      return num[name];
    };
    std::vector<std::int64_t> candidate;
    std::vector<std::string> scenario;
    std::vector<bool> diverged, counted;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const auto& names = problem.space().names;
    for (std::size_t i = 0; i < out.size(); ++i) {
      if (!out[i].error.empty()) throw InputError("X", "/" + std::to_string(i), out[i].error);
      const auto& per = out[i].evaluation.scenarios;
      for (std::size_t s = 0; s < per.size(); ++s) {
        const sim::Metrics& m = per[s];
        candidate.push_back(static_cast<std::int64_t>(i));
        scenario.push_back(problem.scenario(s).name);
        for (std::size_t j = 0; j < names.size(); ++j) column(names[j]).push_back(r.rows[i][j]);
        column("objective").push_back(problem.job().objective.value(m));
        for (const sim::MetricField& f : sim::kMetricFields) {
          const std::string name(f.name);
          switch (f.scope) {
            case sim::MetricScope::window:
              column(name).push_back(m.errors.*f.in_window);
              for (std::size_t k = 0; k < segments; ++k)
                column(name + "_segment" + std::to_string(k + 1))
                    .push_back(k < m.extra.size() ? m.extra[k].*f.in_window : nan);
              break;
            case sim::MetricScope::run:
              column(name).push_back(m.*f.per_run);
              break;
            case sim::MetricScope::fault:
              for (std::size_t k = 0; k < faults; ++k)
                column(name + "_fault" + std::to_string(k + 1))
                    .push_back(k < (m.*f.per_fault).size() ? (m.*f.per_fault)[k] : nan);
              break;
          }
        }
        // Each segment's window (s): the segments of members with other fault onsets differ.
        for (std::size_t k = 0; k < segments; ++k) {
          const bool has = k < m.extra_windows.size();
          column("segment" + std::to_string(k + 1) + "_t0")
              .push_back(has ? m.extra_windows[k].t0 : nan);
          column("segment" + std::to_string(k + 1) + "_t1")
              .push_back(has ? m.extra_windows[k].t1 : nan);
        }
        diverged.push_back(m.diverged);
        column("diverged_at").push_back(m.diverged ? m.diverged_at : nan);
        counted.push_back(problem.counted(s));
      }
    }
    py::dict d;
    d["candidate"] = py::array(py::cast(candidate));
    d["scenario"] = scenario;
    for (const std::string& name : order)
      d[py::str(name)] =
          py::array_t<double>(static_cast<py::ssize_t>(num[name].size()), num[name].data());
    d["diverged"] = diverged;
    d["counted"] = counted;
    return d;
  }
};

// A tuning run through the run API (`ftctune run`'s own code), computed without an output
// directory: run.json and the files are the run API's, written by write_run.
struct Result {
  tune::RunJobResult run;
  const tune::TuningOutcome& r() const { return run.outcome; }

  std::string gains() const { return tune::gains_document(r()).dump(2) + "\n"; }

  // The files of `ftctune run` into `dir` (locked, through a staging directory, gains.json
  // last), exactly as the CLI writes them. A directory that holds a run is refused unless
  // `replace`; a run the callback stopped has no files (as `ftctune run` stopped keeps only
  // its checkpoint).
  std::vector<std::string> write(const std::string& dir, bool replace) const {
    const fs::path out(dir);
    if (!replace && tune::holds_run(out))
      throw InputError("dir", "", dir + " already holds a run; pass replace=True to write over it");
    if (run.stopped)
      throw InputError("dir", "",
                       "the callback stopped this run before it finished: it has no "
                       "files to write (its gains are in .gains)");
    tune::write_run(run, out, replace);
    std::vector<std::string> written{"run.json"};
    for (const std::string& f : run.files)
      if (f != "run.json" && f != "gains.json") written.push_back(f);
    written.push_back("gains.json");
    return written;
  }
};

Result tune_job(const Job& j, std::optional<int> threads, std::optional<std::uint64_t> seed,
                const py::object& callback) {
  require_tuning(j, "tune");
  PythonEvaluator evaluator(threads_of(threads));
  tune::RunJobOptions o;
  o.job_file = j.source;
  o.seed = seed;
  o.write = false;
  o.evaluator = &evaluator;
  const auto& params = j.job.tuning->parameters;
  o.on_iteration = [&](const tune::IterationReport& report) {
    const tune::HistoryRow& h = report.row;
    park_if_exiting();
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw PythonErrorPending{};
    if (callback.is_none()) return true;
    try {
      py::dict best;
      for (std::size_t k = 0; k < params.size() && k < h.best.size(); ++k)
        best[py::str(params[k].name)] = h.best[k];
      py::dict row;
      row["iteration"] = h.iteration;
      row["evaluations"] = h.evaluations;
      row["best_fitness"] = h.best_fitness;
      row["best"] = best;
      if (report.front_points) row["front_points"] = *report.front_points;
      const py::object answer = callback(row);
      return answer.is_none() || PyObject_IsTrue(answer.ptr()) == 1;
    } catch (py::error_already_set& e) {
      e.restore();
      throw PythonErrorPending{};
    }
  };
  Result res;
  res.run = without_gil([&] {
    tune::RunJobResult r = tune::run_job(j.job, o);
    // Stopped by the callback: the best so far is compared as the service compares a
    // cancelled run's, and its gains say it did not complete.
    if (r.stopped) tune::compare_best(r.outcome, evaluator);
    return r;
  });
  return res;
}

sim::ControllerConfig chosen_controller(const Job& j, const py::object& gains,
                                        const py::object& controller, const py::object& set,
                                        std::string& warning) {
  if (!gains.is_none()) {
    if (!controller.is_none() || !set.is_none())
      throw InputError("gains", "", "cannot be combined with controller or set");
    const std::string path = py::module_::import("os").attr("fspath")(gains).cast<std::string>();
    const ftc::runtime::Gains g = ftc::runtime::read_gains(path);
    for (const sim::Scenario& s : j.job.scenarios)
      ftc::runtime::check_sample_time(g, s.sample_time);
    try {
      ftc::runtime::check_job(g, tune::canonical_job_sha256(j.job));
    } catch (const InputError& e) {
      warning = std::string(e.what()) + ": the metrics are not the objective they were tuned to";
    }
    return g.controller;
  }
  sim::ControllerConfig base = j.job.controller;
  if (!controller.is_none()) {
    const std::string type = controller.cast<std::string>();
    const auto t = sim::controller_type_from_string(type);
    if (!t)
      throw InputError("controller", "",
                       "unknown controller type \"" + type + "\" (known: " +
                           std::string(sim::controller_type_list()) + ")");
    base = sim::ControllerConfig::table1(*t);
  }
  if (set.is_none()) return base;
  // {"Kp": 12, ...}: the controller's fields, checked as a job's controller is.
  json c = tune::to_json(base);
  const json values = to_json_value(set, "set");
  if (!values.is_object()) throw InputError("set", "", "must be a dict of parameter values");
  std::vector<FieldError> errs;
  for (const auto& [key, value] : values.items()) {
    if (key == "type" || !c.contains(key))
      errs.push_back({"/" + key, "is not a parameter of controller " +
                                     std::string(sim::to_string(base.type))});
    else
      c[key] = value;
  }
  ftc::throw_if_errors("set", std::move(errs));
  const sim::ControllerConfig chosen = tune::parse_controller(c, "", errs);
  ftc::throw_if_errors("set", std::move(errs));
  return chosen;
}

// `ftctune simulate`: the controller on each listed scenario of the job, with the documents
// the CLI writes (metrics.json's scenarios, each trajectory's CSV).
py::dict simulate(const Job& j, const py::object& gains, const py::object& controller,
                  const py::object& set, const py::object& record_every) {
  std::string warning;
  const sim::ControllerConfig c = chosen_controller(j, gains, controller, set, warning);
  tune::SimulateJobOptions o;
  o.record_every = record_every.is_none() ? 0.01 : record_every.cast<double>();
  o.write = false;
  o.after_scenario = check_signals;
  // The command's own call: the same metrics.json document and trajectories, not written.
  const tune::SimulateJobResult r =
      without_gil([&] { return tune::simulate_job(j.job, c, o); });
  py::list trajectories;
  for (const auto& t : r.trajectories) trajectories.append(t.second);
  const json& doc = r.document;
  py::dict d;
  d["document"] = doc.dump();
  d["trajectories"] = trajectories;
  d["warning"] = warning;
  py::list notes;
  for (const std::string& w : r.warnings) notes.append(w);
  d["notes"] = notes;
  return d;
}

// The job's ensemble members as `ftctune ensemble` writes them (JSON text of the list).
std::string ensemble(const Job& j, std::optional<std::uint64_t> seed,
                     std::optional<std::int64_t> count) {
  if (!j.job.ensemble) throw InputError(j.source, "/ensemble", "the job has no ensemble to expand");
  const std::uint64_t s = seed.value_or(j.job.ensemble->seed);
  const std::int64_t n = tune::ensemble_count(j.job, count);
  const std::unique_ptr<sim::AnyPlant> plant = sim::make_plant(j.job.plant);
  json members = json::array();
  for (std::int64_t k = 0; k < n; ++k) {
    if (k % 1024 == 1023 && PyErr_CheckSignals() != 0) raise_pending();
    const sim::Scenario m = tune::ensemble_member(j.job, s, k);
    json v = tune::to_json(m);
    v["recoverable"] = plant->recoverable(m);
    members.push_back(std::move(v));
  }
  return members.dump();
}

// `ftctune evaluate`: per controller and scenario (listed, then held-out members) the member's
// numbers, and each scenario's faults as the job file writes them.
py::dict evaluate(const Job& j, const std::vector<std::pair<std::string, std::string>>& gains,
                  std::optional<std::uint64_t> seed, std::optional<std::int64_t> count,
                  std::optional<int> threads) {
  tune::EvaluateOptions o;
  for (const auto& [label, path] : gains) o.gains.push_back({path, label});
  o.seed = seed;
  o.count = count;
  PythonEvaluator evaluator(threads_of(threads));
  const tune::EvaluationResult r =
      without_gil([&] { return tune::evaluate_out_of_sample(j.job, o, evaluator); });
  std::vector<std::string> label, source, scenario;
  std::vector<std::int64_t> index;
  std::vector<bool> recoverable, diverged;
  std::vector<double> objective;
  // Every field of the metrics record, in its order: a window or run field as one column, a
  // fault field as one column per fault onset (<name>_fault<k>, as Problem.metrics names it;
  // NaN where a member has fewer).
  std::size_t onsets = 0;
  for (const tune::EvaluatedController& c : r.controllers)
    for (const tune::MemberResult& m : c.members) onsets = std::max(onsets, m.metrics.onsets);
  std::vector<std::string> columns;
  for (const sim::MetricField& f : sim::kMetricFields)
    if (f.scope != sim::MetricScope::fault)
      columns.emplace_back(f.name);
    else
      for (std::size_t k = 1; k <= onsets; ++k)
        columns.push_back(std::string(f.name) + "_fault" + std::to_string(k));
  std::vector<std::vector<double>> values(columns.size());
  json summaries = json::array();
  for (const tune::EvaluatedController& c : r.controllers) {
    summaries.push_back({{"label", c.label},
                         {"source", c.source},
                         {"controller", tune::to_json(c.controller)},
                         {"aggregates", tune::summary_json(c.aggregates)}});
    for (std::size_t i = 0; i < c.members.size(); ++i) {
      const tune::MemberResult& m = c.members[i];
      label.push_back(c.label);
      source.push_back(c.source);
      scenario.push_back(m.scenario);
      index.push_back(static_cast<std::int64_t>(i));
      recoverable.push_back(m.recoverable);
      diverged.push_back(m.diverged);
      objective.push_back(m.objective);
      std::size_t col = 0;
      for (std::size_t f = 0; f < sim::kMetricFieldCount; ++f) {
        const std::span<const double> v = m.metrics.field(f);
        if (sim::kMetricFields[f].scope != sim::MetricScope::fault) {
          values[col++].push_back(v[0]);
          continue;
        }
        for (std::size_t k = 0; k < onsets; ++k)
          values[col++].push_back(k < v.size() ? v[k] : std::numeric_limits<double>::quiet_NaN());
      }
    }
  }
  // Each scenario's faults: the listed ones', then member k's of the held-out seed.
  json faults = json::array();
  const std::size_t listed = r.job.scenarios.size();
  const std::size_t total = r.controllers.empty() ? 0 : r.controllers[0].members.size();
  for (std::size_t i = 0; i < total; ++i) {
    const sim::Scenario s =
        i < listed ? r.job.scenarios[i]
                   : tune::ensemble_member(r.job, r.seed, static_cast<std::int64_t>(i - listed));
    faults.push_back(tune::to_json(s).value("faults", json::array()));
  }
  py::dict d;
  d["controller"] = label;
  d["source"] = source;
  d["scenario"] = scenario;
  d["scenario_index"] = index;
  d["recoverable"] = recoverable;
  d["objective"] = objective;
  d["metric_columns"] = columns;
  for (std::size_t c = 0; c < columns.size(); ++c) d[py::str(columns[c])] = values[c];
  d["diverged"] = diverged;
  d["faults"] = faults.dump();
  d["summaries"] = summaries.dump();
  d["seed"] = r.seed;
  d["count"] = r.count;
  d["simulations"] = r.simulations;
  return d;
}

// A gains file, checked as `ftctune simulate --gains` reads it; its text.
std::string load_gains(const py::object& path) {
  const std::string p = py::module_::import("os").attr("fspath")(path).cast<std::string>();
  (void)ftc::runtime::read_gains(p);
  std::optional<std::string> text = tune::read_file(p);
  if (!text) throw InputError(p, "", "cannot be read");
  return *text;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "The native half of the ftctune module (use `import ftctune`)";
  // ftctune.InputError(ValueError): every error on a line of the message, each with its JSON
  // path; .source (the input) and .errors ([(path, message)]) as attributes.
  m.attr("InputError") = py::exception<InputError>(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      std::string message = e.source().empty() ? std::string() : e.source() + ": ";
      py::list errors;
      // The message lists the first kMaxReportedErrors, as `ftctune validate` does (20 000 bad
      // rows of X made a message of 20 000 lines); `errors` keeps them all.
      std::size_t k = 0;
      for (const FieldError& f : e.errors()) {
        if (k++ < tune::kMaxReportedErrors) {
          if (e.errors().size() > 1) message += "\n  ";
          message += f.path.empty() ? f.message : f.path + ": " + f.message;
        }
        errors.append(py::make_tuple(f.path, f.message));
      }
      if (e.errors().size() > tune::kMaxReportedErrors)
        message += "\n  ... and " + std::to_string(e.errors().size() - tune::kMaxReportedErrors) +
                   " more (the first " + std::to_string(tune::kMaxReportedErrors) +
                   " are listed; .errors has every one)";
      const py::object type = py::module_::import("ftctune._core").attr("InputError");
      const py::object error = type(message);
      error.attr("source") = e.source();
      error.attr("errors") = errors;
      PyErr_SetObject(type.ptr(), error.ptr());
    }
  });

  m.attr("version") = ftc::kVersion;  // ftctune --version's; the package's __version__
  py::module_::import("atexit").attr("register")(py::cpp_function(&on_interpreter_exit));

  py::class_<Job> job_class(m, "Job");
  made_by_functions(job_class);
  job_class.def_property_readonly("name", [](const Job& j) { return j.job.name; })
      .def_property_readonly("source", [](const Job& j) { return j.source; })
      .def("to_json", [](const Job& j) { return tune::to_json(j.job).dump(); })
      .def("sha256", [](const Job& j) { return tune::canonical_job_sha256(j.job); });
  m.def("load_job", &load_job, py::arg("path_or_dict"));
  // The plant search path's own directories (--plant-path's; FTCTUNE_PLANT_PATH's follow).
  m.def("set_plant_path", [](const std::vector<std::string>& dirs) {
    sim::set_plant_search_path(std::vector<std::filesystem::path>(dirs.begin(), dirs.end()));
  });

  py::class_<Problem> problem_class(m, "Problem");
  made_by_functions(problem_class);
  m.def(
      "problem",
      [](const Job& j, std::optional<int> threads) {
        return std::make_unique<Problem>(j, threads);
      },
      py::arg("job"), py::arg("threads") = py::none());
  problem_class.def_property_readonly("names", [](const Problem& p) { return p.problem.space().names; })
      .def_property_readonly("bounds",
                             [](const Problem& p) {
                               std::vector<std::pair<double, double>> b;
                               for (const auto& q : p.problem.job().tuning->parameters)
                                 b.emplace_back(q.lower, q.upper);
                               return b;
                             })
      .def_property_readonly("scales",
                             [](const Problem& p) {
                               std::vector<std::string> s;
                               for (const auto& q : p.problem.job().tuning->parameters)
                                 s.push_back(q.scale == tune::Scale::log ? "log" : "linear");
                               return s;
                             })
      .def_property_readonly("scenarios",
                             [](const Problem& p) {
                               std::vector<std::string> s;
                               for (std::size_t i = 0; i < p.problem.scenarios(); ++i)
                                 s.push_back(p.problem.scenario(i).name);
                               return s;
                             })
      .def_property_readonly("threads", [](const Problem& p) { return p.evaluator.concurrency(); })
      .def("objective", &Problem::objective, py::arg("X"))
      .def("metrics", &Problem::metrics, py::arg("X"));

  py::class_<Result> result_class(m, "Result");
  made_by_functions(result_class);
  result_class.def_property_readonly("completed", [](const Result& r) { return r.r().completed(); })
      .def_property_readonly("gains_text", &Result::gains)
      .def_property_readonly("trials_csv", [](const Result& r) { return tune::trials_csv(r.r()); })
      .def_property_readonly("history_csv",
                             [](const Result& r) { return tune::history_csv(r.r()); })
      .def_property_readonly(
          "comparison_text",
          [](const Result& r) { return tune::comparison_document(r.r()).dump(); })
      .def_property_readonly("warnings", [](const Result& r) { return r.r().warnings; })
      .def_property_readonly("noise_floor",
                             [](const Result& r) { return tune::noise_floor_sentence(r.r()); })
      .def_property_readonly("seed", [](const Result& r) { return r.r().seed; })
      .def_property_readonly("simulations", [](const Result& r) { return r.r().simulations; })
      .def_property_readonly("threads", [](const Result& r) { return r.r().threads; })
      .def_property_readonly("wall_seconds", [](const Result& r) { return r.run.wall_seconds; })
      .def("write", &Result::write, py::arg("dir"), py::arg("replace") = false);
  m.def("tune", &tune_job, py::arg("job"), py::arg("threads") = py::none(),
        py::arg("seed") = py::none(), py::arg("callback") = py::none());
  m.def("simulate", &simulate, py::arg("job"), py::arg("gains") = py::none(),
        py::arg("controller") = py::none(), py::arg("set") = py::none(),
        py::arg("record_every") = py::none());
  m.def("ensemble", &ensemble, py::arg("job"), py::arg("seed") = py::none(),
        py::arg("count") = py::none());
  m.def("evaluate", &evaluate, py::arg("job"), py::arg("gains"), py::arg("seed") = py::none(),
        py::arg("count") = py::none(), py::arg("threads") = py::none());
  m.def("load_gains", &load_gains, py::arg("path"));
}
