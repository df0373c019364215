#!/usr/bin/env bash
# Every ftc:: symbol the pagmo adapter module needs must be in the CLI's dynamic symbol table:
# the module resolves them against the executable that opens it (tuner/CMakeLists.txt).
set -euo pipefail
module=$1 exe=$2
needed=$(nm -D --undefined-only "$module" | awk '{print $2}' | grep '^_ZN3ftc' | sort -u)
exported=$(nm -D --defined-only "$exe" | awk '{print $3}' | sort -u)
missing=$(comm -23 <(echo "$needed") <(echo "$exported"))
if [[ -n "$missing" ]]; then
  echo "the module needs symbols $exe does not export:"
  echo "$missing" | c++filt
  exit 1
fi
echo "$(echo "$needed" | wc -l) ftc symbols needed by the module, all exported by $(basename "$exe")"
