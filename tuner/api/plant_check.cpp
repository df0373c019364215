#include "ftc/tune/api/plant_check.hpp"

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "ftc/sim/input_error.hpp"
#include "ftc/sim/isa.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/optimizers/rng.hpp"
#include "io/text.hpp"

namespace ftc::tune {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string fmt(double v) { return detail::format_number(v, "%.3g"); }

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// One evaluation of f, G and G⁺ at x.
struct Eval {
  std::vector<double> f, G, Gp;
  bool ok = false;
  std::string error;
};

Eval evaluate(const sim::PlantPlugin& p, const std::vector<double>& values,
              const std::vector<double>& x) {
  const int n = p.kind->axes, m = p.kind->actuators;
  Eval e;
  e.f.assign(n, 0.0);
  e.G.assign(static_cast<std::size_t>(n * m), 0.0);
  e.Gp.assign(static_cast<std::size_t>(m * n), 0.0);
  try {
    e.ok = p.api->evaluate(values, x.data(), e.f.data(), e.G.data(), e.Gp.data(), &e.error);
  } catch (const std::exception& ex) {
    e.error = ex.what();
  }
  return e;
}

bool identical(const Eval& a, const Eval& b) {
  const auto eq = [](const std::vector<double>& u, const std::vector<double>& v) {
    for (std::size_t i = 0; i < u.size(); ++i)
      if (!same_bits(u[i], v[i])) return false;
    return true;
  };
  return eq(a.f, b.f) && eq(a.G, b.G) && eq(a.Gp, b.Gp);
}

// The simulations the lane check runs: every controller type on four scenarios of the plant.
struct LaneCase {
  std::vector<sim::ControllerConfig> controllers;
  std::vector<sim::Scenario> scenarios;
  sim::SimulationOptions options;
};

LaneCase lane_case(const sim::PlantKind& k, Rng& rng) {
  LaneCase c;
  for (const sim::ControllerType t :
       {sim::ControllerType::pi_fosmc, sim::ControllerType::fosmc, sim::ControllerType::nftsmc,
        sim::ControllerType::adaptive_neural_pi_fosmc}) {
    sim::ControllerConfig cc;
    cc.type = t;
    c.controllers.push_back(cc);
  }
  for (int s = 0; s < 4; ++s) {
    sim::Scenario sc;
    sc.name = "check-" + std::to_string(s);
    sc.duration = 2.0;
    sc.sample_time = 1e-3;
    sc.initial_state = k.default_initial_state;
    if (s > 0)
      for (double& v : sc.initial_state) v += rng.uniform(-0.1, 0.1);
    sim::Fault f;
    f.actuator = s % 2 == 0 ? 1 : k.actuators;
    f.type = sim::FaultType::loss_of_effectiveness;
    f.onset = 0.5 + 0.25 * s;
    f.fraction = 0.3;
    sc.faults.push_back(f);
    c.scenarios.push_back(sc);
  }
  c.options.window = {0.0, 2.0};
  return c;
}

bool same_result(const sim::SimulationResult& a, const sim::SimulationResult& b) {
  if (a.samples != b.samples || a.final_state.size() != b.final_state.size()) return false;
  for (std::size_t i = 0; i < a.final_state.size(); ++i)
    if (!same_bits(a.final_state[i], b.final_state[i])) return false;
  const sim::ErrorIntegrals &x = a.metrics.errors, &y = b.metrics.errors;
  for (const auto f :
       {&sim::ErrorIntegrals::ise, &sim::ErrorIntegrals::iae, &sim::ErrorIntegrals::itae,
        &sim::ErrorIntegrals::control_energy, &sim::ErrorIntegrals::peak_command})
    if (!same_bits(x.*f, y.*f)) return false;
  return true;
}

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The user's model at `states`: {"f": [...], "G": [[...]...]} per state, from a Python process.
json python_model(const PlantCheckOptions& o, const sim::PlantKind& k,
                  const std::vector<double>& values,
                  const std::vector<std::vector<double>>& states) {
  static const char* kDriver = R"py(import importlib.util, json, sys
spec = importlib.util.spec_from_file_location("ftctune_user_model", sys.argv[1])
model = importlib.util.module_from_spec(spec)
spec.loader.exec_module(model)
for name in ("f", "G"):
    if not callable(getattr(model, name, None)):
        sys.exit(sys.argv[1] + " defines no function " + name + "(x, p)")
with open(sys.argv[2]) as fh:
    d = json.load(fh)
out = []
for x in d["states"]:
    f = [float(v) for v in model.f(list(x), dict(d["params"]))]
    G = [[float(v) for v in row] for row in model.G(list(x), dict(d["params"]))]
    out.append({"f": f, "G": G})
with open(sys.argv[3], "w") as fh:
    json.dump(out, fh)
)py";
  if (!fs::is_regular_file(o.against))
    throw InputError("--against", "", o.against.string() + ": no such file");
  json params = json::object();
  std::size_t at = 0;
  for (const sim::PlantParameter& p : k.parameters) {
    if (p.size() == 1)
      params[p.name] = values[at];
    else
      params[p.name] = std::vector<double>(values.begin() + static_cast<long>(at),
                                           values.begin() + static_cast<long>(at + p.size()));
    at += p.size();
  }
  // A directory of its own (mkdtemp: 0700, a name nobody could have made first).
  std::string tmpl = (fs::temp_directory_path() / "ftctune-plant-check-XXXXXX").string();
  if (!::mkdtemp(tmpl.data()))
    throw InputError("--against", "", "cannot make a temporary directory: " + tmpl);
  const fs::path dir = tmpl;
  struct Cleanup {
    fs::path d;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  } cleanup{dir};
  std::ofstream(dir / "driver.py") << kDriver;
  std::ofstream(dir / "in.json") << json{{"states", states}, {"params", params}}.dump();
  const std::string cmd = shell_quote(o.python) + " " + shell_quote((dir / "driver.py").string()) +
                          " " + shell_quote(fs::absolute(o.against).string()) + " " +
                          shell_quote((dir / "in.json").string()) + " " +
                          shell_quote((dir / "out.json").string()) + " 2>" +
                          shell_quote((dir / "err.txt").string());
  const int status = std::system(cmd.c_str());
  if (status != 0) {
    std::ifstream err(dir / "err.txt");
    std::string line, last;
    while (std::getline(err, line))
      if (!line.empty()) last = line;
    throw InputError("--against", "",
                     o.against.string() + ": the model failed (" +
                         (last.empty() ? "exit status " + std::to_string(status) : last) + ")");
  }
  std::ifstream in(dir / "out.json");
  return json::parse(in);
}

}  // namespace

