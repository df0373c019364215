# The ftctune Python module against the CLI of the same build: every function, its errors, the
# GIL release and Ctrl-C. Short jobs only (Table 1 tunes in about half a second).
import json
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pandas as pd
import pytest

import ftctune


def run_cli(cli, *args, cwd=None):
    p = subprocess.run([cli, "--quiet", *args], capture_output=True, text=True, cwd=cwd)
    assert p.returncode == 0, p.stderr
    return p


def files_under(d):
    d = pathlib.Path(d)
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}


# --- load_job, Job ---------------------------------------------------------------------------

def test_load_job_reads_a_file_and_a_dict_to_the_same_resolved_job(table1_path):
    job = ftctune.load_job(table1_path)
    assert job.name == "table1" and job.source == table1_path
    d = job.to_dict()
    assert sorted(d["tuning"]["parameters"]) == ["Ki", "Kp"]
    again = ftctune.load_job(d)
    assert again.source == "<dict>"
    assert again.to_dict() == d
    assert ftctune.load_job(pathlib.Path(table1_path)).to_dict() == d


def test_load_job_names_the_json_path_of_each_error(robust_dict):
    robust_dict["controller"]["Kp"] = "twenty"
    robust_dict["ensemble"]["count"] = 0
    with pytest.raises(ftctune.InputError) as e:
        ftctune.load_job(robust_dict)
    assert "/controller/Kp" in str(e.value) and "/ensemble/count" in str(e.value)
    assert e.value.source == "<dict>"
    assert [path for path, _ in e.value.errors] == ["/controller/Kp", "/ensemble/count"]
    assert isinstance(e.value, ValueError)
    with pytest.raises(ftctune.InputError, match="no-such-job.json"):
        ftctune.load_job("no-such-job.json")


# --- Problem ---------------------------------------------------------------------------------

def test_problem_objective_is_what_run_saw_for_every_trial(table1_path):
    job = ftctune.load_job(table1_path)
    problem = ftctune.Problem(job)
    assert problem.names == ["Kp", "Ki"]
    assert problem.bounds == [(1.0, 50.0), (0.0, 50.0)]
    assert problem.scenarios == ["paper"]
    trials = ftctune.tune(job).trials
    X = trials[problem.names].to_numpy()
    values = problem.objective(X)
    assert values.shape == (len(trials),)
    # To the bit: the same simulations in lanes on the same threads as `run`.
    assert np.array_equal(values, trials["objective"].to_numpy())
    assert problem.objective(X[3]) == values[3]
    assert isinstance(problem.objective(X[3]), float)


def test_python_threads_may_share_a_problem(table1_path):
    problem = ftctune.Problem(table1_path)
    X = np.column_stack([np.linspace(1, 50, 40), np.linspace(0, 50, 40)])
    expected = problem.objective(X)
    results = [None] * 4

    def work(k):
        results[k] = problem.objective(X)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert np.array_equal(r, expected)


def test_problem_objective_refuses_bad_candidates_with_their_paths(table1_path):
    problem = ftctune.Problem(table1_path, threads=1)
    with pytest.raises(ftctune.InputError, match=r"/1/0: Kp = 60 is outside its bounds \[1, 50\]"):
        problem.objective([[20, 5], [60, 5]])
    with pytest.raises(ftctune.InputError, match="has 3 columns"):
        problem.objective(np.zeros((2, 3)))
    with pytest.raises(ftctune.InputError, match="outside its bounds"):
        problem.objective([np.nan, 5])
    notune = ftctune.load_job(table1_path).to_dict()
    del notune["tuning"]
    with pytest.raises(ftctune.InputError, match="/tuning"):
        ftctune.Problem(notune)


