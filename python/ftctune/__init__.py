"""ftctune from Python: tune fault-tolerant sliding-mode controllers in-process.

    import ftctune
    job = ftctune.load_job("jobs/table1.json")
    result = ftctune.tune(job)              # what `ftctune run` computes
    result.gains["tuned"], result.history   # a dict, a pandas DataFrame
    result.write("out/table1")              # the same files as `ftctune run`

The simulations run in the library (ftctune._core, C++), on all cores, with the GIL released;
Ctrl-C stops a long call with KeyboardInterrupt. Bad input raises ftctune.InputError, whose
message names the input and the JSON path of each error. docs/python.md has the whole API.
"""

# The module's namespace is its API: what it imports is kept under private names.
import io as _io
import json as _json
import os as _os
import tempfile as _tempfile
import warnings as _warnings

import numpy as _np
import pandas as _pd

from . import _core

__all__ = ["InputError", "RunWarning", "Job", "Problem", "Result", "load_job", "tune", "simulate",
           "ensemble", "evaluate", "load_gains"]

__version__ = _core.version  # the C++ library's, as `ftctune --version` prints it

InputError = _core.InputError
InputError.__module__ = __name__
InputError.__doc__ = ("Bad input (a job, a gains file, an argument): the message names the input "
                      "and the JSON path of each error.")


class RunWarning(UserWarning):
    """A warning of a tuning run (a parameter on its bound, a compared controller that scores
    lower, a loop that diverged or left its model's validity): tune() issues each through
    warnings.warn, as `ftctune run` logs it; Result.warnings keeps them as text."""


class Job:
    """A validated job (ftctune.job/1) with every default filled in."""

    def __init__(self, native):
        self._native = native

    @property
    def name(self):
        return self._native.name

    @property
    def source(self):
        """The file it was read from, or "<dict>"."""
        return self._native.source

    def to_dict(self):
        """The resolved job as a dict: what `ftctune run` writes to job.json."""
        return _json.loads(self._native.to_json())

    def __repr__(self):
        return f"ftctune.Job({self.name!r} from {self.source!r})"


def load_job(path_or_dict, plant_path=None):
    """Reads and validates a job file (a path) or a job given as a dict.

    A job whose plant is a plugin ("plugin:NAME", docs/plugins.md) finds ftctune_plant_NAME.so in
    plant_path (a directory or a list of them; kept for later calls, as `--plant-path` is for a
    command) or in the environment's FTCTUNE_PLANT_PATH."""
    if plant_path is not None:
        dirs = [plant_path] if isinstance(plant_path, (str, _os.PathLike)) else list(plant_path)
        _core.set_plant_path([_os.fspath(d) for d in dirs])
    if isinstance(path_or_dict, Job):
        return path_or_dict
    return Job(_core.load_job(path_or_dict))


def _job(job):
    return load_job(job)._native


class Problem:
    """A job as a tuning problem: the tuned parameters, their bounds and the objective.

    objective(X) and metrics(X) take parameter values in natural units (not ln x), one
    candidate per row of X, (n, d), or one candidate, (d,). The candidates are simulated in
    batches in the plant's SIMD lanes on all threads (or `threads`), and each objective is the
    value `ftctune run` would see for those parameters, to the bit.
    """

    def __init__(self, job, threads=None):
        job = load_job(job)
        self._job, self._threads = job, threads
        self._name = job.name
        self._native = _core.problem(job._native, threads)

    def __deepcopy__(self, memo):
        # pygmo.problem() deep-copies the problem it is given; the native half is not copyable,
        # so the copy is a Problem of the same job and threads (the same values to the bit).
        return Problem(self._job, self._threads)

    def __repr__(self):
        space = ", ".join(f"{n} in [{lo:g}, {hi:g}]{' (log)' if s == 'log' else ''}"
                          for n, (lo, hi), s in zip(self.names, self.bounds, self.scales))
        n, t = len(self.scenarios), self.threads
        return (f"ftctune.Problem({self._name!r}: {space}; {n} scenario{'s' * (n != 1)}, "
                f"{t} thread{'s' * (t != 1)})")

    def __call__(self, x):
        """The objective of one candidate as a float, so that the problem is a function
        scipy.optimize takes: minimize(problem, x0, bounds=problem.bounds)."""
        return float(self._native.objective(_np.asarray(x, dtype=float).reshape(1, -1))[0])

    # pygmo's user-defined problem protocol: pygmo.problem(ftctune.Problem(job)) is a problem of
    # one objective (minimised) over the tuned parameters' bounds.
    def fitness(self, x):
        """[objective] of one candidate (pygmo's fitness)."""
        return [self(x)]

    def get_bounds(self):
        """(lower bounds, upper bounds), natural units (pygmo's get_bounds)."""
        return tuple(list(side) for side in zip(*self.bounds))

    def get_nobj(self):
        return 1

    def get_name(self):
        return f"ftctune {self._name}"

    @property
    def names(self):
        """The tuned parameters, in the order of X's columns."""
        return list(self._native.names)

    @property
    def bounds(self):
        """(lower, upper) per parameter, natural units."""
        return [tuple(b) for b in self._native.bounds]

    @property
    def scales(self):
        """"linear" or "log" per parameter (how the optimisers search it)."""
        return list(self._native.scales)

    @property
    def scenarios(self):
        """The scenarios a candidate is simulated on: the listed ones, then ensemble members."""
        return list(self._native.scenarios)

    @property
    def threads(self):
        return self._native.threads

    def objective(self, X):
        """The job's objective (minimised; inf for a diverged candidate) per row of X."""
        return self._native.objective(X)

    def metrics(self, X):
        """A DataFrame, one row per (candidate, scenario): the parameters, the scenario's value
        of the job's metric ("objective"), every metric of the metrics record (per fault
        segment: <metric>_segment<k>; per fault: <metric>_fault<k>), diverged and whether the
        scenario counts in the objective."""
        return _pd.DataFrame(self._native.metrics(X))


