#!/usr/bin/env bash
# Reflection motion accuracy (paper 001 §7.4, Figs. 12-13):
# per frame of a moving camera over dnrender scenes 6 and 1, the share of the
# reflect pipeline's mirror and glossy motion vectors within 1 px of the
# brute-force optimum, and their mean error. The measurement is the test
# ReflectTest.MotionAccuracyAgainstBruteForceOverAFlythrough (96x54, 5 frame
# pairs per scene, the device's reflect_motion against a search over every
# previous pixel); this runs it with DN_MOTION_ACCURACY_OUT and plots the
# figures. Writes OUT/accuracy.tsv and OUT/reflection_motion.png; --docs also
# copies the plot to docs/images/reflection_motion.png.
# Environment: DN_BUILD_DIR (default build) holds the test binary.
set -euo pipefail
cd "$(dirname "$0")/.."
out=out/reflection_motion
docs=0
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    --docs) docs=1; shift ;;
    *) echo "usage: bench/reflection_motion.sh [--out DIR] [--docs]" >&2; exit 2 ;;
  esac
done
bin=${DN_BUILD_DIR:-build}
mkdir -p "$out"
DN_MOTION_ACCURACY_OUT="$out/accuracy.tsv" "$bin/tests/pipelines/dn_pipelines_tests" \
  --gtest_filter='ReflectTest.MotionAccuracyAgainstBruteForceOverAFlythrough' | grep -E '^\[ +(info|OK|FAILED)'
for s in 6 1; do
  for c in mirror glossy; do
    awk -F'\t' -v s="$s" -v c="$c" 'NR > 1 && $1 == s && $3 == c { print $2, 100 * $5, $6 }' "$out/accuracy.tsv" > "$out/scene${s}_$c.dat"
  done
done
gnuplot <<GP
set terminal png size 1100,420 font ",11" noenhanced
set output '$out/reflection_motion.png'
set multiplot layout 1,2 title 'reflect: motion vectors against the brute-force optimum (96x54, dnrender)'
set grid
set key outside right
set xlabel 'frame'
set ylabel '% within 1 px'
set yrange [0:100]
plot for [f in 'scene6_mirror scene6_glossy scene1_mirror scene1_glossy'] '$out/'.f.'.dat' using 1:2 with linespoints title f
set ylabel 'mean error, px'
set yrange [0:*]
plot for [f in 'scene6_mirror scene6_glossy scene1_mirror scene1_glossy'] '$out/'.f.'.dat' using 1:3 with linespoints title f
unset multiplot
GP
if [ "$docs" = 1 ]; then
  mkdir -p docs/images
  cp "$out/reflection_motion.png" docs/images/reflection_motion.png
fi
echo "reflection_motion: $out/accuracy.tsv, $out/reflection_motion.png"
