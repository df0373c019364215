#!/usr/bin/env bash
# A plant plugin as a user builds it: ftctune's runtime and plant SDK installed (components
# runtime and plant_sdk of the build the suite runs in) to a temporary prefix, examples/plant-plugin
# configured and built against it with find_package(ftctune) and ftctune_add_plant, the result
# checked with `ftctune plant check`, and its example job tuned: the run files must be the bytes
# the build tree's copy of the plugin gives (which ftc_plugin_tests compares with the same plant
# compiled in).
# usage: plant_plugin_package.sh SOURCE_DIR BUILD_DIR FTCTUNE_CLI TREE_PLUGIN_DIR
set -euo pipefail
src=$1 build=$2 cli=$3 tree_plugins=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --component runtime --prefix "$tmp/prefix" >/dev/null
cmake --install "$build" --component plant_sdk --prefix "$tmp/prefix" >/dev/null
[ -f "$tmp/prefix/include/ftc/plant_sdk/lanes/closed_loop.hpp" ] ||
  { echo "the plant SDK's headers are not installed"; exit 1; }
start=$(date +%s)
cmake -S "$src/examples/plant-plugin" -B "$tmp/example" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  >"$tmp/example.log" 2>&1 || { cat "$tmp/example.log"; exit 1; }
cmake --build "$tmp/example" -j2 >>"$tmp/example.log" 2>&1 || { cat "$tmp/example.log"; exit 1; }
echo "configured and built the example against the package in $(( $(date +%s) - start )) s"
lib="$tmp/example/ftctune_plant_reaction_wheel_pendulum.so"
[ -f "$lib" ] || { echo "no $lib"; ls "$tmp/example"; exit 1; }
# Only the entry point is exported.
exported=$(nm -D --defined-only "$lib" | awk '$2 == "T" {print $3}' | tr '\n' ' ')
[ "$exported" = "ftctune_plant_plugin " ] || { echo "the plugin exports: $exported"; exit 1; }

"$cli" plant check "$lib"
job="$src/examples/plant-plugin/job.json"
"$cli" run "$job" --plant-path "$tmp/example" --out "$tmp/run" --threads 2 -q
"$cli" run "$job" --plant-path "$tree_plugins" --out "$tmp/tree" --threads 2 -q
for f in gains.json history.csv trials.csv comparison.json; do
  cmp "$tmp/run/$f" "$tmp/tree/$f" || { echo "$f differs from the build tree's plugin's"; exit 1; }
done
echo "the installed package's plugin tunes to the bytes of the build tree's"