def test_problem_metrics_has_a_row_per_candidate_and_scenario(robust_dict):
    problem = ftctune.Problem(robust_dict)
    assert sorted(problem.names) == ["Ki", "Kp", "switching_gain"]
    scales = dict(zip(problem.names, problem.scales))
    assert scales == {"Kp": "linear", "Ki": "linear", "switching_gain": "log"}
    candidates = [{"Kp": 20.0, "Ki": 5.0, "switching_gain": 20.0},
                  {"Kp": 30.0, "Ki": 10.0, "switching_gain": 50.0}]
    X = np.array([[c[n] for n in problem.names] for c in candidates])
    m = problem.metrics(X)
    assert isinstance(m, pd.DataFrame)
    assert len(m) == 2 * len(problem.scenarios) == 2 * 7
    assert list(m["scenario"][:7]) == problem.scenarios
    for column in ("candidate", "Kp", "Ki", "switching_gain", "objective", "ise", "iae", "itae",
                   "max_abs_u", "control_tv", "peak_error_after_fault_fault1", "diverged",
                   "counted"):
        assert column in m.columns
    assert (m[m.candidate == 1]["Kp"] == 30.0).all()
    # The objective is the job's CVaR of the counted scenarios' values.
    values = problem.objective(X)
    for i in range(2):
        rows = m[(m.candidate == i) & m.counted]
        v = np.sort(rows["objective"].to_numpy())
        tail = v[-int(np.ceil(0.1 * len(v))):]
        assert values[i] == pytest.approx(tail.mean(), rel=1e-12)


# --- tune, Result ----------------------------------------------------------------------------

@pytest.mark.parametrize("job", ["table1", "manipulator"])
def test_tune_writes_the_bytes_of_ftctune_run(cli, root, job, tmp_path):
    job_path = str(root / "jobs" / f"{job}.json")
    run_cli(cli, "run", job_path, "--out", str(tmp_path / "cli"))
    result = ftctune.tune(job_path)
    assert result.completed
    written = result.write(tmp_path / "py")
    assert written[0] == "run.json" and written[-1] == "gains.json"
    cli_files, py_files = files_under(tmp_path / "cli"), files_under(tmp_path / "py")
    assert sorted(cli_files) == sorted(py_files)
    for name in cli_files:
        if name != "run.json":
            assert py_files[name] == cli_files[name], name
    a = json.loads(cli_files["run.json"])
    b = json.loads(py_files["run.json"])
    for key in ("started_at", "wall_seconds", "max_rss_kib"):
        a.pop(key), b.pop(key)
    assert a == b
    assert result.gains == json.loads(cli_files["gains.json"])
    assert result.history.equals(pd.read_csv(tmp_path / "cli" / "history.csv",
                                             float_precision="round_trip"))
    assert result.comparison == json.loads(cli_files["comparison.json"])
    with pytest.raises(ftctune.InputError, match="already holds a run"):
        result.write(tmp_path / "py")
    assert result.write(tmp_path / "py", replace=True)[-1] == "gains.json"


def test_tune_of_an_ensemble_job_writes_the_bytes_of_ftctune_run(cli, robust_dict, tmp_path):
    job_file = tmp_path / "robust-small.json"
    job_file.write_text(json.dumps(robust_dict))
    run_cli(cli, "run", str(job_file), "--out", str(tmp_path / "cli"), "--seed", "3",
            "--threads", "1")
    ftctune.tune(str(job_file), seed=3, threads=2).write(tmp_path / "py")
    cli_files, py_files = files_under(tmp_path / "cli"), files_under(tmp_path / "py")
    assert sorted(cli_files) == sorted(py_files)
    for name in cli_files:
        if name != "run.json":
            assert py_files[name] == cli_files[name], name


def test_tune_calls_back_each_iteration_and_stops_when_told(table1_path, tmp_path):
    seen = []

    def callback(row):
        seen.append(row)
        return row["iteration"] < 3

    result = ftctune.tune(table1_path, threads=1, seed=5, callback=callback)
    assert [r["iteration"] for r in seen] == [0, 1, 2, 3]
    assert set(seen[-1]["best"]) == {"Kp", "Ki"}
    assert not result.completed
    assert result.gains["optimizer"]["completed"] is False
    assert result.history["iteration"].max() == 3
    assert len(result.trials) == seen[-1]["evaluations"]
    with pytest.raises(ftctune.InputError, match="no files to write"):
        result.write(tmp_path / "stopped")
    assert not (tmp_path / "stopped").exists()


