#!/usr/bin/env bash
# scripts/list_outputs.sh (the end of scripts/main.sh): on an out/ holding a
# part of what a run writes, it lists exactly what exists, each with what it
# is, and names the method folders it found.
set -euo pipefail
script=$1
out=$(mktemp -d /tmp/dn-list-outputs-XXXXXX)
trap 'rm -rf "$out"' EXIT
mkdir -p "$out/scene1/svgf" "$out/scene1/reflect" "$out/scene1/input"
touch "$out/metrics.md" "$out/scene1.png" "$out/speed_error.png"
listing=$("$script" "$out")
echo "$listing"
fail() { echo "FAIL: $*"; exit 1; }
expect() { grep -qF -- "$1" <<< "$listing" || fail "not listed: $1"; }
expect_not() { ! grep -qF -- "$1" <<< "$listing" || fail "listed although absent: $1"; }
expect "$out/metrics.md"
expect "the metrics table (markdown)"
expect "$out/scene1.png"
expect "each named in its label strip"
expect "$out/speed_error.png"
expect "$out/scene1/input/"
expect "of each method: reflect, svgf"
expect_not "$out/results.tsv"
expect_not "$out/region.tsv"
expect_not "$out/scene1/refs/"
expect_not "$out/dnserver.log"
[ "$(grep -c "^  $out/" <<< "$listing")" = 5 ] || fail "expected 5 lines"
echo PASS
