#!/usr/bin/env bash
# The runtime as flight software gets it: configure ftctune with FTCTUNE_RUNTIME_ONLY (and every
# tuner dependency made unfindable, so the runtime provably needs none of them), install it to a
# temporary prefix, build examples/runtime against it with find_package(ftctune), and run it on
# a gains file the full CLI writes.
# usage: runtime_package.sh SOURCE_DIR FTCTUNE_CLI
set -euo pipefail
src=$1 cli=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$src" -B "$tmp/runtime-build" -DCMAKE_BUILD_TYPE=Release -DFTCTUNE_RUNTIME_ONLY=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_TBB=ON -DCMAKE_DISABLE_FIND_PACKAGE_spdlog=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_SQLite3=ON -DCMAKE_DISABLE_FIND_PACKAGE_CLI11=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON "${launcher[@]}" >"$tmp/configure.log" 2>&1 ||
  { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/runtime-build" -j2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
cmake --install "$tmp/runtime-build" --prefix "$tmp/prefix" >/dev/null
if [ -e "$tmp/prefix/bin/ftctune" ]; then echo "runtime-only install has the CLI"; exit 1; fi

cmake -S "$src/examples/runtime" -B "$tmp/example" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  "${launcher[@]}" >"$tmp/example.log" 2>&1 || { cat "$tmp/example.log"; exit 1; }
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