def test_a_callback_that_raises_stops_the_run_with_its_exception(table1_path):
    def callback(row):
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        ftctune.tune(table1_path, callback=callback)


def test_tune_refuses_bad_arguments(table1_path):
    with pytest.raises(ftctune.InputError, match="threads"):
        ftctune.tune(table1_path, threads=-1)


def test_tune_releases_the_gil(table1_path):
    count = 0
    running = True

    def counter():
        nonlocal count
        while running:
            count += 1
            time.sleep(0.001)

    t = threading.Thread(target=counter)
    t.start()
    try:
        start = time.monotonic()
        before = count
        ftctune.tune(table1_path)
        elapsed = time.monotonic() - start
        during = count - before
    finally:
        running = False
        t.join()
    # Held, the GIL would let the thread count at most once or twice (at the call's ends); let
    # go, it counts every millisecond or so (a loaded machine may make that several).
    assert elapsed > 0.1
    assert during >= 0.05 * elapsed / 0.001 and during > 20, (during, elapsed)


CTRL_C_SCRIPT = """
import json, sys, time, ftctune
job = ftctune.load_job(sys.argv[1]).to_dict()
job["tuning"]["algorithm"]["iterations"] = 1000  # minutes of work; its trials fit the memory budget
job["tuning"]["algorithm"]["population"] = 200
print("tuning", flush=True)
try:
    ftctune.tune(job, callback=None)
except KeyboardInterrupt:
    print("interrupted", time.monotonic(), flush=True)
    sys.exit(42)
"""


def test_ctrl_c_stops_a_tuning_run_within_a_second(table1_path):
    p = subprocess.Popen([sys.executable, "-c", CTRL_C_SCRIPT, table1_path],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert p.stdout.readline().strip() == "tuning"
        time.sleep(0.5)  # well inside the first iterations' simulations
        sent = time.monotonic()
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=10)
        stopped = time.monotonic()
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 42, err
    assert out.startswith("interrupted")
    assert float(out.split()[1]) - sent < 1.0
    assert stopped - sent < 2.0


DAEMON_SCRIPT = """
import sys, threading, time, ftctune
job = ftctune.load_job(sys.argv[1]).to_dict()
job["tuning"]["algorithm"]["iterations"] = 1000
job["tuning"]["algorithm"]["population"] = 200
problem = ftctune.Problem(sys.argv[1], threads=1)
threading.Thread(target=ftctune.tune, args=(job,), kwargs={"threads": 1}, daemon=True).start()
threading.Thread(target=lambda: [problem.objective([[10.0, 20.0]] * 2000) for _ in range(100)],
                 daemon=True).start()
time.sleep(1.0)  # both inside their simulations
print("exiting", time.monotonic(), flush=True)
"""


def test_the_interpreter_exits_cleanly_while_daemon_threads_tune(table1_path):
    # It aborted (SIGABRT, exit 134): Python ends a daemon thread by unwinding it through the
    # library's C++ frames when it next takes the GIL after the interpreter began to exit.
    p = subprocess.run([sys.executable, "-c", DAEMON_SCRIPT, table1_path], capture_output=True,
                       text=True, timeout=60)
    ended = time.monotonic()
    assert p.returncode == 0, (p.returncode, p.stderr)
    assert p.stdout.startswith("exiting")
    assert ended - float(p.stdout.split()[1]) < 5.0  # the exit waits a slice, not the run


# --- simulate, ensemble, evaluate, load_gains ------------------------------------------------
# --- simulate, ensemble, evaluate, load_gains ------------------------------------------------

