#!/usr/bin/env bash
# Installs the Debian packages the project needs (only those missing), then
# configures and builds incrementally into build/. Safe to run again.
#
#   scripts/setup.sh                    everything, the tests included (scripts/test.sh)
#   scripts/setup.sh --targets "A B"    only what targets A B need to build and run
#                                       (scripts/main.sh): no test-only packages, and
#                                       a new build/ is configured without the tests
set -euo pipefail
cd "$(dirname "$0")/.."

targets=""
case "${1:-}" in
  --targets) targets=${2:?--targets needs a list of CMake targets} ;;
  "") ;;
  *) echo "usage: scripts/setup.sh [--targets \"TARGET ...\"]" >&2; exit 2 ;;
esac

# What configuring and every program of the project need.
packages=(
  cmake ninja-build g++ pkg-config zlib1g-dev
  libvulkan-dev mesa-vulkan-drivers glslang-tools
  libopenexr-dev libglm-dev libembree-dev gnuplot-nox libbenchmark-dev libcivetweb-dev
)
# What only the tests (and the Python module they test) need.
test_packages=(
  vulkan-validationlayers spirv-tools spirv-cross libgtest-dev libgmock-dev
  chromium-headless-shell haproxy
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest
)
[ -n "$targets" ] || packages+=("${test_packages[@]}")

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
fi

# DN_SKIP_BUILD=1: packages only (scripts/sanitize.sh builds a tree of its own).
[ "${DN_SKIP_BUILD:-0}" = 1 ] && exit 0
configure() { cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@"; }
if [ -n "$targets" ]; then
  # A build/ that has the tests keeps them; a new one is made without.
  [ -f build/build.ninja ] || configure -DDN_BUILD_TESTS=OFF -DDN_BUILD_PYTHON=OFF
  # shellcheck disable=SC2086  # the list splits into targets
  cmake --build build -j "$(nproc)" --target $targets
else
  if [ ! -f build/build.ninja ] || grep -Eq '^DN_BUILD_(TESTS|PYTHON):BOOL=OFF$' build/CMakeCache.txt; then
    configure -DDN_BUILD_TESTS=ON -DDN_BUILD_PYTHON=ON
  fi
  cmake --build build -j "$(nproc)"
fi
