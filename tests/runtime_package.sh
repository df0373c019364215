#!/usr/bin/env bash
# The runtime as flight software gets it. The runtime-only configuration (FTCTUNE_RUNTIME_ONLY)
# is configured with every tuner dependency made unfindable, so the runtime provably needs none
# of them, and offers no target but the two libraries. The libraries themselves come from the
# build the suite runs in: its install component `runtime` goes to a temporary prefix (the
# sources are the same ones; compiling them a second time here took this test 170 to 260 s on
# the 2-core machine, most of the suite's time). examples/runtime is built against that prefix
# with find_package(ftctune), again with the tuner's dependencies unfindable, and run on a gains
# file the full CLI writes.
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
[ "$targets" = "ftc_runtime ftc_sim " ] || { echo "runtime-only targets: $targets"; exit 1; }

cmake --install "$build" --component runtime --prefix "$tmp/prefix" >/dev/null
if [ -e "$tmp/prefix/bin" ]; then echo "the runtime component installs programs:"; ls "$tmp/prefix/bin"; exit 1; fi
if [ -e "$tmp/prefix/include/ftc/tune" ]; then echo "the runtime component installs the tuner's headers"; exit 1; fi
links=$(sed -n 's/.*INTERFACE_LINK_LIBRARIES "\(.*\)".*/\1/p' "$tmp/prefix"/lib*/cmake/ftctune/ftctuneTargets.cmake |
  tr ';' '\n' | sort -u | tr '\n' ' ')
[ "$links" = "Eigen3::Eigen ftctune::sim nlohmann_json::nlohmann_json " ] ||
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
  *"ISE over [0, 1) s = "*"control TV "*"(acceleration: exact, noise 0 rad/s^2, delay 0 samples)"*) ;;
  *) echo "no ISE line"; exit 1 ;;
esac
# The step() loop with the acceleration from differentiated rates, noisy and late: it still runs,
# and it is not the exact acceleration's loop.
out2=$("$tmp/example/runtime_example" "$tmp/run/gains.json" --accel rates --noise 0.01 --delay 2)
echo "$out2"
case "$out2" in
  *"(acceleration: rates, noise 0.01 rad/s^2, delay 2 samples)"*) ;;
  *) echo "unexpected output with --accel rates"; exit 1 ;;
esac
[ "$(echo "$out" | tail -1 | cut -d'(' -f1)" != "$(echo "$out2" | tail -1 | cut -d'(' -f1)" ] ||
  { echo "the noisy, late acceleration changed nothing"; exit 1; }
set +e
"$tmp/example/runtime_example" "$tmp/run/gains.json" --accel gyro >/dev/null 2>&1
status=$?
set -e
[ "$status" -eq 2 ] || { echo "exit $status for --accel gyro"; exit 1; }
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