def test_simulate_gives_the_metrics_and_trajectories_of_ftctune_simulate(cli, table1_path,
                                                                         tmp_path):
    run_cli(cli, "simulate", table1_path, "--set", "Kp=30", "--record-every", "0.05", "--out",
            str(tmp_path))
    s = ftctune.simulate(table1_path, set={"Kp": 30}, record_every=0.05)
    doc = json.loads((tmp_path / "metrics.json").read_text())
    assert s["scenarios"] == doc["scenarios"]
    assert s["objective"] == doc["objective"] and s["fitness"] == doc["fitness"]
    assert s["controller"] == doc["controller"]
    cli_trajectory = pd.read_csv(tmp_path / "trajectory.csv", float_precision="round_trip")
    assert s["trajectories"]["paper"].equals(cli_trajectory)
    assert list(s["metrics"]["scenario"]) == ["paper"]
    assert s["metrics"]["ise"][0] == doc["scenarios"][0]["ise"]
    fosmc = ftctune.simulate(table1_path, controller="fosmc")
    assert fosmc["controller"]["type"] == "fosmc"
    with pytest.raises(ftctune.InputError, match="/Kq"):
        ftctune.simulate(table1_path, set={"Kq": 1})
    with pytest.raises(ftctune.InputError, match="unknown controller type"):
        ftctune.simulate(table1_path, controller="pid")


def test_simulate_and_problem_metrics_name_their_columns_alike(table1_path):
    # A value per fault onset as <metric>_fault<k>, a fault segment's as <metric>_segment<k> with
    # its window; simulate() had the onsets' values as a list in one cell and no segments.
    job = json.loads(pathlib.Path(table1_path).read_text())
    job["objective"]["window"] = [12, 30]  # the run before 12 s is a segment of its own
    s = ftctune.simulate(job)["metrics"]
    problem = ftctune.Problem(job)
    own = [[job["controller"][n] for n in problem.names]]
    m = problem.metrics(own)
    assert "peak_error_after_fault_fault1" in s.columns and "peak_error_after_fault_fault2" in s.columns
    assert "peak_error_after_fault" not in s.columns
    segment_columns = [c for c in m.columns if "segment" in c]
    assert segment_columns and "segment1_t0" in segment_columns
    for c in segment_columns + ["ise", "control_tv", "peak_error_after_fault_fault1"]:
        assert c in s.columns, c
        got = s[c].iloc[0]  # a metric not measured there: null in the document, NaN in Problem
        assert (float("nan") if got is None else got) == pytest.approx(
            m[c].iloc[0], rel=1e-15, nan_ok=True), c


def test_a_jobs_sensors_reach_the_loop_and_their_errors_name_the_path(table1_path):
    job = json.loads(pathlib.Path(table1_path).read_text())
    exact = ftctune.simulate(job)["metrics"]["ise"].iloc[0]
    job["scenarios"][0]["sensors"] = {
        "rate": {"noise": 1e-3}, "delay": 2,
        "acceleration": {"source": "differentiated", "time_constant": 0.005}}
    sensed = ftctune.simulate(job)["metrics"]["ise"].iloc[0]
    assert sensed != exact
    # Every candidate sees the same measurement noise: Problem scores the job's own gains alike.
    problem = ftctune.Problem(job)
    own = [[job["controller"][n] for n in problem.names]]
    assert problem.metrics(own)["ise"].iloc[0] == pytest.approx(sensed, rel=1e-15)
    job["scenarios"][0]["sensors"]["delay"] = -1
    with pytest.raises(ftctune.InputError, match="/scenarios/0/sensors/delay"):
        ftctune.load_job(job)


def test_simulate_takes_tuned_gains(table1_path, tmp_path):
    result = ftctune.tune(table1_path)
    s = ftctune.simulate(table1_path, gains=result)
    best = result.comparison["controllers"][-1]
    assert s["controller"] == result.gains["controller"]
    assert s["objective"] == pytest.approx(ftctune.Problem(table1_path).objective(
        [result.gains["tuned"]["Kp"], result.gains["tuned"]["Ki"]]), rel=0)
    assert best["role"] == "tuned"


