#!/bin/sh
# bench/speed_against.sh with this build's pipeline_bench on both sides at
# 64x36: one table row per pipeline, with the options passed through, each
# with positive median times and one ratio per round; and no base is refused.
# usage: speed_against_test.sh SOURCE_DIR BUILD_DIR WORKDIR
set -eu
src=$1
build=$2
dir=$3
rm -rf "$dir"
mkdir -p "$dir"
bench=$build/bench/pipeline_bench
if DN_BUILD_DIR="$build" "$src/bench/speed_against.sh" --rounds 1 > "$dir/refused" 2>&1; then
  echo "ran without --base or --base-bin"; exit 1
fi
grep -q -- "--base COMMIT or --base-bin PATH is required" "$dir/refused" || { cat "$dir/refused"; exit 1; }
DN_BUILD_DIR="$build" "$src/bench/speed_against.sh" --base-bin "$bench" --rounds 2 --size 64x36 --frames 3 \
  --pipeline svgf --pipeline "progressive --spp-period 4" --out "$dir/out" > "$dir/table" 2>&1 || { cat "$dir/table"; exit 1; }
[ "$(grep -c '^| svgf |' "$dir/table")" -eq 1 ] || { echo "no svgf row"; cat "$dir/table"; exit 1; }
[ "$(grep -c '^| progressive --spp-period 4 |' "$dir/table")" -eq 1 ] || { echo "no progressive row"; cat "$dir/table"; exit 1; }
grep -q -- '--spp-period 4' "$dir/out/rows/progressive_--spp-period_4.current.1" || { echo "--spp-period not passed"; exit 1; }
awk -F'|' '$2 ~ /svgf|progressive/ {
  if (!($3 + 0 > 0 && $4 + 0 > 0 && $6 + 0 > 0)) { print "not positive: " $0; bad = 1 }
  if (split($5, r, ",") != 2) { print "not one ratio per round: " $0; bad = 1 }
} END { exit bad }' "$dir/table" || { cat "$dir/table"; exit 1; }
echo "speed_against smoke: ok"
