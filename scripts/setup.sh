#!/usr/bin/env bash
# Installs the Debian 12 packages geoanchor builds, tests and benchmarks with.
# Idempotent: packages already installed are left alone, and apt is not touched
# at all when nothing is missing. Must run as root (or with sudo available).
#   bash scripts/setup.sh           what the build and the example need
#   bash scripts/setup.sh --tests   and npm, for the test-only independent LAS
#                                   reader (tests/las-verify; scripts/test.sh)
set -euo pipefail

tests=false
case "${1:-}" in
  "") ;;
  --tests) tests=true ;;
  *) echo "usage: bash scripts/setup.sh [--tests]" >&2; exit 2 ;;
esac

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git
  # geodesy core
  libeigen3-dev libgeographiclib-dev geographiclib-tools
  libproj-dev proj-bin proj-data
  # solver
  libceres-dev libsuitesparse-dev libboost-math-dev
  # file formats, CLI, hashes
  nlohmann-json3-dev libcli11-dev libssl-dev libexpat1-dev libgeotiff-dev
  # GUI shells (later issues) and fonts
  libimgui-dev libglfw3-dev libosmesa6-dev libstb-dev fonts-dejavu-core xvfb xauth
  # tests, benchmarks and fuzzing (clang brings libFuzzer)
  libgtest-dev libgmock-dev libbenchmark-dev clang
  # the layout checks (scripts/check_layout.py, run by CTest)
  python3
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q '^install ok installed$'; then
    missing+=("$p")
  fi
done

# npm by its command, not by a package: a Node.js from elsewhere (NodeSource's
# nodejs, which brings its own npm and conflicts with Debian's) serves as well.
if $tests && ! command -v npm >/dev/null; then
  missing+=(npm)
fi

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