def test_simulate_says_when_no_scenario_counts(table1_path):
    # Two wheels stuck from 1 s: no gains can control the spacecraft, so the objective counts
    # nothing and says so (None), while the metrics are what happened.
    job = json.loads(pathlib.Path(table1_path).read_text())
    job["scenarios"][0]["duration"] = 3
    job["scenarios"][0]["faults"] = [
        {"actuator": 1, "type": "stuck", "onset": 1, "value": 0},
        {"actuator": 2, "type": "stuck", "onset": 1, "value": 0}]
    job["objective"]["window"] = [0, 3]
    with pytest.warns(UserWarning, match="is unrecoverable"):
        s = ftctune.simulate(job)
    assert s["objective"] is None and s["fitness"] is None
    assert s["scenarios"][0]["recoverable"] is False and s["scenarios"][0]["counted"] is False
    assert s["metrics"]["ise"][0] > 0
    assert not s["metrics"]["recoverable"][0]


def test_vehicle_plants_load_simulate_and_refuse_at_the_path(table1_path):
    # Your vehicle (SPEC §17): a rigid body with a full tensor and four pyramid wheels, and a
    # quad_x multirotor, through the same calls as the shipped plants.
    jobs = pathlib.Path(table1_path).parent
    sat = json.loads((jobs / "smallsat-pyramid.json").read_text())
    s = ftctune.simulate(ftctune.load_job(sat))
    assert [x["model_invalid"] for x in s["scenarios"]] == [False, False]
    traj = s["trajectories"]["stuck-wheel"]
    assert [c for c in traj.columns if c.startswith("u")] == [
        "ud1", "ud2", "ud3", "ud4", "u1", "u2", "u3", "u4"]
    assert (traj[["u1", "u2", "u3"]].abs().max() <= 0.01).all() and traj["u4"].abs().max() <= 0.006
    # Pitching up through 85 degrees: flagged and warned about, the metrics still there.
    steep = json.loads(json.dumps(sat))
    steep["scenarios"] = [dict(sat["scenarios"][1], duration=0.6,
                               initial_state=[0, 1.2, 0, 0, 0.6, 0], faults=[])]
    steep["objective"]["window"] = [0, 0.6]
    with pytest.warns(UserWarning, match="85"):
        t = ftctune.simulate(steep)
    assert t["scenarios"][0]["model_invalid"] is True and t["objective"] > 0
    quad = ftctune.load_job(str(jobs / "quad-x.json"))
    assert np.isfinite(ftctune.Problem(quad).objective([[1, 8, 4]])).all()
    bad = json.loads(json.dumps(sat))
    bad["plant"]["inertia"][0][1] = 0.02
    with pytest.raises(ftctune.InputError, match="/plant/inertia/1/0"):
        ftctune.load_job(bad)
    # The simulated plant's actuators (SPEC §17.1): the model's values change nothing, a turned
    # wheel changes the run, and a list of the wrong length is refused at its key.
    same = json.loads(json.dumps(sat))
    same["scenarios"][0]["actuator_scale"] = [1, 1, 1, 1]
    assert ftctune.simulate(same)["objective"] == s["objective"]
    turned = json.loads(json.dumps(sat))
    turned["scenarios"][0]["actuator_misalignment"] = [0, 0.05, 0, 0]
    assert ftctune.simulate(turned)["objective"] != s["objective"]
    turned["scenarios"][0]["actuator_misalignment"] = [0, 0.05]
    with pytest.raises(ftctune.InputError, match="/scenarios/0/actuator_misalignment"):
        ftctune.load_job(turned)