def _csv_frame(text):
    # round_trip: the 17 digits of the files give back the very doubles.
    return _pd.read_csv(_io.StringIO(text), float_precision="round_trip")


class Result:
    """A tuning run's outcome (what `ftctune run` computes)."""

    def __init__(self, native):
        self._native = native

    @property
    def completed(self):
        """False when the callback stopped the run (the gains file then says so)."""
        return self._native.completed

    @property
    def gains(self):
        """The gains file's content (ftctune.gains/1) as a dict."""
        return _json.loads(self._native.gains_text)

    @property
    def trials(self):
        """trials.csv as a DataFrame: one row per evaluated candidate."""
        return _csv_frame(self._native.trials_csv)

    @property
    def history(self):
        """history.csv as a DataFrame: one row per iteration."""
        return _csv_frame(self._native.history_csv)

    @property
    def comparison(self):
        """comparison.json as a dict: the compared controllers, the job's own and the tuned."""
        return _json.loads(self._native.comparison_text)

    @property
    def warnings(self):
        """The run's warnings as text (tune() also issued each as a RunWarning)."""
        return list(self._native.warnings)

    @property
    def noise_floor(self):
        """Whether the margin over the job's own controller exceeds the noise floor, in words."""
        return self._native.noise_floor

    @property
    def seed(self):
        return self._native.seed

    @property
    def simulations(self):
        return self._native.simulations

    @property
    def threads(self):
        return self._native.threads

    @property
    def wall_seconds(self):
        return self._native.wall_seconds

    def write(self, dir, replace=False):
        """Writes the files of `ftctune run` into dir, byte for byte the same (run.json's time,
        host and memory are this process's); returns their names. A directory holding a run is
        refused unless replace=True."""
        return self._native.write(_os.fspath(dir), replace)

    def __repr__(self):
        tuned = self.gains.get("tuned", {})
        return f"ftctune.Result(tuned={tuned!r}, completed={self.completed})"


def tune(job, threads=None, seed=None, callback=None):
    """Tunes the job's controller as `ftctune run` does; returns a Result.

    threads: worker threads (default all cores); seed: instead of tuning.seed; callback: called
    after each iteration with a dict (iteration, evaluations, best_fitness, best: parameter
    values); returning False stops the run (Result.completed is then False).
    """
    result = Result(_core.tune(_job(job), threads, seed, callback))
    for text in result.warnings:
        _warnings.warn(text, RunWarning, stacklevel=2)
    return result


def simulate(job, gains=None, controller=None, set=None, record_every=None):
    """Simulates a controller on each listed scenario of the job, as `ftctune simulate`.

    gains: a gains file; controller: a type with its Table 1 values; set: {parameter: value}
    over the job's (or that type's) controller; record_every: trajectory interval in seconds
    (default 0.01). Returns a dict: "metrics" (a DataFrame, one row per scenario, its columns
    named as Problem.metrics names them),
    "trajectories" ({scenario: DataFrame}), "objective", "fitness", "controller",
    "scenarios" (the metrics as metrics.json lists them, with "recoverable" and "counted").
    "objective" is None when no scenario counts (every one is unrecoverable).
    """
    if gains is not None and not isinstance(gains, (str, _os.PathLike)):
        with _tempfile.TemporaryDirectory() as d:
            return simulate(job, _gains_file(gains, d, "gains.json"), controller, set, record_every)
    native = _job(job)
    out = _core.simulate(native, gains, controller, set, record_every)
    if out["warning"]:
        _warnings.warn(out["warning"], stacklevel=2)
    for note in out["notes"]:  # diverged and unrecoverable scenarios, as the command warns
        _warnings.warn(note, stacklevel=2)
    doc = _json.loads(out["document"])
    rows = []
    for s in doc["scenarios"]:
        # Columns as Problem.metrics names them: a value per fault onset as <metric>_fault<k>,
        # each fault segment's metrics as <metric>_segment<k> with its window segment<k>_t0/_t1.
        row = {"scenario": s["name"]}
        for k, v in s.items():
            if k in ("name", "window", "segments"):
                continue
            if isinstance(v, list):
                for i, x in enumerate(v):
                    row["%s_fault%d" % (k, i + 1)] = x
            else:
                row[k] = v
        for i, seg in enumerate(s.get("segments", [])):
            for k, v in seg.items():
                if k != "window":
                    row["%s_segment%d" % (k, i + 1)] = v
            row["segment%d_t0" % (i + 1)], row["segment%d_t1" % (i + 1)] = seg["window"]
        rows.append(row)
    frames = {s["name"]: _csv_frame(t) for s, t in zip(doc["scenarios"], out["trajectories"])}
    objective = doc["objective"]
    if objective is None and any(s["counted"] for s in doc["scenarios"]):
        objective = float("inf")  # a diverged run; None: no scenario counts (unrecoverable)
    return {"metrics": _pd.DataFrame(rows), "trajectories": frames,
            "objective": objective,
            "fitness": doc["fitness"], "controller": doc["controller"],
            "scenarios": doc["scenarios"]}


