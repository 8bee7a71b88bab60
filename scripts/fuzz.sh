#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan; CMake preset "fuzz") and
# runs each for SECONDS (default 150, so 30 minutes for the twelve), growing
# the committed corpus in fuzz/corpus/<target>/. Any crash, hang, leak or
# sanitizer report stops that target with its input saved as
# build/fuzz/<target>-crash-*; replay it with build/fuzz/fuzz/fuzz_<target> FILE.
# Targets named after SECONDS run alone (e.g. `bash scripts/fuzz.sh 600 sinex`).
#   bash scripts/fuzz.sh [SECONDS [TARGET...]]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-150}"
all=(las laz las_tile ply csv sidecar vector transform control network dynaml gama sinex)
targets=("${all[@]}")
if [ $# -gt 1 ]; then
  targets=("${@:2}")
  for t in "${targets[@]}"; do
    if [[ " ${all[*]} " != *" $t "* ]]; then
      echo "fuzz.sh: no target '$t'; expected one of: ${all[*]}" >&2
      exit 2
    fi
  done
fi

bash scripts/setup.sh
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --target "${targets[@]/#/fuzz_}"

status=0
for target in "${targets[@]}"; do
  corpus="fuzz/corpus/${target}"
  [ "$target" = las_tile ] && corpus=fuzz/corpus/las  # the LAS corpus, through the tile path
  echo "== fuzz_${target}: ${seconds} s =="
  # New inputs go to a scratch folder first; -merge keeps only those that add coverage.
  scratch="build/fuzz/new-${target}"
  rm -rf "$scratch" && mkdir -p "$scratch"
  before=$(find "${corpus}" -type f | wc -l)
  if ! build/fuzz/fuzz/fuzz_${target} "$scratch" "${corpus}" -max_total_time="$seconds" \
       -max_len=4096 -timeout=10 -rss_limit_mb=2048 -artifact_prefix="build/fuzz/${target}-" -print_final_stats=1 \
       2>&1 | tail -n 12; then
    status=1
  fi
  build/fuzz/fuzz/fuzz_${target} -merge=1 "${corpus}" "$scratch" 2>/dev/null | tail -n 1 || true
  echo "corpus ${target}: ${before} -> $(find "${corpus}" -type f | wc -l) files"
done
exit "$status"
