#!/usr/bin/env bash
# The runtime as flight software gets it. The runtime-only configuration (FTCTUNE_RUNTIME_ONLY)
# is configured with every tuner dependency made unfindable, so the runtime provably needs none
# of them, and offers no target but the two libraries (and ftc_sim's kernel copies, whose objects
# go into it). The libraries themselves come from the build the suite runs in: its install
# component `runtime` goes to a temporary prefix (the sources are the same ones; compiling them a
# second time here took this test 170 to 260 s on the 2-core machine, most of the suite's time).
# examples/runtime is built against that prefix with find_package(ftctune), again with the
# tuner's dependencies unfindable, and run on a gains file the full CLI writes.
# usage: runtime_package.sh SOURCE_DIR BUILD_DIR FTCTUNE_CLI
set -euo pipefail
src=$1 build=$2 cli=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
no_tuner_deps=(-DCMAKE_DISABLE_FIND_PACKAGE_TBB=ON -DCMAKE_DISABLE_FIND_PACKAGE_spdlog=ON
  -DCMAKE_DISABLE_FIND_PACKAGE_SQLite3=ON -DCMAKE_DISABLE_FIND_PACKAGE_CLI11=ON
  -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON -DCMAKE_DISABLE_FIND_PACKAGE_Pagmo=ON
  -DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON -DCMAKE_DISABLE_FIND_PACKAGE_xsimd=ON)
cmake -S "$src" -B "$tmp/runtime-only" -DCMAKE_BUILD_TYPE=Release -DFTCTUNE_RUNTIME_ONLY=ON \
  "${no_tuner_deps[@]}" >"$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; exit 1; }
targets=$(cmake --build "$tmp/runtime-only" --target help | sed -n 's/^\.\.\. \([a-z_]*\).*/\1/p' |
  grep -Ev '^(all|clean|depend|edit_cache|rebuild_cache|install|install_local|install_strip|list_install_components)$' |
  sort | tr '\n' ' ')
# ftc_sim_kernels: the objects of ftc_sim's kernel copies (sim_core/CMakeLists.txt).
[ "$targets" = "ftc_runtime ftc_sim ftc_sim_kernels " ] ||
  { echo "runtime-only targets: $targets"; exit 1; }

cmake --install "$build" --component runtime --prefix "$tmp/prefix" >/dev/null
if [ -e "$tmp/prefix/bin" ]; then echo "the runtime component installs programs:"; ls "$tmp/prefix/bin"; exit 1; fi
if [ -e "$tmp/prefix/include/ftc/tune" ]; then echo "the runtime component installs the tuner's headers"; exit 1; fi
links=$(sed -n 's/.*INTERFACE_LINK_LIBRARIES "\(.*\)".*/\1/p' "$tmp/prefix"/lib*/cmake/ftctune/ftctuneTargets.cmake |
  tr ';' '\n' | sort -u | tr '\n' ' ')
# (dl: ftctune::sim opens plant plugins, ftc/sim/plant_plugin.hpp; glibc's own.)
[ "$links" = 'Eigen3::Eigen \$<LINK_ONLY:dl> ftctune::sim nlohmann_json::nlohmann_json ' ] ||
  { echo "the installed libraries link: $links"; exit 1; }

cmake -S "$src/examples/runtime" -B "$tmp/example" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  "${no_tuner_deps[@]}" >"$tmp/example.log" 2>&1 || { cat "$tmp/example.log"; exit 1; }
cmake --build "$tmp/example" >>"$tmp/example.log" 2>&1 || { cat "$tmp/example.log"; exit 1; }

"$cli" run "$src/jobs/table1.json" --out "$tmp/run" --threads 2 -q
out=$("$tmp/example/runtime_example" "$tmp/run/gains.json")
echo "$out"
case "$out" in
  *"pi_fosmc from job table1, Ts = 0.001 s: after 1.0 s the attitude error is "*) ;;
  *) echo "unexpected output"; exit 1 ;;
esac
case "$out" in
  *"ISE over [0, 1) s = "*"control TV "*"(acceleration: ideal; sensors: exact)"*) ;;
  *) echo "no ISE line"; exit 1 ;;
esac
# The step() loop with the rates differentiated, a noisy gyro and measurements 2 samples late
# (the tuner's sensor model): it still runs, and it is not the exact loop.
out2=$("$tmp/example/runtime_example" "$tmp/run/gains.json" --accel differentiated --noise 0.01 --delay 2)
echo "$out2"
case "$out2" in
  *"(acceleration: differentiated (tau 0 s); sensors: rate noise 0.01 rad/s, delay 2 samples, acceleration differentiated, noise seed 1, stream 0)"*) ;;
  *) echo "unexpected output with --accel differentiated"; exit 1 ;;