def ensemble(job, seed=None, count=None):
    """The members of the job's ensemble as `ftctune ensemble` lists them: a list of scenario
    dicts with their faults as structured fields, and "recoverable"."""
    return _json.loads(_core.ensemble(_job(job), seed, count))


def _gains_file(gains, directory, name):
    """A path for gains given as a path, a Result or a gains dict."""
    if isinstance(gains, (str, _os.PathLike)):
        return _os.fspath(gains)
    doc = gains.gains if isinstance(gains, Result) else gains
    if not isinstance(doc, dict):
        raise TypeError("gains must be a path, a Result or a gains dict")
    path = _os.path.join(directory, name)
    with open(path, "w") as f:
        _json.dump(doc, f, indent=2)
    return path


def _flat(fault):
    """A fault's fields, nested ones (its profile) as <field>_<key>."""
    out = {}
    for key, value in fault.items():
        if isinstance(value, dict):
            for k, v in value.items():
                out[f"{key}_{k}"] = v
        else:
            out[key] = value
    return out


def _fault_columns(faults):
    """fault<k>_<field> columns from each scenario's list of faults."""
    faults = [[_flat(f) for f in fs] for fs in faults]
    width = max((len(f) for f in faults), default=0)
    columns = {"faults": [len(f) for f in faults]}
    keys = []
    for fs in faults:
        for k, f in enumerate(fs):
            for key in f:
                if (k, key) not in keys:
                    keys.append((k, key))
    for k in range(width):
        for (kk, key) in keys:
            if kk == k:
                columns[f"fault{k + 1}_{key}"] = [fs[k].get(key) if k < len(fs) else None
                                                  for fs in faults]
    return columns


def evaluate(job, gains=(), seed=None, count=None, threads=None):
    """Out-of-sample evaluation, as `ftctune evaluate`: the job's compare controllers, its own
    and each of `gains` on its listed scenarios and its ensemble drawn with a held-out seed
    (default the ensemble's seed + 1).

    gains: a list of paths, Results or gains dicts (labelled by path, or "gains<k>"), or a dict
    {label: one of those}. Returns a DataFrame, one row per (controller, scenario), with the
    member's metrics in the objective's window (every field of the metrics record, a per-fault
    field as <name>_fault<k>) and the scenario's faults as columns (faults, fault<k>_type,
    fault<k>_onset, ...); its .attrs hold
    the held-out seed, the member count and each controller's aggregates.
    """
    items = list(gains.items()) if isinstance(gains, dict) else [
        (_os.fspath(g) if isinstance(g, (str, _os.PathLike)) else f"gains{k + 1}", g)
        for k, g in enumerate(gains)]
    with _tempfile.TemporaryDirectory() as d:
        pairs = [(label, _gains_file(g, d, f"{k}.json")) for k, (label, g) in enumerate(items)]
        out = _core.evaluate(_job(job), pairs, seed, count, threads)
    faults = _json.loads(out["faults"])
    index = out["scenario_index"]
    per_scenario = _fault_columns(faults)
    columns = ["controller", "source", "scenario", "recoverable", "objective",
               *out["metric_columns"], "diverged"]
    frame = _pd.DataFrame({k: out[k] for k in columns})
    for name, values in per_scenario.items():
        frame[name] = [values[i] for i in index]
    frame.attrs["seed"] = out["seed"]
    frame.attrs["count"] = out["count"]
    frame.attrs["simulations"] = out["simulations"]
    frame.attrs["controllers"] = _json.loads(out["summaries"])
    return frame


def load_gains(path):
    """A gains file (ftctune.gains/1), checked as the runtime loader checks it, as a dict."""
    return _json.loads(_core.load_gains(path))
