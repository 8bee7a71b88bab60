#!/usr/bin/env bash
# Sets up (Debian packages), builds and runs the whole test suite through CTest.
#   bash scripts/test.sh           Release build (build/release)
#   bash scripts/test.sh --asan    AddressSanitizer + UBSan build (build/asan)
set -euo pipefail
cd "$(dirname "$0")/.."

preset=release
case "${1:-}" in
  "") ;;
  --asan) preset=asan ;;
  *) echo "usage: bash scripts/test.sh [--asan]" >&2; exit 2 ;;
esac

bash scripts/setup.sh --tests
# The independent LAS reader the apply tests compare with (test-only, npm;
# versions pinned by the committed package-lock.json).
if [ ! -d tests/las-verify/node_modules/copc ] || [ tests/las-verify/package-lock.json -nt tests/las-verify/node_modules ]; then
  npm ci --prefix tests/las-verify --no-audit --no-fund --loglevel=error
fi
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset"
ctest --preset "$preset" -j "$(nproc)"