esac
[ "$(echo "$out" | sed -n 2p | cut -d'(' -f1)" != "$(echo "$out2" | sed -n 2p | cut -d'(' -f1)" ] ||
  { echo "the noisy, late sensors changed nothing"; exit 1; }
set +e
"$tmp/example/runtime_example" "$tmp/run/gains.json" --accel rates >/dev/null 2>&1
status=$?
set -e
[ "$status" -eq 2 ] || { echo "exit $status for --accel rates"; exit 1; }

# A job tuned with sensors: its gains file records the differentiated acceleration, and the
# example, reading the job's scenario through the same sensors and forming the acceleration with
# the runtime's estimator, replays the tuned objective inside the rounding part of the run's noise
# floor (the same noise: another noise stream would move it by the sensor part, 2000 times more).
sed -e 's|"name": "table1"|"name": "table1-sensed"|' \
    -e 's|"substeps": 1,|"substeps": 1, "sensors": {"angle": {"noise": 1e-4}, "rate": {"noise": 1e-3, "bias": 2e-3, "bias_walk": 1e-4, "quantization": 1e-5}, "delay": 1, "acceleration": {"source": "differentiated", "time_constant": 0.005}},|' \
    "$src/jobs/table1.json" >"$tmp/sensed.json"
"$cli" run "$tmp/sensed.json" --out "$tmp/sensed" --threads 2 -q
grep -q '"source": "differentiated"' "$tmp/sensed/gains.json" ||
  { echo "the gains file does not record the differentiated acceleration"; exit 1; }
out3=$("$tmp/example/runtime_example" "$tmp/sensed/gains.json" --scenario "$tmp/sensed/job.json")
echo "$out3"
case "$out3" in
  *"(acceleration: differentiated (tau 0.005 s); sensors: angle noise 0.0001 rad, rate noise 0.001 rad/s"*) ;;
  *) echo "the replay did not read the job's sensors"; exit 1 ;;
esac
echo "$out3" | tail -1 | awk '{
  for (i = 1; i <= NF; ++i) { if ($i == "%" && $(i + 1) == "from") d = $(i - 1); if ($i == "alone") f = $(i + 1) }
  if (d == "" || f == "") { print "no comparison line with the rounding part of the floor"; exit 1 }
  if (d < 0) d = -d
  if (!(d < f)) { print "the replay is " d " % from the recorded objective, beyond the rounding floor " f " %"; exit 1 }
}'
# The second of two listed scenarios draws its noise from stream 1, as the tuner's does: the
# example's ISE on it is `ftctune simulate`'s on it, to the example's six digits.
/usr/bin/python3 - "$tmp/sensed/job.json" "$tmp/two.json" <<'PY'
import json, sys
job = json.load(open(sys.argv[1]))
second = dict(job["scenarios"][0], name="second")
job["scenarios"].append(second)
json.dump(job, open(sys.argv[2], "w"))
PY
"$cli" simulate "$tmp/two.json" --gains "$tmp/sensed/gains.json" -q --out "$tmp/two"
want=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["scenarios"][1]["ise"])' "$tmp/two/metrics.json")
got=$("$tmp/example/runtime_example" "$tmp/sensed/gains.json" --scenario "$tmp/two.json" --index 1 |
  sed -n 's/^ISE over \[0, 30) s = \([^ ]*\) rad^2 s.*stream 1)$/\1/p')
[ -n "$got" ] || { echo "no ISE line with stream 1 for --index 1"; exit 1; }
awk -v got="$got" -v want="$want" 'BEGIN { d = (got - want) / want; if (d < 0) d = -d
  if (!(d < 5e-6)) { print "--index 1: ISE " got ", simulate gives " want; exit 1 } }'
# Another noise seed is another draw of the same sensors: no longer the recorded run's bits.
out4=$("$tmp/example/runtime_example" "$tmp/sensed/gains.json" --scenario "$tmp/sensed/job.json" --seed 2)
[ "$(echo "$out3" | tail -1)" != "$(echo "$out4" | tail -1)" ] || { echo "--seed changed nothing"; exit 1; }
# A file of another format is refused with exit 2 and the loader's message.
sed 's|"ftctune.gains/1"|"ftctune.gains/9"|' "$tmp/run/gains.json" >"$tmp/other.json"
set +e
err=$("$tmp/example/runtime_example" "$tmp/other.json" 2>&1)
status=$?
set -e
[ "$status" -eq 2 ] || { echo "exit $status for a foreign file: $err"; exit 1; }
case "$err" in
  *'/schema: this file is "ftctune.gains/9", expected "ftctune.gains/1"'*) ;;
  *) echo "unexpected message: $err"; exit 1 ;;
esac
