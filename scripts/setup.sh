#!/usr/bin/env bash
# Installs the Debian packages the project needs (only those missing), then
# configures and builds incrementally into build/. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  cmake ninja-build g++ pkg-config zlib1g-dev
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers glslang-tools spirv-tools spirv-cross
  libopenexr-dev libglm-dev libembree-dev gnuplot-nox
  libgtest-dev libgmock-dev libbenchmark-dev
  libcivetweb-dev chromium-headless-shell haproxy
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest
)
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
if [ ! -f build/build.ninja ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo
fi
cmake --build build -j "$(nproc)"
