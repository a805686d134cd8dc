#!/bin/sh
# bench/speed_error.sh at 64x36 on scene 1: every row is present with finite
# numbers (also the noise-corrected columns from the second reference, and
# every region: the roughness-mapped floor, glossy surfaces, highlights,
# disocclusions), the noise-corrected MSE is below the plain MSE for the noisy
# input (the references' noise removed), the filters flicker less than the
# noisy input on the still shot, and the plot and the side-by-side image are
# written.
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
for method in noisy accumulate atrous svgf svgf-fb svgf-split stat-temporal stat-temporal-r6; do
  grep -q "^1	$method	" "$results" || { echo "no row for $method"; cat "$results"; exit 1; }
  for region in roughness-mapped glossy highlights disocclusion; do
    grep -q "^1	$region	$method	" "$dir/out/region.tsv" ||
      { echo "no $region row for $method"; cat "$dir/out/region.tsv"; exit 1; }
  done
done
# The glossy still-shot temporal error of every method (scene 1 has glossy
# spheres), and svgf's below the noisy input's there too.
for method in noisy svgf; do
  grep -q "^1	glossy	$method	" "$dir/out/region_temporal.tsv" ||
    { echo "no glossy temporal row for $method"; cat "$dir/out/region_temporal.tsv"; exit 1; }
done
awk -F'\t' '$3 == "noisy" { noisy = $4 } $3 == "svgf" { svgf = $4 }
            END { if (!(svgf < 0.5 * noisy)) { print "glossy temporal: noisy " noisy " svgf " svgf; exit 1 } }' \
  "$dir/out/region_temporal.tsv"
# Every numeric field is a finite number.
# (results.tsv: from field 3 on; region.tsv: scene, region, method, then numbers)
awk -F'\t' 'FNR == 1 { first = FILENAME ~ /region/ ? 4 : 3 }
            FNR > 1 { for (i = first; i <= NF; ++i) if ($i !~ /^-?[0-9.]+(e[-+]?[0-9]+)?$/) { print FILENAME " field " i " of row " FNR ": " $i; bad = 1 } }
            END { exit bad }' "$results" "$dir/out/region.tsv"
# Noise-corrected MSE (column 10) against the plain MSE (RMSE^2, column 3) and
# the references' noise (column 12): for the noisy input, nc = plain - noise
# within the sampling error; checked loosely (nc < plain, noise > 0).
awk -F'\t' '$2 == "noisy" { if (!($10 < $3 * $3 && $12 > 0)) { print "nc_mse " $10 " rmse^2 " $3 * $3 " ref_noise " $12; exit 1 } }' "$results"
# Temporal error on the still shot: any filter well below the noisy input.
awk -F'\t' '$2 == "noisy" { noisy = $6 } $2 == "accumulate" { acc = $6 } $2 == "svgf" { svgf = $6 }
            END { if (!(acc < 0.5 * noisy && svgf < 0.5 * noisy)) { print "temporal: noisy " noisy " accumulate " acc " svgf " svgf; exit 1 } }' "$results"
for png in speed_error.png scene1.png; do
  test "$(wc -c < "$dir/out/$png")" -gt 1000 || { echo "$png missing or empty"; exit 1; }
done
# bench/pass_cost.sh on the same frames: a median for every pass of both
# pipelines, reflect's own passes among them.
DN_BUILD_DIR="$build" "$src/bench/pass_cost.sh" --input "$dir/out/scene1/input" --frames 3 --warmup 1 --repeat 1 \
  --out "$dir/pass_cost" > "$dir/pass_cost.log" 2>&1 || { cat "$dir/pass_cost.log"; exit 1; }
for pass in svgf_reproject_specular reflect_prepare reflect_motion reflect_median; do
  grep -Eq "^\| $pass \|( [0-9.]* \|)* [0-9]+\.[0-9]+ \|$" "$dir/pass_cost/passes.md" ||
    { echo "pass_cost: no time for $pass"; cat "$dir/pass_cost/passes.md"; exit 1; }
done
echo "speed_error_test: $(($(wc -l < "$results") - 1)) rows"