def test_ensemble_lists_the_members_of_ftctune_ensemble(cli, robust_dict, tmp_path):
    job_file = tmp_path / "job.json"
    job_file.write_text(json.dumps(robust_dict))
    out = run_cli(cli, "ensemble", str(job_file), "--seed", "9", "--count", "5").stdout
    members = ftctune.ensemble(robust_dict, seed=9, count=5)
    assert members == json.loads(out)["scenarios"]
    assert members[0]["name"] == "paper-0"
    assert {"type", "onset", "actuator"} <= set(members[0]["faults"][0])
    assert len(ftctune.ensemble(robust_dict)) == 6
    with pytest.raises(ftctune.InputError, match="--count"):
        ftctune.ensemble(robust_dict, count=0)
    no_ensemble = dict(robust_dict)
    del no_ensemble["ensemble"]
    with pytest.raises(ftctune.InputError, match="/ensemble"):
        ftctune.ensemble(no_ensemble)


def test_evaluate_rows_match_ftctune_evaluate_with_faults_as_columns(cli, robust_dict, tmp_path):
    job_file = tmp_path / "job.json"
    job_file.write_text(json.dumps(robust_dict))
    result = ftctune.tune(robust_dict)
    gains_file = tmp_path / "tuned.json"
    gains_file.write_text(json.dumps(result.gains, indent=2))
    run_cli(cli, "evaluate", str(job_file), "--gains", f"tuned={gains_file}", "--count", "4",
            "--no-figure", "--out", str(tmp_path / "evaluation"))
    frame = ftctune.evaluate(robust_dict, gains={"tuned": gains_file}, count=4)
    assert frame.attrs["seed"] == 8 and frame.attrs["count"] == 4
    doc = json.loads((tmp_path / "evaluation" / "evaluation.json").read_text())
    labels = [c["label"] for c in doc["controllers"]]
    assert list(dict.fromkeys(frame["controller"])) == labels
    assert len(frame) == len(labels) * 5  # the listed scenario and 4 members
    cli_rows = pd.read_csv(tmp_path / "evaluation" / "evaluation.csv", float_precision="round_trip")
    assert list(frame["objective"]) == list(cli_rows["objective"])
    # Every metric of the record, as evaluation.csv has it (a per-fault field split by onset).
    for column in ("ise", "iae", "itae", "max_abs_u", "control_tv", "control_energy",
                   "peak_command", "saturation_fraction", "steady_state_error"):
        assert np.array_equal(frame[column].to_numpy(float), cli_rows[column].to_numpy(float),
                              equal_nan=True), column
    first_peaks = [float(str(v).split(";")[0]) for v in cli_rows["peak_error_after_fault"]]
    assert np.array_equal(frame["peak_error_after_fault_fault1"].to_numpy(float),
                          np.array(first_peaks), equal_nan=True)
    members = ftctune.ensemble(robust_dict, seed=8, count=4)
    tuned = frame[frame.controller == "tuned"].reset_index(drop=True)
    for k, m in enumerate(members):
        row = tuned.iloc[k + 1]
        assert row["scenario"] == m["name"]
        assert row["faults"] == len(m["faults"])
        assert row["fault1_type"] == m["faults"][0]["type"]
        assert row["fault1_onset"] == m["faults"][0]["onset"]
    # Gains given as a Result or a dict are the same gains.
    again = ftctune.evaluate(robust_dict, gains=[result, result.gains], count=4)
    assert list(again[again.controller == "gains1"]["objective"]) == list(tuned["objective"])
    assert list(again[again.controller == "gains2"]["objective"]) == list(tuned["objective"])
    with pytest.raises(ftctune.InputError):
        ftctune.evaluate(robust_dict, gains=[tmp_path / "missing.json"])


def test_load_gains_reads_a_checked_gains_file(table1_path, tmp_path):
    result = ftctune.tune(table1_path)
    result.write(tmp_path)
    assert ftctune.load_gains(tmp_path / "gains.json") == result.gains
    bad = dict(result.gains)
    bad["schema"] = "ftctune.gains/9"
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(ftctune.InputError, match="/schema"):
        ftctune.load_gains(tmp_path / "bad.json")