PlantCheckReport check_plant_plugin(const fs::path& library, const PlantCheckOptions& o) {
  const sim::PlantPlugin& p = sim::load_plant_plugin(library);
  const sim::PlantKind& k = *p.kind;
  const int n = k.axes, m = k.actuators;
  PlantCheckReport r;
  r.model = k.model;
  r.file = p.file.string();
  r.axes = n;
  r.actuators = m;
  const std::vector<double> values = k.defaults();
  Rng rng(o.seed);
  std::vector<std::vector<double>> states;
  for (int s = 0; s < o.states; ++s) {
    std::vector<double> x = k.default_initial_state;
    for (int i = 0; i < 2 * n; ++i) x[i] += rng.uniform(-1.0, 1.0) * std::max(1.0, std::abs(x[i]));
    states.push_back(std::move(x));
  }

  PlantCheckItem finite{"f(X), G(X), G⁺(X) finite", true, ""};
  PlantCheckItem deterministic{"f(X), G(X), G⁺(X) the same bits twice", true, ""};
  PlantCheckItem inverse{"G(X) G⁺(X) = I", true, ""};
  double worst_inverse = 0.0;
  std::vector<Eval> evals;
  for (const std::vector<double>& x : states) {
    Eval e = evaluate(p, values, x);
    if (!e.ok) {
      finite.passed = false;
      finite.detail = "the plant refused its default values: " + e.error;
      break;
    }
    const auto all_finite = [](const std::vector<double>& v) {
      return std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); });
    };
    if (finite.passed && !(all_finite(e.f) && all_finite(e.G) && all_finite(e.Gp))) {
      finite.passed = false;
      finite.detail = "not finite at a state of the draw (seed " + std::to_string(o.seed) + ")";
    }
    if (deterministic.passed && !identical(e, evaluate(p, values, x))) {
      deterministic.passed = false;
      deterministic.detail = "a second evaluation at the same state gave other bits";
    }
    // ‖G G⁺ − I‖max relative to ‖G‖max ‖G⁺‖max.
    double scale = 0.0, err = 0.0;
    for (const double v : e.G) scale = std::max(scale, std::abs(v));
    double pscale = 0.0;
    for (const double v : e.Gp) pscale = std::max(pscale, std::abs(v));
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        double s = 0.0;
        for (int c = 0; c < m; ++c) s += e.G[i * m + c] * e.Gp[c * n + j];
        err = std::max(err, std::abs(s - (i == j ? 1.0 : 0.0)));
      }
    const double rel = err / std::max(1.0, scale * pscale);
    if (!(rel <= worst_inverse)) worst_inverse = rel;  // NaN sticks
    evals.push_back(std::move(e));
  }
  inverse.passed = finite.passed && worst_inverse <= 1e-9;
  inverse.detail = "worst |G G⁺ − I| " + fmt(worst_inverse) + " over " +
                   std::to_string(evals.size()) + " random states (limit 1e-9)";
  if (finite.passed)
    finite.detail = "at " + std::to_string(evals.size()) + " random states (seed " +
                    std::to_string(o.seed) + ")";
  if (deterministic.passed) deterministic.detail = "at every state";
  r.items = {finite, deterministic, inverse};

  PlantCheckItem trim{"actuator trim inside its limits", true, "no operating point"};
  std::vector<double> u0(m), lo(m), hi(m);
  if (p.api->trim(values, u0.data(), lo.data(), hi.data())) {
    for (int j = 0; j < m; ++j)
      if (!(lo[j] <= 0.0 && 0.0 <= hi[j] && lo[j] < hi[j] && std::isfinite(u0[j]))) {
        trim.passed = false;
        trim.detail = "actuator " + std::to_string(j + 1) + ": u0 " + fmt(u0[j]) +
                      ", deviation range [" + fmt(lo[j]) + ", " + fmt(hi[j]) + "] does not hold 0";
        break;
      }
    if (trim.passed) trim.detail = "u0 of every actuator inside its range";
  }
  r.items.push_back(trim);

  // SIMD lanes against one lane, on every instruction set.
  const std::unique_ptr<sim::AnyPlant> plant = k.make(values);
  const LaneCase c = lane_case(k, rng);
  std::vector<sim::PackTask> tasks;
  for (const sim::ControllerConfig& cc : c.controllers)
    for (const sim::Scenario& sc : c.scenarios) tasks.push_back({&cc, &sc, &c.options});
  std::vector<sim::SimulationResult> one(tasks.size());
  for (std::size_t i = 0; i < tasks.size(); ++i)
    one[i] = plant->simulate(*tasks[i].controller, *tasks[i].scenario, *tasks[i].options);
  for (const sim::Isa isa : sim::supported_isas()) {
    std::vector<sim::SimulationResult> lanes(tasks.size());
    std::vector<std::string> errors(tasks.size());
    plant->simulate_pack(tasks, lanes, errors, isa);
    int differ = 0;
    std::string first_error;
    for (std::size_t i = 0; i < tasks.size(); ++i) {
      if (!errors[i].empty() && first_error.empty()) first_error = errors[i];
      if (!errors[i].empty() || !same_result(lanes[i], one[i])) ++differ;
    }
    PlantCheckItem item{std::string("lanes equal one lane (") + sim::to_string(isa) + ", " +
                            std::to_string(sim::lane_width(isa)) + " wide)",
                        differ == 0, ""};
    item.detail = differ == 0
                      ? std::to_string(tasks.size()) +
                            " simulations (4 controllers, 4 faulted scenarios), bit for bit"
                      : std::to_string(differ) + " of " + std::to_string(tasks.size()) +
                            " simulations differ" + (first_error.empty() ? "" : ": " + first_error);
    r.items.push_back(item);
  }

  if (!o.against.empty()) {
    const json py = python_model(o, k, values, states);
    double worst_f = 0.0, worst_G = 0.0;
    std::string shape_error;
    for (std::size_t s = 0; s < evals.size() && s < py.size(); ++s) {
      const std::vector<double> f = py[s].at("f").get<std::vector<double>>();
      const auto G = py[s].at("G").get<std::vector<std::vector<double>>>();
      if (f.size() != static_cast<std::size_t>(n) || G.size() != static_cast<std::size_t>(n) ||
          std::any_of(G.begin(), G.end(), [&](const std::vector<double>& row) {
            return row.size() != std::size_t(m);
          })) {
        shape_error = "the model's f has " + std::to_string(f.size()) + " values and its G " +
                      std::to_string(G.size()) + " rows; the plant has n = " + std::to_string(n) +
                      ", m = " + std::to_string(m);
        break;
      }
      double fs = 0.0, fe = 0.0, gs = 0.0, ge = 0.0;
      for (int i = 0; i < n; ++i) {
        fs = std::max(fs, std::abs(f[i]));
        fe = std::max(fe, std::abs(f[i] - evals[s].f[i]));
        for (int j = 0; j < m; ++j) {
          gs = std::max(gs, std::abs(G[i][j]));
          ge = std::max(ge, std::abs(G[i][j] - evals[s].G[i * m + j]));
        }
      }
      const double rf = fe / std::max(fs, 1e-300), rg = ge / std::max(gs, 1e-300);
      if (!(rf <= worst_f)) worst_f = fe == 0.0 ? worst_f : rf;
      if (!(rg <= worst_G)) worst_G = ge == 0.0 ? worst_G : rg;
    }
    PlantCheckItem item{"f and G against " + o.against.filename().string(), false, shape_error};
    if (shape_error.empty()) {
      item.passed = worst_f <= o.tolerance && worst_G <= o.tolerance;
      item.detail = "worst relative difference: f " + fmt(worst_f) + ", G " + fmt(worst_G) +
                    " over " + std::to_string(evals.size()) + " states (tolerance " +
                    fmt(o.tolerance) + ")";
    }
    r.items.push_back(item);
  }
  return r;
}

}  // namespace ftc::tune
