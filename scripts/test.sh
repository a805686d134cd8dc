#!/usr/bin/env bash
# The whole test suite: installs and builds what is missing, then runs ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
ctest --test-dir build --output-on-failure -j 2 "$@"
