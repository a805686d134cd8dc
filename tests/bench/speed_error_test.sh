#!/bin/sh
# bench/speed_error.sh at 64x36 on scene 1: every row is present with finite
# numbers (also over the roughness-mapped floor), the filters flicker less
# than the noisy input on the still shot, and the plot and the side-by-side
# image are written.
# usage: speed_error_test.sh SOURCE_DIR BUILD_DIR WORKDIR
set -eu
src=$1
build=$2
dir=$3
rm -rf "$dir"
mkdir -p "$dir"
DN_SKIP_SETUP=1 DN_BUILD_DIR="$build" "$src/bench/speed_error.sh" --scenes 1 --frames 3 --still 6 --size 64x36 \
  --ref-spp 32 --out "$dir/out" --cache "$dir/cache" > "$dir/log" 2>&1 || { cat "$dir/log"; exit 1; }
results="$dir/out/results.tsv"
for method in noisy accumulate atrous svgf svgf-fb svgf-split; do
  grep -q "^1	$method	" "$results" || { echo "no row for $method"; cat "$results"; exit 1; }
  grep -q "^1	$method	" "$dir/out/region.tsv" || { echo "no floor row for $method"; cat "$dir/out/region.tsv"; exit 1; }
done
# Every numeric field is a finite number.
awk -F'\t' 'FNR > 1 { for (i = 3; i <= NF; ++i) if ($i !~ /^-?[0-9.]+(e[-+]?[0-9]+)?$/) { print FILENAME " field " i " of row " FNR ": " $i; bad = 1 } }
            END { exit bad }' "$results" "$dir/out/region.tsv"
# Temporal error on the still shot: any filter well below the noisy input.
awk -F'\t' '$2 == "noisy" { noisy = $6 } $2 == "accumulate" { acc = $6 } $2 == "svgf" { svgf = $6 }
            END { if (!(acc < 0.5 * noisy && svgf < 0.5 * noisy)) { print "temporal: noisy " noisy " accumulate " acc " svgf " svgf; exit 1 } }' "$results"
for png in speed_error.png scene1.png; do
  test "$(wc -c < "$dir/out/$png")" -gt 1000 || { echo "$png missing or empty"; exit 1; }
done
echo "speed_error_test: $(($(wc -l < "$results") - 1)) rows"
