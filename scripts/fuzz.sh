#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan; CMake preset "fuzz") and
# runs each for SECONDS (default 150, so 12.5 minutes for the five), growing the
# committed corpus in fuzz/corpus/<target>/. Any crash, hang, leak or
# sanitizer report stops that target with its input saved as
# build/fuzz/<target>-crash-*; replay it with build/fuzz/fuzz/fuzz_<target> FILE.
#   bash scripts/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-150}"

bash scripts/setup.sh
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --target fuzz_las fuzz_laz fuzz_ply fuzz_csv fuzz_sidecar

status=0
for target in las laz ply csv sidecar; do
  echo "== fuzz_${target}: ${seconds} s =="
  # New inputs go to a scratch folder first; -merge keeps only those that add coverage.
  scratch="build/fuzz/new-${target}"
  rm -rf "$scratch" && mkdir -p "$scratch"
  if ! build/fuzz/fuzz/fuzz_${target} "$scratch" "fuzz/corpus/${target}" -max_total_time="$seconds" \
       -max_len=4096 -timeout=10 -rss_limit_mb=2048 -artifact_prefix="build/fuzz/${target}-" -print_final_stats=1 \
       2>&1 | tail -n 12; then
    status=1
  fi
  build/fuzz/fuzz/fuzz_${target} -merge=1 "fuzz/corpus/${target}" "$scratch" 2>/dev/null | tail -n 1 || true
done
exit "$status"