def test_a_pagmo_job_runs_from_python(table1_path):
    job = ftctune.load_job(table1_path).to_dict()
    job["tuning"]["algorithm"] = {"type": "pagmo", "name": "sade", "population": 7,
                                  "generations": 2}
    result = ftctune.tune(job)
    assert result.completed
    assert result.gains["optimizer"]["type"] == "pagmo"
    assert result.gains["optimizer"]["name"] == "sade"
    assert len(result.trials) == 7 * 3


INSTALLED_SCRIPT = """
import sys, ftctune
job = ftctune.load_job(sys.argv[1]).to_dict()
job["tuning"]["algorithm"] = {"type": "pagmo", "name": "sade", "population": 7, "generations": 1}
print(ftctune.__file__, ftctune.tune(job).completed)
"""


def test_cmake_install_installs_a_module_that_finds_its_pagmo_adapter(cli, table1_path, tmp_path):
    build = pathlib.Path(cli).resolve().parents[1]
    prefix = tmp_path / "prefix"
    p = subprocess.run(["cmake", "--install", str(build), "--prefix", str(prefix)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr
    site = next(prefix.glob("lib/python3*/dist-packages"))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "FTCTUNE_PLUGIN_DIR")}
    env["PYTHONPATH"] = str(site)
    p = subprocess.run([sys.executable, "-c", INSTALLED_SCRIPT, table1_path], capture_output=True,
                       text=True, env=env, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    module_file, completed = p.stdout.split()
    assert module_file == str(site / "ftctune" / "__init__.py") and completed == "True"


# --- the package itself (#41 item 7) ---------------------------------------------------------

def test_version_is_the_commands_and_the_namespace_is_the_api(cli):
    p = subprocess.run([cli, "--version"], capture_output=True, text=True)
    assert p.stdout.splitlines()[0] == "ftctune " + ftctune.__version__
    public = {n for n in dir(ftctune) if not n.startswith("_")}
    # What the module imports (numpy, pandas, os, json, io, tempfile, warnings) is not its API.
    assert public == set(ftctune.__all__)
    for name in ("np", "pd", "os", "json", "io", "tempfile", "warnings"):
        assert not hasattr(ftctune, name), name


def test_native_objects_cannot_be_made_without_their_value(table1_path):
    # An object __new__ made has no C++ value (no __init__ builds one): its first method call read
    # raw memory and crashed the interpreter. The native types are made only by the functions.
    import copy
    from ftctune import _core
    for cls in (_core.Job, _core.Problem, _core.Result):
        for make in (lambda: cls.__new__(cls), lambda: object.__new__(cls), lambda: cls()):
            with pytest.raises(TypeError):
                make()
    job = ftctune.load_job(table1_path)
    with pytest.raises(TypeError):
        copy.copy(job._native)  # copy goes through __new__ too
    assert ftctune.Problem(job, threads=1)([20.0, 5.0]) > 0  # the functions still make them


def test_problem_and_its_calls_take_the_memory_budget(table1_path, monkeypatch):
    # As `ftctune run` is: a Problem holds the job's members, and a call keeps an outcome per
    # row (issue 44: 1.29 GB for one call). Refused before the work, with what it would need.
    problem = ftctune.Problem(table1_path, threads=1)
    monkeypatch.setenv("FTCTUNE_MEMORY_MIB", "70")
    with pytest.raises(ftctune.InputError, match=r"a Problem of this job would need about"):
        ftctune.Problem(table1_path, threads=1)
    monkeypatch.setenv("FTCTUNE_MEMORY_MIB", "100")
    with pytest.raises(ftctune.InputError, match=r"100000 rows of X at once would need about"):
        problem.objective(np.full((100000, 2), 10.0))
    assert problem.objective(np.full((2, 2), 10.0)).shape == (2,)


def test_an_error_message_lists_the_first_hundred_problems(table1_path):
    problem = ftctune.Problem(table1_path, threads=1)
    with pytest.raises(ftctune.InputError) as caught:
        problem.objective(np.full((500, 2), -1.0))  # every row outside the bounds
    n = len(caught.value.errors)
    assert n >= 500
    assert str(caught.value).count("\n") == 101  # 100 listed and a line for the rest
    assert "... and %d more" % (n - 100) in str(caught.value)


def test_problem_is_a_function_for_scipy_and_a_pygmo_problem(table1_path):
    from scipy.optimize import minimize
    problem = ftctune.Problem(table1_path, threads=1)
    assert repr(problem) == ("ftctune.Problem('table1': Kp in [1, 50], Ki in [0, 50]; "
                             "1 scenario, 1 thread)")
    x = [10.0, 20.0]
    assert problem(x) == problem.objective(np.array(x))
    assert problem.fitness(x) == [problem(x)]
    assert problem.get_bounds() == ([1.0, 0.0], [50.0, 50.0])
    assert problem.get_nobj() == 1
    assert problem.get_name() == "ftctune table1"
    # pygmo.problem() deep-copies what it is given (pygmo itself is not installed here).
    import copy
    twin = copy.deepcopy(problem)
    assert twin is not problem and twin(x) == problem(x) and repr(twin) == repr(problem)
    # scipy takes it as it is: a bounded search that ends no worse than where it started.
    r = minimize(problem, x0=x, bounds=problem.bounds, method="Powell",
                 options={"maxfev": 20})
    assert r.fun <= problem(x)
    assert all(lo <= v <= hi for v, (lo, hi) in zip(r.x, problem.bounds))


def test_tune_issues_its_warnings_as_run_warnings(table1_path):
    with pytest.warns(ftctune.RunWarning) as caught:
        result = ftctune.tune(table1_path, threads=1)
    assert [str(w.message) for w in caught if w.category is ftctune.RunWarning] == result.warnings
    assert any("Ki = 50 ended at its upper bound 50" in w for w in result.warnings)


def test_a_front_runs_callback_gets_the_fronts_size(table1_path):
    job = ftctune.load_job(table1_path).to_dict()
    del job["objective"]
    job["goals"] = [{"metric": "ise", "minimize": True},
                    {"metric": "control_tv", "minimize": True}]
    job["tuning"]["algorithm"].update({"population": 3, "iterations": 1})
    rows = []
    result = ftctune.tune(job, threads=1, callback=lambda row: rows.append(row))
    assert [r["iteration"] for r in rows] == [0, 1]
    assert all(r["front_points"] >= 1 for r in rows)
    assert rows[-1]["front_points"] == result.gains["goals"]["front"]["points"]


def test_load_job_reads_a_plugin_plant_and_tunes_as_the_cli_does(cli, root, tmp_path):
    """A job naming plugin:reaction_wheel_pendulum (examples/plant-plugin), found through
    plant_path: the module loads the library into the interpreter and tunes to the bytes of
    `ftctune run` with the same plugin."""
    plugins = pathlib.Path(cli).resolve().parents[1] / "tests" / "plugins"
    path = str(root / "examples" / "plant-plugin" / "job.json")
    ftctune._core.set_plant_path([])
    with pytest.raises(ftctune.InputError, match="is not on the plant search path"):
        ftctune.load_job(json.loads(pathlib.Path(path).read_text().replace(
            "reaction_wheel_pendulum", "no_such_plant")))
    job = ftctune.load_job(path, plant_path=plugins)
    assert job.to_dict()["plant"]["model"] == "plugin:reaction_wheel_pendulum"
    result = ftctune.tune(job, threads=2)
    out = tmp_path / "cli"
    subprocess.run([cli, "run", path, "--plant-path", str(plugins), "--out", str(out), "-q"],
                   check=True)
    assert result.gains == json.loads((out / "gains.json").read_text())
